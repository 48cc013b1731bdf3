//! `coagula run` as an ensemble: blocks of replicas (of every sweep point) shared out
//! over processes, saved as they finish when a checkpoint directory is given, and
//! merged in a fixed order on rank 0.
//!
//! Work item k is block b of sweep point p, numbered point by point; rank `k mod P`
//! runs it. A block's statistics are its replicas pushed in order, and rank 0 merges
//! the blocks of a point in block order ([`runner::statistics`] does the same in one
//! process), so the figures have the same bits for any number of processes and of
//! threads per process, and for a run resumed from its checkpoints.
//!
//! One encoding carries a block between processes and into its checkpoint file: words
//! of 64 bits (floats by their bits, so NaN and the last bit survive), headed by the
//! plan's fingerprint, so a block of another scenario is refused.

use crate::runner::{self, Block, Outcome, Progress};
use crate::scenario::Plan;
use coagula_core::observe::Replicas;
use coagula_core::scheme::StepReport;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The processes of an ensemble.
pub trait World {
    /// This process's rank, 0..size.
    fn rank(&self) -> usize;
    /// Number of processes.
    fn size(&self) -> usize;
    /// Every rank's words at rank 0, in rank order; `None` on the other ranks.
    fn gather(&self, mine: Vec<u64>) -> Option<Vec<Vec<u64>>>;
    /// An error on this rank alone before the gather (the others would wait for it
    /// forever): with other processes, prints it and ends the whole job; alone, hands
    /// it back.
    fn fatal(&self, e: String) -> String {
        e
    }
}

/// One process.
pub struct Alone;

impl World for Alone {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn gather(&self, mine: Vec<u64>) -> Option<Vec<Vec<u64>>> {
        Some(vec![mine])
    }
}

/// How a front end opens its world of processes.
pub type Opener = fn() -> Result<Box<dyn World>, String>;

static OPENER: std::sync::OnceLock<Opener> = std::sync::OnceLock::new();

/// Makes [`world`] open the processes through `open` (the `coagula-mpi` binary installs
/// MPI's world this way, before the command line is parsed). Once per process: a second
/// call is refused.
pub fn set_opener(open: Opener) -> Result<(), String> {
    OPENER
        .set(open)
        .map_err(|_| "the world of processes was set already".to_string())
}

/// The world of this process: what [`set_opener`] installed, else one process.
pub fn world() -> Result<Box<dyn World>, String> {
    match OPENER.get() {
        Some(open) => open(),
        None => Ok(Box::new(Alone)),
    }
}

const BLOCK_MAGIC: u64 = u64::from_le_bytes(*b"coagBLK1");
const FILE_MAGIC: u64 = u64::from_le_bytes(*b"coagCKP1");

