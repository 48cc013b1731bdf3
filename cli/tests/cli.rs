//! End-to-end tests of the `coagula` binary.

mod common;

use common::{coagula, examples, json_of, succeeded};

/// `coagula run` writes the documented CSV, and its moments are those of the exact
/// solution to QMC accuracy (N = 2^10, P = 100: errors ~1e-3, far below a factor-2 bug).
#[test]
fn run_writes_csv_close_to_exact() {
    let dir = std::env::temp_dir().join(format!("coagula-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("run.csv");
    let svg = dir.join("run.svg");
    let out = coagula()
        .args(["run", "--m", "10", "--steps", "100", "--csv"])
        .arg(&csv)
        .arg("--plot")
        .arg(&svg)
        .output()
        .unwrap();
    succeeded(&out);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "t,M2,M2_exact,M3,M3_exact");
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 100);
    for r in &rows {
        let t = r[0];
        let m2 = 3.0 - 2.0 * (-t / 3.0f64).exp();
        let m3 = 18.0 - 36.0 * (-t / 3.0f64).exp() + 19.0 * (-t / 2.0f64).exp();
        assert!(
            (r[2] - m2).abs() < 1e-12 && (r[4] - m3).abs() < 1e-12,
            "exact columns"
        );
        assert!((r[1] - m2).abs() < 0.01 * m2, "t={t}: M2 {} vs {m2}", r[1]);
        assert!((r[3] - m3).abs() < 0.02 * m3, "t={t}: M3 {} vs {m3}", r[3]);
    }
    let svg_text = std::fs::read_to_string(&svg).unwrap();
    assert!(svg_text.starts_with("<svg"), "an SVG");
    assert!(
        svg_text.contains("M2(t)") && svg_text.contains("M3: (ours − exact) / exact"),
        "panels"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `coagula run --help` names every scheme of the registry.
#[test]
fn run_help_names_every_scheme() {
    let out = coagula().args(["run", "--help"]).output().unwrap();
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for s in coagula_core::scheme::registry::SCHEMES {
        assert!(
            help.contains(&format!(" {},", s.name)) || help.contains(&format!(" {}]", s.name)),
            "`coagula run --help` does not name {}",
            s.name
        );
    }
}

/// `--csv -` writes the CSV to standard output (the table moves to standard error).
#[test]
fn run_csv_to_standard_output() {
    let out = coagula()
        .args(["run", "--m", "6", "--steps", "100", "--csv", "-"])
        .output()
        .unwrap();
    succeeded(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,M2,M2_exact,M3,M3_exact"));
    assert_eq!(lines.count(), 100);
    assert!(String::from_utf8_lossy(&out.stderr).contains("M2 exact"));
    assert!(!std::path::Path::new("-").exists(), "no file named '-'");
}

/// Every example scenario runs, scaled down (fewer particles, two replicas where it
/// has replicas), and reports every output time of every observable; where an exact
/// solution is known, its values are in the report.
#[test]
fn every_example_scenario_runs() {
    for path in examples() {
        let text = std::fs::read_to_string(&path).unwrap();
        let table: toml::Table = toml::from_str(&text).unwrap();
        let massflow = table["scheme"]["name"].as_str() == Some("massflow");
        let mut cmd = coagula();
        cmd.arg("run").arg(&path).args(["--json", "-", "--quiet"]);
        if massflow {
            cmd.args(["--m", "10"]);
        } else {
            cmd.args(["--particles", "4000"]);
        }
        let reps = table
            .get("run")
            .and_then(|r| r.get("replicas"))
            .and_then(|r| r.as_integer())
            .unwrap_or(1);
        if reps > 1 {
            cmd.args(["--replicas", "2"]);
        }
        let j = json_of(&cmd.output().unwrap());
        let times = j["times"].as_array().unwrap().len();
        let series = j["series"].as_array().unwrap();
        let observables = table["output"]["observables"].as_array().unwrap().len();
        assert_eq!(series.len(), observables, "{}", path.display());
        for s in series {
            assert_eq!(s["mean"].as_array().unwrap().len(), times);
            assert!(
                s["mean"].as_array().unwrap().iter().all(|v| v.is_f64()),
                "{}",
                path.display()
            );
        }
        if j["exact_solution"].is_string() {
            assert!(
                series.iter().any(|s| s["exact"][0].is_f64()),
                "{}: an exact solution with no exact values",
                path.display()
            );
        }
    }
}

/// Replicas are bit-identical whatever the thread count (the seed policy gives each
/// replica its own streams; statistics are merged in replica order).
#[test]
fn replicas_do_not_depend_on_threads() {
    let run = |threads: &str| {
        let out = coagula()
            .args([
                "run",
                "quickstart-golovin",
                "--particles",
                "3000",
                "--replicas",
                "6",
            ])
            .args(["--threads", threads, "--json", "-", "--quiet"])
            .output()
            .unwrap();
        let mut j = json_of(&out);
        // (the wall time, the memory, which counts the replicas run at once, and the
        // scenario, which names the thread count, differ)
        for key in [
            "seconds",
            "scenario",
            "memory_estimate",
            "resident_before",
            "resident_peak",
        ] {
            j.as_object_mut().unwrap().remove(key);
        }
        j
    };
    let one = run("1");
    assert_eq!(one, run("4"));
    assert_eq!(one, run("2"));
    // and a different seed is a different run
    let other = json_of(
        &coagula()
            .args([
                "run",
                "quickstart-golovin",
                "--particles",
                "3000",
                "--replicas",
                "6",
            ])
            .args(["--seed", "2", "--json", "-", "--quiet"])
            .output()
            .unwrap(),
    );
    assert_ne!(one["series"], other["series"]);
}

/// A scenario's observables against the exact solution, through the whole CLI: the
/// constant kernel from an exponential start with the default low-rank scheme; the
/// tolerance is 6 standard errors of 12 replicas (a wrong factor of 2 in the kernel's
/// coefficient moves M0(2) from 0.5 to 0.333, hundreds of SE).
#[test]
fn run_agrees_with_the_exact_solution() {
    let out = coagula()
        .args([
            "run",
            "quickstart-golovin",
            "--set",
            "kernel.kind=\"constant\"",
        ])
        .args([
            "--set",
            "output.count=4",
            "--particles",
            "20000",
            "--replicas",
            "12",
        ])
        .args(["--json", "-", "--quiet"])
        .output()
        .unwrap();
    let j = json_of(&out);
    assert_eq!(j["exact_solution"], "constant kernel, exponential start");
    for s in j["series"].as_array().unwrap() {
        for i in 0..4 {
            let (m, se, x) = (
                s["mean"][i].as_f64().unwrap(),
                s["std_error"][i].as_f64().unwrap(),
                s["exact"][i].as_f64().unwrap(),
            );
            assert!(
                (m - x).abs() <= 6.0 * se,
                "{}: {m} vs {x} (SE {se})",
                s["observable"]
            );
        }
    }
}

/// The scenario bench runs schemes side by side and prints a row for each.
#[test]
fn bench_scenario_compares_schemes() {
    let out = coagula()
        .args([
            "bench",
            "scenario",
            "quickstart-constant",
            "--schemes",
            "lowrank,rejection",
        ])
        .args(["--particles", "2000", "--repeat", "1"])
        .output();
    // --particles is not a bench flag: it goes through --set
    assert!(!out.unwrap().status.success());
    let out = coagula()
        .args([
            "bench",
            "scenario",
            "quickstart-constant",
            "--schemes",
            "lowrank,rejection",
        ])
        .args(["--set", "initial.particles=2000", "--repeat", "1"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    succeeded(&out);
    assert!(text.lines().any(|l| l.starts_with("lowrank ")), "{text}");
    assert!(text.lines().any(|l| l.starts_with("rejection ")), "{text}");
    assert!(text.contains("note: N0"), "{text}");
}

/// `--plot F.png` writes a PNG (the SVG rasterised), `--plot F.svg` an SVG with the
/// exact curve and the error panels.
#[test]
fn plots_in_both_formats() {
    let dir = std::env::temp_dir().join(format!("coagula-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for ext in ["png", "svg"] {
        let path = dir.join(format!("p.{ext}"));
        let out = coagula()
            .args([
                "run",
                "quickstart-constant",
                "--particles",
                "2000",
                "--replicas",
                "3",
            ])
            .arg("--plot")
            .arg(&path)
            .arg("--quiet")
            .output()
            .unwrap();
        succeeded(&out);
        let bytes = std::fs::read(&path).unwrap();
        if ext == "png" {
            assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        } else {
            let text = String::from_utf8(bytes).unwrap();
            assert!(text.contains("n1: (ours − exact) / exact"), "error panel");
            assert!(text.contains("95% CI of the mean"), "band");
            // axes with units, and the size-distribution panel (issue 40)
            assert!(text.contains("t (units of 1/(K c0))"), "time axis");
            assert!(text.contains("M0 [per volume]"), "value axis");
            assert!(text.contains("size distribution dN/dlog10 x"), "size panel");
            assert!(text.contains("dN/dlog10 x [per volume]"), "size axis");
        }
    }
    // log-spaced output times give a log time axis: ticks at decades only
    let path = dir.join("log.svg");
    let out = coagula()
        .args([
            "run",
            "quickstart-constant",
            "--particles",
            "2000",
            "--replicas",
            "3",
        ])
        .args([
            "--set",
            "output.spacing=\"log\"",
            "--set",
            "output.t-start=0.01",
        ])
        .arg("--plot")
        .arg(&path)
        .arg("--quiet")
        .output()
        .unwrap();
    succeeded(&out);
    let text = std::fs::read_to_string(&path).unwrap();
    for decade in [">\n0.01\n<", ">\n0.1\n<", ">\n1\n<", ">\n10\n<"] {
        assert!(text.contains(decade), "log time axis: {decade:?}");
    }
    assert!(!text.contains(">\n0.032\n<"), "no ticks between decades");
    std::fs::remove_dir_all(&dir).ok();
}

/// A run killed part-way resumes from its checkpoint directory and gives the same
/// CSV, bit for bit, as an unbroken run (the blocks it saved are taken, not rerun).
#[test]
fn a_killed_run_resumes_with_the_same_results() {
    let dir = std::env::temp_dir().join(format!("coagula-resume-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let ckpt = dir.join("ckpt");
    // 12 blocks of 8 replicas, one thread: about a second of work
    let args = |csv: &std::path::Path| {
        let mut c = coagula();
        c.args([
            "run",
            "quickstart-constant",
            "--replicas",
            "96",
            "--threads",
            "1",
        ])
        .args(["--particles", "100000", "--quiet", "--csv"])
        .arg(csv);
        c
    };
    let whole = dir.join("whole.csv");
    let out = args(&whole).output().unwrap();
    succeeded(&out);
    let mut child = args(&dir.join("killed.csv"))
        .arg("--checkpoint")
        .arg(&ckpt)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let saved = |d: &std::path::Path| {
        std::fs::read_dir(d).map_or(0, |it| {
            it.filter(|e| {
                e.as_ref()
                    .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "bin"))
            })
            .count()
        })
    };
    let t0 = std::time::Instant::now();
    while saved(&ckpt) == 0 && t0.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = saved(&ckpt);
    assert!(before >= 1, "no block saved in 120 s");
    let resumed = dir.join("resumed.csv");
    let out = args(&resumed)
        .arg("--checkpoint")
        .arg(&ckpt)
        .output()
        .unwrap();
    succeeded(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(&format!(
            "12 blocks of up to 8 replicas over 1 processes; {before} resumed"
        )),
        "{text}"
    );
    assert_eq!(
        std::fs::read(&whole).unwrap(),
        std::fs::read(&resumed).unwrap(),
        "resumed ({before} of 12 blocks saved) vs unbroken"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A `[sweep]` runs every combination (first axis slowest), each point with the bits
/// of a run of that point alone, and refuses a key swept and set at once.
#[test]
fn a_sweep_runs_every_point_as_a_run_of_its_own() {
    let dir = std::env::temp_dir().join(format!("coagula-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("sweep.toml");
    std::fs::write(
        &file,
        "[kernel]\nkind = \"constant\"\n[initial]\nkind = \"monodisperse\"\nparticles = 1000\n\
         [scheme]\nname = \"lowrank\"\n[output]\nt-end = 2.0\ncount = 2\nobservables = [\"M0\", \"M2\"]\n\
         [run]\nreplicas = 12\n[sweep]\ninitial.particles = [500, 2000]\nkernel.coefficient = [1.0, 2.0, 4.0]\n",
    )
    .unwrap();
    let out = coagula()
        .arg("run")
        .arg(&file)
        .args(["--quiet", "--csv", "-"])
        .output()
        .unwrap();
    succeeded(&out);
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "initial.particles,kernel.coefficient,t,M0,M0_ci95,M0_exact,M2,M2_ci95,M2_exact"
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 6 * 2);
    let keys: Vec<String> = rows
        .iter()
        .step_by(2)
        .map(|r| r.split(',').take(2).collect::<Vec<_>>().join(","))
        .collect();
    assert_eq!(
        keys,
        [
            "500,1.0", "500,2.0", "500,4.0", "2000,1.0", "2000,2.0", "2000,4.0"
        ]
    );
    // the point (2000, 4.0) alone
    let alone = coagula()
        .arg("run")
        .arg(&file)
        .args(["--quiet", "--csv", "-", "--set", "initial.particles=2000"])
        .args(["--set", "kernel.coefficient=4.0", "--set", "sweep={}"])
        .output()
        .unwrap();
    let alone_text = String::from_utf8_lossy(&alone.stdout);
    let alone_rows: Vec<&str> = alone_text.lines().skip(1).collect();
    assert_eq!(
        alone_rows.len(),
        2,
        "{}",
        String::from_utf8_lossy(&alone.stderr)
    );
    for (s, a) in rows[10..].iter().zip(&alone_rows) {
        assert_eq!(s.split_once(",4.0,").unwrap().1, *a);
    }
    // a key both swept and set, or lying in a table set, is refused
    for (set, says) in [
        (
            "kernel.coefficient=3.0",
            "is swept and kernel.coefficient is set",
        ),
        ("kernel={kind=\"constant\"}", "is swept and kernel is set"),
    ] {
        let out = coagula()
            .arg("run")
            .arg(&file)
            .args(["--set", set])
            .output()
            .unwrap();
        assert!(!out.status.success());
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(says),
            "--set {set}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A list of sizes (or counts) starts the particle schemes that take samples of the
/// number distribution (`dsa`, `lowrank-sizes`) from those very particles in the volume
/// N / c0: before any event M0 = c0, M1 = c0 · mean and M2 = c0 · mean of x². (They
/// were once resampled from the mass distribution, the mass-flow schemes' start: M0
/// then came out as 0.67 c0 for these sizes.)
#[test]
fn a_size_list_starts_direct_schemes_from_its_particles() {
    let dir = std::env::temp_dir().join(format!("coagula-cli-sizes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let common = "[kernel]\nkind = \"constant\"\n[output]\ntimes = [1e-9]\nobservables = [\"M0\", \"M1\", \"M2\"]\n[run]\nreplicas = 2\n";
    let starts = [
        "[initial]\nkind = \"sizes\"\nsizes = [1.0, 1.0, 1.0, 5.0]\nconcentration = 2.0\n",
        "[initial]\nkind = \"counts\"\ncounts = [3, 0, 0, 0, 1]\nparticles = 8\nconcentration = 2.0\n",
    ];
    for (i, start) in starts.iter().enumerate() {
        let file = dir.join(format!("start{i}.toml"));
        std::fs::write(&file, format!("{start}{common}")).unwrap();
        for scheme in ["dsa", "lowrank-sizes"] {
            let out = coagula()
                .args([
                    "run",
                    file.to_str().unwrap(),
                    "--scheme",
                    scheme,
                    "--csv",
                    "-",
                ])
                .output()
                .unwrap();
            succeeded(&out);
            let text = String::from_utf8(out.stdout).unwrap();
            let row = text.lines().last().unwrap();
            let v: Vec<f64> = row.split(',').map(|x| x.parse().unwrap()).collect();
            // t, M0, ±, M1, ±, M2, ±
            for (got, want) in [(v[1], 2.0), (v[3], 4.0), (v[5], 14.0)] {
                approx::assert_relative_eq!(got, want, max_relative = 1e-12);
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The standard output of a `coagula` run that must succeed.
fn stdout_of(args: &[&str]) -> String {
    let out = coagula().args(args).output().unwrap();
    succeeded(&out);
    String::from_utf8(out.stdout).unwrap()
}

/// Both peers' five recorded rows are printed.
fn assert_peer_rows(text: &str) {
    for code in ["PySDM", "PyPartMC"] {
        let rows = text.lines().filter(|l| l.starts_with(code)).count();
        assert_eq!(rows, 5, "{code} rows in\n{text}");
    }
}

/// `coagula bench peers` parses its built-in figures and prints every peer row next to
/// ours (a short run: 2 seeds, 2^12 particles).
#[test]
fn bench_peers_prints_the_recorded_figures() {
    let text = stdout_of(&["bench", "peers", "--seeds", "2", "--max-log2n", "12"]);
    assert_peer_rows(&text);
    assert!(
        text.contains("3.0.1") && text.contains("2026-12-03"),
        "{text}"
    );
    // our one row: 2^12 particles, errors printed as percentages
    let ours = text
        .lines()
        .find(|l| l.trim_start().starts_with("2^12"))
        .unwrap();
    assert!(ours.matches('%').count() == 2, "{ours}");
}

/// `coagula bench peers --problem constant`: the constant kernel's recorded peer rows,
/// and our two layouts (continuous sizes and the 1/64 grid), each with errors small
/// enough to show the moments are read in the right units (a grid M2 not divided by
/// 64² would be off by a factor of 4096).
#[test]
fn bench_peers_runs_the_constant_kernel_problem() {
    let text = stdout_of(&[
        "bench",
        "peers",
        "--problem",
        "constant",
        "--seeds",
        "2",
        "--max-log2n",
        "12",
    ]);
    assert!(text.contains("to t = 10"), "{text}");
    assert_peer_rows(&text);
    assert!(text.contains("1/64 grid"), "{text}");
    let ours: Vec<&str> = text
        .lines()
        .filter(|l| l.trim_start().starts_with("2^12"))
        .collect();
    assert_eq!(ours.len(), 2, "{text}");
    for row in ours {
        // 2^12 particles, 2 seeds: M0 and M2 within 10 % (about 5 standard errors)
        let errs: Vec<f64> = row
            .split_whitespace()
            .filter_map(|w| w.strip_suffix('%'))
            .map(|w| w.parse().unwrap())
            .collect();
        assert_eq!(errs.len(), 2, "{row}");
        assert!(errs.iter().all(|&e| e < 10.0), "{row}");
    }
}

/// `coagula bench lowrank-small --host-steps`: cells built once and stepped, the three
/// layouts each printing a row with events per call near the one event it aims at.
#[test]
fn bench_lowrank_small_steps_cells_like_a_host() {
    let text = stdout_of(&[
        "bench",
        "lowrank-small",
        "--n0",
        "64",
        "--replicas",
        "20",
        "--host-steps",
        "20",
    ]);
    for layout in ["tree", "bucketed", "sizes"] {
        let row = text
            .lines()
            .find(|l| l.split_whitespace().nth(1) == Some(layout))
            .unwrap_or_else(|| panic!("{layout} in\n{text}"));
        // N0, layout, '|', build ns, ns/event, events/call, t, M
        let per_call: f64 = row.split_whitespace().nth(5).unwrap().parse().unwrap();
        assert!((0.3..3.0).contains(&per_call), "{row}");
    }
}

/// Issue 40: the benches' paper columns printed `NaN` where the paper has no row;
/// a missing figure is `-`.
#[test]
fn bench_tables_print_no_nan() {
    for args in [
        &[
            "bench",
            "temperature",
            "--n0",
            "2000",
            "--times",
            "1",
            "--scaled-times",
            "--skip-baseline",
        ][..],
        &["bench", "dsmc", "--particles", "1000", "--times", "1,2"][..],
    ] {
        let out = coagula().args(args).output().unwrap();
        assert!(out.status.success(), "{args:?}");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(!text.contains("NaN"), "{args:?}:\n{text}");
    }
}
