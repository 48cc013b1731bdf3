//! The engine's bookkeeping: allowances, caps and majorants after every event.

use super::*;
use crate::kernel::Coagulation;
use rand_pcg::Pcg64Mcg;

/// Every block's sides within their allowances, the allowances within `Î`, `I ≤ Î`, and
/// every cap at or below the least allowance of its list.
fn check(e: &BlockEngine) {
    for (id, b) in e.part.blocks.iter().enumerate() {
        let (rn, cn) = e.nodes(b);
        let allow = |node: usize| {
            let k = e
                .part
                .find(node as u32, id)
                .expect("a block in its strips' lists");
            let a = e.part.members[k].allow;
            assert!(
                e.caps[node] <= a,
                "cap of node {node} above block {id}'s allowance"
            );
            u64::from(a)
        };
        let (x, y) = (allow(rn), if b.diagonal() { allow(rn) } else { allow(cn) });
        let (r, c) = (e.tree[rn], e.tree[cn]);
        assert!(
            r <= x && c <= y,
            "block {id}: counts ({r}, {c}) past ({x}, {y})"
        );
        let hat = e.hats.leaf(id);
        assert!(e.intensity_of(id) <= hat, "block {id}: I above Î");
        assert!(
            e.sup[id][0] * pairs(b.diagonal(), x, y) <= hat,
            "block {id}: allowances above Î"
        );
    }
}

/// Merges proposed pairs (every proposal accepted: the bookkeeping does not depend on
/// the rule) through growth of M and doublings, checking after every event.
#[test]
fn allowances_hold_through_events_growth_and_doubling() {
    let k = Coagulation::atmospheric();
    let mut counts = alloc::vec![0u64; 40];
    counts[0] = 300;
    counts[1] = 60;
    counts[39] = 5;
    let n0: u64 = counts.iter().sum();
    let mut pop = Population::new(&counts, 100.0).unwrap();
    let mut e = <BlockEngine as ProposalEngine<1>>::build(&k, &counts, &pop).unwrap();
    check(&e);
    let mut rng = Pcg64Mcg::new(45);
    let (mut events, mut doublings, m0) = (0, 0, e.m);
    while events < 1000 {
        let Some(c) = <BlockEngine as ProposalEngine<1>>::propose(&mut e, &mut rng) else {
            check(&e);
            continue;
        };
        let out = Outcome::Merge { size: c.x + c.y };
        <BlockEngine as ProposalEngine<1>>::prepare(&mut e, &k, &out, &pop).unwrap();
        <BlockEngine as ProposalEngine<1>>::apply(&mut e, &c, &out);
        pop.n -= 1;
        events += 1;
        if pop.n < n0 / 2 {
            <BlockEngine as ProposalEngine<1>>::double(&mut e, &pop);
            pop.n *= 2;
            doublings += 1;
        }
        check(&e);
    }
    assert!(
        doublings >= 3 && e.m > m0,
        "{doublings} doublings, M {m0} -> {}",
        e.m
    );
}

/// The split of a block's headroom: both sides at or above their counts, the pair
/// within `Î`, on and off the diagonal, with empty sides and near the float limits.
#[test]
fn allot_stays_within_the_majorant() {
    for diagonal in [false, true] {
        for (r, c) in [
            (0, 0),
            (0, 3),
            (5, 0),
            (1, 1),
            (7, 2),
            (1000, 3),
            (1 << 40, 1 << 20),
        ] {
            let c = if diagonal { r } else { c };
            for sup in [1e-300, 0.37, 4.0, 1e200] {
                let i = sup * pairs(diagonal, r, c);
                for hat in [i, hat_for(i), 2.0 * i + 1.0] {
                    let (x, y) = allot(diagonal, sup, hat, r, c);
                    assert!(
                        x >= r && y >= c,
                        "{diagonal} ({r}, {c}) {sup} {hat}: ({x}, {y})"
                    );
                    assert!(
                        sup * pairs(diagonal, x, y) <= hat,
                        "{diagonal} ({r}, {c}) {sup} {hat}"
                    );
                    if diagonal {
                        assert_eq!(x, y);
                    }
                }
            }
        }
    }
    assert_eq!(allot(false, 0.0, 1.0, 3, 4), (u64::MAX, u64::MAX));
    assert_eq!(allot(false, 1.0, f64::INFINITY, 3, 4), (u64::MAX, u64::MAX));
}

/// The memory of a log-linear partition, as the estimate counts it: the engine's own
/// figure for the blocks it builds, a few hundred an octave — a small fraction of the
/// per-size figure the other kernels take (1.33 blocks a size), and above the count
/// tree alone.
#[test]
fn log_linear_memory_is_the_count_tree_and_few_blocks() {
    let k = Coagulation::gravitational(1e-5).unwrap();
    for levels in [10u32, 16, 20] {
        let m = 1u64 << levels;
        let bytes = BlockEngine::log_linear_bytes(m).unwrap();
        let e = BlockEngine::with_size(&k, &[100, 50], m, usize::MAX).unwrap();
        assert_eq!(
            Some(bytes),
            BlockEngine::bytes_for(m, e.part.blocks.len()),
            "2^{levels}"
        );
        let per_size = (24.0 + 72.0 * BLOCKS_PER_SIZE) * m as f64;
        assert!(bytes as f64 > 24.0 * m as f64, "2^{levels}: {bytes}");
        if levels >= 16 {
            assert!((bytes as f64) < per_size / 3.0, "2^{levels}: {bytes}");
        }
    }
    assert_eq!(BlockEngine::log_linear_bytes(3 << 10), None);
    assert_eq!(BlockEngine::log_linear_bytes(1 << 32), None);
}