/// What identifies a plan's results: everything but the threads (results do not
/// depend on them), the memory estimate (which does) and the memory budget (the
/// machine's), with the CLI's version.
pub fn fingerprint(plan: &Plan) -> u64 {
    let mut p = plan.clone();
    p.threads = 0;
    p.memory = 0;
    p.scenario.run.threads = 0;
    // (from the machine's memory: ranks on other machines must agree)
    p.options = p.options.with_memory_budget(0);
    let text = format!("{} {p:?}", env!("CARGO_PKG_VERSION"));
    // FNV-1a, 64 bits
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn report_words(t: &StepReport) -> [u64; 10] {
    [
        t.time.to_bits(),
        t.events,
        t.proposals,
        t.rejections,
        t.bound_violations,
        t.clipped,
        t.doublings,
        t.removed,
        t.bounces,
        u64::from(t.interrupted),
    ]
}

fn report_of(w: &[u64]) -> StepReport {
    let mut t = StepReport::default();
    t.time = f64::from_bits(w[0]);
    t.events = w[1];
    t.proposals = w[2];
    t.rejections = w[3];
    t.bound_violations = w[4];
    t.clipped = w[5];
    t.doublings = w[6];
    t.removed = w[7];
    t.bounces = w[8];
    t.interrupted = w[9] != 0;
    t
}

/// Block b of point p as words.
pub fn encode(fingerprint: u64, point: usize, b: u64, block: &Block) -> Vec<u64> {
    let times = block.stats.len();
    let obs = block.stats.first().map_or(0, Vec::len);
    let mut w = vec![
        BLOCK_MAGIC,
        fingerprint,
        point as u64,
        b,
        times as u64,
        obs as u64,
        block.events.len() as u64,
    ];
    w.extend(report_words(&block.totals));
    w.extend(&block.events);
    for row in &block.stats {
        for r in row {
            let (n, mean, m2) = r.to_raw();
            w.extend([n, mean.to_bits(), m2.to_bits()]);
        }
    }
    w
}

/// Decodes a block: `(fingerprint, point, block, results)`; an error names what is
/// wrong.
pub fn decode(w: &[u64]) -> Result<(u64, usize, u64, Block), String> {
    const HEAD: usize = 7 + 10;
    if w.len() < HEAD || w[0] != BLOCK_MAGIC {
        return Err("not a block of results".into());
    }
    let (fp, point, b) = (w[1], w[2] as usize, w[3]);
    let (times, obs, reps) = (w[4] as usize, w[5] as usize, w[6] as usize);
    if times == 0 || obs == 0 {
        // (a plan has at least one of each; the length check below then bounds both)
        return Err("a block of no time or no observable".into());
    }
    let cells = times.checked_mul(obs).and_then(|c| c.checked_mul(3));
    let want = cells.and_then(|c| c.checked_add(HEAD + reps));
    if want != Some(w.len()) || reps as u64 > runner::BLOCK {
        return Err(format!(
            "a block of {} words does not hold its shape",
            w.len()
        ));
    }
    let totals = report_of(&w[7..HEAD]);
    let events = w[HEAD..HEAD + reps].to_vec();
    let mut cells = w[HEAD + reps..].chunks_exact(3);
    let mut stats = Vec::with_capacity(times);
    for _ in 0..times {
        let mut row = Vec::with_capacity(obs);
        for _ in 0..obs {
            let c = cells.next().ok_or("short block")?;
            let r = Replicas::from_raw(c[0], f64::from_bits(c[1]), f64::from_bits(c[2]))
                .ok_or("a block holds an impossible statistic")?;
            row.push(r);
        }
        stats.push(row);
    }
    Ok((
        fp,
        point,
        b,
        Block {
            stats,
            totals,
            events,
        },
    ))
}

/// The checkpoint file of block b of point p.
pub fn checkpoint_path(dir: &Path, point: usize, b: u64) -> PathBuf {
    dir.join(format!("point{point:05}-block{b:07}.bin"))
}

/// Writes a block's checkpoint: a temporary file, then a rename, so a killed run
/// leaves either the whole file or none.
fn save(path: &Path, words: &[u64]) -> Result<(), String> {
    let mut bytes = Vec::with_capacity(8 * (words.len() + 1));
    bytes.extend(FILE_MAGIC.to_le_bytes());
    for w in words {
        bytes.extend(w.to_le_bytes());
    }
    // a name of this process's own: two runs on one directory never share it
    let tmp = path.with_extension(format!("{}.tmp", std::process::id()));
    let write = || -> std::io::Result<()> {
        use std::io::Write;
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(&bytes)?;
        // on disk before it gets its name: a crash leaves no empty block file
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| format!("checkpoint {}: {e}", path.display()))
}

/// A saved block, if its file exists: it must be a block of this plan, point and
/// block number.
fn load(path: &Path, fp: u64, point: usize, b: u64, plan: &Plan) -> Result<Option<Block>, String> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("checkpoint {}: {e}", path.display())),
    };
    let bad = |why: &str| {
        format!(
            "checkpoint {}: {why}; delete it (or the directory) to run the block again",
            path.display()
        )
    };
    if bytes.len() % 8 != 0 || bytes.len() < 8 || bytes[..8] != FILE_MAGIC.to_le_bytes() {
        return Err(bad("not a coagula checkpoint"));
    }
    let words: Vec<u64> = bytes[8..]
        .chunks_exact(8)
        .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    let (f, p, bb, block) = decode(&words).map_err(|e| bad(&e))?;
    if f != fp {
        return Err(bad("it belongs to another scenario, seed or version"));
    }
    if p != point || bb != b || !shaped(&block, plan, b) {
        return Err(bad("it holds another block"));
    }
    Ok(Some(block))
}

/// Whether a block has the shape plan's block b must have.
fn shaped(block: &Block, plan: &Plan, b: u64) -> bool {
    block.events.len() == runner::block_replicas(plan.replicas, b).count()
        && block.stats.len() == plan.times.len()
        && block.stats.iter().all(|r| r.len() == plan.columns())
}

/// A rank's message to rank 0: status 0, the number of blocks it resumed from
/// checkpoints, then each block as (length, words); or status 1 and an error message.
fn message(result: Result<(u64, Vec<Vec<u64>>), String>) -> Vec<u64> {
    match result {
        Ok((resumed, blocks)) => {
            let mut m = vec![0, resumed];
            for b in blocks {
                m.push(b.len() as u64);
                m.extend(b);
            }
            m
        }
        Err(e) => {
            let mut m = vec![1, e.len() as u64];
            m.extend(e.as_bytes().chunks(8).map(|c| {
                let mut w = [0u8; 8];
                w[..c.len()].copy_from_slice(c);
                u64::from_le_bytes(w)
            }));
            m
        }
    }
}

/// The blocks (and resumed count) of a rank's message, or its error.
fn unpack(m: &[u64]) -> Result<(u64, Vec<&[u64]>), String> {
    match m {
        [0, resumed, rest @ ..] => {
            let mut blocks = Vec::new();
            let mut rest = rest;
            while let [len, tail @ ..] = rest {
                let len = usize::try_from(*len).map_err(|e| e.to_string())?;
                if len > tail.len() {
                    return Err("a truncated message".into());
                }
                blocks.push(&tail[..len]);
                rest = &tail[len..];
            }
            Ok((*resumed, blocks))
        }
        [1, len, text @ ..] => {
            let bytes: Vec<u8> = text.iter().flat_map(|w| w.to_le_bytes()).collect();
            let len = (*len as usize).min(bytes.len());
            Err(String::from_utf8_lossy(&bytes[..len]).into_owned())
        }
        _ => Err("a malformed message".into()),
    }
}

/// Runs this rank's share of the blocks of every point: resumed from `checkpoint`
/// where a block was saved, else run (and saved).
fn run_share(
    points: &[Plan],
    prints: &[u64],
    world: &dyn World,
    checkpoint: Option<&Path>,
    quiet: bool,
) -> Result<(u64, Vec<Vec<u64>>), String> {
    let (rank, size) = (world.rank(), world.size());
    let mut items = Vec::new();
    let mut k = 0usize;
    for (p, plan) in points.iter().enumerate() {
        for b in 0..runner::blocks(plan.replicas) {
            if k % size == rank {
                items.push((p, b));
            }
            k += 1;
        }
    }
    if let Some(dir) = checkpoint {
        std::fs::create_dir_all(dir).map_err(|e| format!("--checkpoint {}: {e}", dir.display()))?;
    }
    // every saved block is read (and a bad file refused) before any work starts
    let mut saved = Vec::with_capacity(items.len());
    for &(p, b) in &items {
        saved.push(match checkpoint {
            Some(dir) => load(&checkpoint_path(dir, p, b), prints[p], p, b, &points[p])?,
            None => None,
        });
    }
    let resumed = saved.iter().filter(|s| s.is_some()).count() as u64;
    let ticks: u64 = items
        .iter()
        .zip(&saved)
        .filter(|(_, s)| s.is_none())
        .map(|(&(p, b), _)| {
            let plan = &points[p];
            runner::block_replicas(plan.replicas, b).count() as u64 * plan.times.len() as u64
        })
        .sum();
    let label = if points.len() > 1 {
        format!("{} sweep points", points.len())
    } else {
        format!("{} x {}", points[0].replicas, points[0].scheme.name)
    };
    let progress = Progress::new(ticks, &label, quiet || rank != 0);
    let tick = || progress.tick();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(points[0].threads)
        .build()
        .map_err(|e| format!("thread pool: {e}"))?;
    // the first failure stops the rank's remaining blocks
    let blocks: Result<Vec<Vec<u64>>, String> = pool.install(|| {
        items
            .par_iter()
            .zip(saved)
            .map(|(&(p, b), saved)| {
                if let Some(block) = saved {
                    return Ok(encode(prints[p], p, b, &block));
                }
                let block = runner::run_block(&points[p], b, &tick)?;
                let words = encode(prints[p], p, b, &block);
                if let Some(dir) = checkpoint {
                    save(&checkpoint_path(dir, p, b), &words)?;
                }
                Ok(words)
            })
            .collect()
    });
    progress.finish();
    Ok((resumed, blocks?))
}

/// What an ensemble gave, at rank 0.
pub struct Ensemble {
    /// One outcome per sweep point (`values` left empty: the blocks carry statistics).
    pub outcomes: Vec<Outcome>,
    /// Blocks taken from checkpoints instead of run.
    pub resumed: u64,
    /// Blocks in all.
    pub blocks: u64,
}

/// Runs every point's replicas over the world's processes. Rank 0 returns the
/// outcomes; the other ranks `None` (an error of theirs is reported by rank 0).
pub fn run(
    points: &[Plan],
    world: &dyn World,
    checkpoint: Option<&Path>,
    quiet: bool,
) -> Result<Option<Ensemble>, String> {
    if points.is_empty() {
        return Err("no sweep point to run".into());
    }
    let start = Instant::now();
    let before = runner::resident_memory();
    let prints: Vec<u64> = points.iter().map(fingerprint).collect();
    let mine = message(run_share(points, &prints, world, checkpoint, quiet));
    let Some(all) = world.gather(mine) else {
        return Ok(None);
    };
    let mut slots: Vec<Vec<Option<Block>>> = points
        .iter()
        .map(|p| vec![None; runner::blocks(p.replicas) as usize])
        .collect();
    let mut resumed = 0;
    for (rank, m) in all.iter().enumerate() {
        let prefix = |e: String| {
            if all.len() > 1 {
                format!("rank {rank}: {e}")
            } else {
                e
            }
        };
        let (r, blocks) = unpack(m).map_err(prefix)?;
        resumed += r;
        for words in blocks {
            let (fp, p, b, block) = decode(words).map_err(prefix)?;
            let slot = slots
                .get_mut(p)
                .and_then(|s| s.get_mut(b as usize))
                .filter(|_| prints.get(p) == Some(&fp) && shaped(&block, &points[p], b))
                .ok_or_else(|| prefix(format!("block {b} of point {p} does not fit the plan")))?;
            *slot = Some(block);
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    // what this process held: the run's when it ran alone (one rank, one point)
    let resident = before
        .zip(runner::resident_memory())
        .map(|((now, _), (_, peak))| (now, peak))
        .filter(|_| all.len() == 1 && points.len() == 1);
    let mut outcomes = Vec::with_capacity(points.len());
    let mut count = 0;
    for (plan, blocks) in points.iter().zip(slots) {
        let mut stats = vec![vec![Replicas::new(); plan.columns()]; plan.times.len()];
        let mut totals = StepReport::default();
        let mut events = Vec::with_capacity(plan.replicas as usize);
        for (b, block) in blocks.into_iter().enumerate() {
            let block = block.ok_or_else(|| format!("block {b} never arrived"))?;
            runner::merge_stats(&mut stats, &block.stats);
            totals.accumulate(&block.totals);
            events.extend(block.events);
            count += 1;
        }
        outcomes.push(Outcome {
            values: Vec::new(),
            stats,
            totals,
            events,
            seconds,
            resident,
        });
    }
    Ok(Some(Ensemble {
        outcomes,
        resumed,
        blocks: count,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block() -> Block {
        let mut r = Replicas::new();
        for x in [0.1, f64::MIN_POSITIVE, 7.0] {
            r.push(x);
        }
        let mut nan = Replicas::new();
        nan.push(f64::NAN);
        let mut totals = StepReport::default();
        totals.events = 12;
        totals.time = 0.3;
        totals.interrupted = true;
        Block {
            stats: vec![vec![r, nan], vec![Replicas::new(), r]],
            totals,
            events: vec![5, 7, 0],
        }
    }

    #[test]
    fn blocks_round_trip_bit_for_bit() {
        let b = block();
        let w = encode(42, 3, 9, &b);
        let (fp, p, bb, back) = decode(&w).unwrap();
        assert_eq!((fp, p, bb), (42, 3, 9));
        assert_eq!(back.events, b.events);
        assert_eq!(back.totals, b.totals);
        let raw = |s: &Block| -> Vec<u64> {
            s.stats
                .iter()
                .flatten()
                .flat_map(|r| {
                    let (n, m, v) = r.to_raw();
                    [n, m.to_bits(), v.to_bits()]
                })
                .collect()
        };
        assert_eq!(raw(&back), raw(&b));
        // every truncation and a stray word are refused
        for cut in 0..w.len() {
            assert!(decode(&w[..cut]).is_err(), "cut at {cut}");
        }
        let mut long = w.clone();
        long.push(0);
        assert!(decode(&long).is_err());
    }

    /// P ranks in one process: ranks 1..P run first and post their messages, then
    /// rank 0 gathers them.
    struct Fake<'a> {
        rank: usize,
        size: usize,
        mail: &'a std::sync::Mutex<Vec<Vec<u64>>>,
    }

    impl World for Fake<'_> {
        fn rank(&self) -> usize {
            self.rank
        }
        fn size(&self) -> usize {
            self.size
        }
        fn gather(&self, mine: Vec<u64>) -> Option<Vec<Vec<u64>>> {
            let mut mail = self.mail.lock().unwrap();
            if self.rank == 0 {
                let mut all = vec![mine];
                all.append(&mut mail);
                Some(all)
            } else {
                mail.push(mine);
                None
            }
        }
    }

    fn over(points: &[Plan], size: usize, dir: Option<&Path>) -> Result<Ensemble, String> {
        let mail = std::sync::Mutex::new(Vec::new());
        for rank in (1..size).chain([0]) {
            let w = Fake {
                rank,
                size,
                mail: &mail,
            };
            if let Some(e) = run(points, &w, dir, true)? {
                return Ok(e);
            }
        }
        unreachable!("rank 0 returns")
    }

    fn plans(replicas: i64, threads: i64, seed: i64) -> Vec<Plan> {
        let ov = vec![
            ("run.replicas".to_string(), toml::Value::Integer(replicas)),
            ("run.threads".to_string(), toml::Value::Integer(threads)),
            ("run.seed".to_string(), toml::Value::Integer(seed)),
            ("initial.particles".to_string(), toml::Value::Integer(3000)),
            ("output.t-end".to_string(), toml::Value::Float(2.0)),
            ("output.count".to_string(), toml::Value::Integer(3)),
        ];
        crate::plans::points(Some("quickstart-constant"), ov, None)
            .unwrap()
            .into_iter()
            .map(|(_, p)| p)
            .collect()
    }

    /// Every figure of an outcome as bits.
    fn bits(o: &Outcome) -> Vec<u64> {
        let mut v: Vec<u64> = o
            .stats
            .iter()
            .flatten()
            .flat_map(|r| {
                let (n, m, v) = r.to_raw();
                [n, m.to_bits(), v.to_bits()]
            })
            .collect();
        v.extend(report_words(&o.totals));
        v.extend(&o.events);
        v
    }

    #[test]
    fn any_number_of_processes_and_threads_gives_the_same_bits() {
        // 21 replicas: two whole blocks and a partial one
        let one = runner::run(&plans(21, 1, 5)[0], true).unwrap();
        assert_eq!(one.stats[0][0].count(), 21);
        for (size, threads) in [(1, 2), (2, 1), (3, 2), (5, 1)] {
            let e = over(&plans(21, threads, 5), size, None).unwrap();
            assert_eq!(e.blocks, 3);
            assert_eq!(
                bits(&e.outcomes[0]),
                bits(&one),
                "P = {size}, {threads} threads"
            );
        }
        // and another seed gives other bits
        let other = over(&plans(21, 1, 6), 2, None).unwrap();
        assert_ne!(bits(&other.outcomes[0]), bits(&one));
    }

    #[test]
    fn the_fingerprint_ignores_the_machine_but_not_the_case() {
        let p = plans(16, 1, 5).remove(0);
        let mut q = plans(16, 2, 5).remove(0);
        // a machine with more memory and cores
        q.options = q
            .options
            .with_memory_budget(p.options.memory_budget() * 2 + 1);
        q.memory += 12345;
        assert_eq!(fingerprint(&q), fingerprint(&p));
        for other in [plans(16, 1, 6), plans(24, 1, 5)] {
            assert_ne!(fingerprint(&other[0]), fingerprint(&p));
        }
    }

    #[test]
    fn a_resumed_run_gives_the_same_bits_and_refuses_foreign_blocks() {
        let dir = std::env::temp_dir().join(format!("coagula-ckpt-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let full = over(&plans(30, 1, 7), 2, Some(&dir)).unwrap();
        assert_eq!((full.blocks, full.resumed), (4, 0));
        // as if the run had died before blocks 1 and 3 were saved
        for b in [1, 3] {
            std::fs::remove_file(checkpoint_path(&dir, 0, b)).unwrap();
        }
        let resumed = over(&plans(30, 2, 7), 3, Some(&dir)).unwrap();
        assert_eq!(resumed.resumed, 2);
        assert_eq!(bits(&resumed.outcomes[0]), bits(&full.outcomes[0]));
        // a directory of another seed is refused, by name
        let e = over(&plans(30, 1, 8), 1, Some(&dir)).err().unwrap();
        assert!(
            e.contains("another scenario") && e.contains("block0000000"),
            "{e}"
        );
        // a damaged file is refused, not run over
        std::fs::write(checkpoint_path(&dir, 0, 2), b"coagCKP1 broken").unwrap();
        let e = over(&plans(30, 1, 7), 2, Some(&dir)).err().unwrap();
        assert!(e.contains("block0000002") && e.contains("delete it"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn messages_carry_blocks_and_errors() {
        let w = encode(1, 0, 2, &block());
        let m = message(Ok((1, vec![w.clone(), w.clone()])));
        let (resumed, blocks) = unpack(&m).unwrap();
        assert_eq!(resumed, 1);
        assert_eq!(blocks, vec![&w[..], &w[..]]);
        let e = message(Err("replica 3 at t = 1: bound exceeded ✓".into()));
        assert_eq!(
            unpack(&e).unwrap_err(),
            "replica 3 at t = 1: bound exceeded ✓"
        );
        assert!(unpack(&[0, 0, 5, 1]).is_err());
        assert!(unpack(&[]).is_err());
    }
}
