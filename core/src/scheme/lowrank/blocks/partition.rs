//! The mosaic partition of the size-pair matrix into blocks (Dyachenko, Matveev &
//! Valiakhmetov 2025; `docs/design/block-majorants.md`): a quad-tree over the upper
//! triangle of the `M × M` matrix of size indices, a block kept whole once its gap to
//! the diagonal is at least `separation` times its side, split otherwise down to side
//! `2^min_level`.
//!
//! A block is a row strip and a column strip, each an aligned strip of the count tree.
//! The quad-tree's blocks are square: strips of `2^ℓ` sizes, rows `a` and columns
//! `c ≥ a` (`c = a`: a diagonal block, which holds both orders of its pairs). A square
//! kept whole whose rows are the first strip (sizes `1 ..= 2^ℓ`) has its rows cut where
//! the size doubles (1, 2, 3..4, ..., `2^(ℓ−1)+1 ..= 2^ℓ`), each piece against the whole
//! column strip: a kernel that goes as a power of the smaller size (the atmospheric
//! kernel as `x^{-5/9}`) would otherwise be bounded at size 1 across rows that reach
//! `2^ℓ`, and late in a run, when most particles are large, such blocks accepted
//! 1–3 % of their proposals. So every block's rows and columns span sizes within a
//! factor 2, apart from the finest level next to the diagonal.
//!
//! With `log_linear` (a kernel smooth next to the diagonal,
//! `CoagulationKernel::log_linear_blocks`), a square is also kept whole once its rows
//! are a *thin* strip, at most `2^-LOG_LINEAR_BITS` (1/32) of its smallest size wide,
//! as the buckets of the bucketed layout: the partition then grows by about 190 blocks
//! per added octave of sizes instead of 1.25 blocks per size.
//!
//! Every unordered pair of sizes lies in exactly one block. For each strip the partition
//! lists the blocks that meet it (as rows, or as columns off the diagonal), so a count
//! change finds the blocks whose sums it moves.

use crate::error::Result;
use crate::memory::try_reserve;
use alloc::vec::Vec;
use core::ops::Range;

/// One block: a row strip and a column strip, each an aligned strip of sizes (a node of
/// the count tree) given by its level and index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Block {
    /// The row strip's level: `2^row_level` sizes.
    pub row_level: u8,
    /// The column strip's level.
    pub col_level: u8,
    /// Row strip: size indices `row·2^row_level .. (row + 1)·2^row_level`.
    pub row: u32,
    /// Column strip, at or after the rows.
    pub col: u32,
}

impl Block {
    /// Whether the block straddles the diagonal (rows and columns the same strip).
    #[inline]
    pub fn diagonal(&self) -> bool {
        self.row == self.col && self.row_level == self.col_level
    }

    /// The first and one past the last size index of the rows and of the columns.
    pub fn ranges(&self) -> ((u64, u64), (u64, u64)) {
        let span = |l: u8, s: u32| (u64::from(s) << l, u64::from(s + 1) << l);
        (
            span(self.row_level, self.row),
            span(self.col_level, self.col),
        )
    }
}

/// A block in the list of a strip it meets: the block, the count-tree node of the strip
/// on its other side (its own on the diagonal), the position in `members` of the
/// block's entry in that strip's list (its own on the diagonal), and the strip's
/// allowance in the block (the particle number this side may reach before the block's
/// majorant must be looked at; kept by the engine, saturated at `u32::MAX`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Member {
    pub id: u32,
    pub other: u32,
    pub twin: u32,
    pub allow: u32,
}

/// The partition of a matrix of `2^levels` sizes (see the module docs). Blocks are
/// numbered by row strip and column strip, so that the blocks of a row strip are
/// neighbours.
#[derive(Clone, Debug)]
pub(crate) struct Partition {
    pub blocks: Vec<Block>,
    /// `log2 M`.
    pub levels: u32,
    pub min_level: u32,
    /// Per (level, strip), from `min_level` up, then strips 0 and 1 of the levels below
    /// it, the range of `members` meeting it.
    starts: Vec<u32>,
    pub members: Vec<Member>,
}

/// A thin strip is at most `2^-LOG_LINEAR_BITS` of its smallest size wide.
pub(crate) const LOG_LINEAR_BITS: u32 = 5;

/// Calls `f` for every block of the partition of `2^levels` sizes, in a fixed order.
fn visit(levels: u32, min_level: u32, sep: u64, log_linear: bool, f: &mut dyn FnMut(Block)) {
    fn go(l: u32, a: u64, c: u64, min: u32, sep: u64, ll: bool, f: &mut dyn FnMut(Block)) {
        // (gap c − a − 1 at least sep)
        let apart = c > a && c - a > sep;
        // rows 2^l sizes from size a·2^l + 1 (indices are sizes − 1), at most
        // 2^-LOG_LINEAR_BITS of it: kept whole when the kernel allows (the columns, at
        // or after the rows, are thinner still)
        let thin = ll && (1u64 << (l + LOG_LINEAR_BITS)) <= (a << l) + 1;
        if apart && a == 0 && l > 0 {
            // rows 1 ..= 2^l: the kernel may vary as a power of the smaller size, so
            // the rows are cut where they double (sizes 1, 2, 3..4, 5..8, ...), each
            // against the whole column strip
            for (rl, row) in core::iter::once((0, 0)).chain((0..l).map(|k| (k, 1))) {
                f(Block {
                    row_level: rl as u8,
                    col_level: l as u8,
                    row,
                    col: c as u32,
                });
            }
        } else if l == min || apart || thin {
            f(Block {
                row_level: l as u8,
                col_level: l as u8,
                row: a as u32,
                col: c as u32,
            });
        } else if c == a {
            go(l - 1, 2 * a, 2 * a, min, sep, ll, f);
            go(l - 1, 2 * a, 2 * a + 1, min, sep, ll, f);
            go(l - 1, 2 * a + 1, 2 * a + 1, min, sep, ll, f);
        } else {
            for (da, dc) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                go(l - 1, 2 * a + da, 2 * c + dc, min, sep, ll, f);
            }
        }
    }
    go(levels, 0, 0, min_level.min(levels), sep, log_linear, f);
}

impl Partition {
    /// The number of blocks of the partition of `2^levels` sizes.
    pub fn count(levels: u32, min_level: u32, sep: u64, log_linear: bool) -> usize {
        let mut n = 0;
        visit(levels, min_level, sep, log_linear, &mut |_| n += 1);
        n
    }

    /// The member lists' keys: every strip from `min_level` up, then strips 0 and 1 of
    /// each level below it.
    fn keys(levels: u32, min_level: u32) -> usize {
        let min_level = min_level.min(levels);
        ((2usize << levels) >> min_level) + 2 * min_level as usize
    }

    /// Bytes of a partition of `b` blocks over `2^levels` sizes: the blocks, their
    /// members in the lists of their row and their column strip (at most two, a
    /// `Member` each), and the list starts.
    pub fn bytes(levels: u32, min_level: u32, b: usize) -> Option<usize> {
        let per = core::mem::size_of::<Block>() + 2 * core::mem::size_of::<Member>();
        b.checked_mul(per)?.checked_add(
            Self::keys(levels, min_level)
                .checked_add(1)?
                .checked_mul(4)?,
        )
    }

    pub fn new(levels: u32, min_level: u32, sep: u64, log_linear: bool) -> Result<Partition> {
        if levels > 31 {
            // (member lists name count-tree nodes, below 2^32)
            return Err(crate::error::Error::Capacity {
                name: "maximum particle size",
                capacity: 1 << 31,
            });
        }
        let min_level = min_level.min(levels);
        let mut blocks = Vec::new();
        try_reserve(&mut blocks, Self::count(levels, min_level, sep, log_linear))?;
        visit(levels, min_level, sep, log_linear, &mut |b| blocks.push(b));
        blocks.sort_unstable_by_key(|b| (b.row_level, b.row, b.col_level, b.col));
        let strips = Self::keys(levels, min_level);
        let mut starts = Vec::new();
        try_reserve(&mut starts, strips + 1)?;
        starts.resize(strips + 1, 0u32);
        let node = |l: u8, s: u32| ((1u32 << levels) >> l) + s;
        let meets = |b: &Block, f: &mut dyn FnMut(usize, u32)| {
            let (rk, ck) = (
                Self::key(levels, min_level, u32::from(b.row_level), u64::from(b.row)),
                Self::key(levels, min_level, u32::from(b.col_level), u64::from(b.col)),
            );
            // (every strip a block uses has a key)
            if let Some(k) = rk {
                f(k, node(b.col_level, b.col));
            }
            if !b.diagonal()
                && let Some(k) = ck
            {
                f(k, node(b.row_level, b.row));
            }
        };
        for b in &blocks {
            meets(b, &mut |k, _| starts[k + 1] += 1);
        }
        for k in 0..strips {
            starts[k + 1] += starts[k];
        }
        let mut members = Vec::new();
        try_reserve(&mut members, starts[strips] as usize)?;
        let none = Member {
            id: 0,
            other: 0,
            twin: 0,
            allow: 0,
        };
        members.resize(starts[strips] as usize, none);
        let mut fill = starts.clone();
        for (id, b) in blocks.iter().enumerate() {
            let mut at = [u32::MAX; 2];
            let mut n = 0;
            meets(b, &mut |k, other| {
                members[fill[k] as usize] = Member {
                    id: id as u32,
                    other,
                    twin: 0,
                    allow: 0,
                };
                at[n] = fill[k];
                n += 1;
                fill[k] += 1;
            });
            // (every block is in its row strip's list, and off the diagonal in its
            // column strip's)
            let (a, c) = (at[0], if n == 2 { at[1] } else { at[0] });
            members[a as usize].twin = c;
            members[c as usize].twin = a;
        }
        Ok(Partition {
            blocks,
            levels,
            min_level,
            starts,
            members,
        })
    }

    /// The member list of strip `strip` of level `l`, if strips of that level and index
    /// can hold blocks.
    #[inline]
    fn key(levels: u32, min_level: u32, l: u32, strip: u64) -> Option<usize> {
        if l >= min_level {
            let base = ((2usize << levels) >> min_level) - ((2usize << levels) >> l);
            Some(base + strip as usize)
        } else {
            (strip <= 1)
                .then(|| ((2usize << levels) >> min_level) + 2 * l as usize + strip as usize)
        }
    }

    /// The range in `members` of the list of count-tree node `node` (empty for a node
    /// no block uses).
    #[inline]
    pub fn list(&self, node: u32) -> Range<usize> {
        let top = 31 - node.leading_zeros();
        let l = self.levels - top;
        let strip = u64::from(node - (1 << top));
        Self::key(self.levels, self.min_level, l, strip).map_or(0..0, |k| {
            self.starts[k] as usize..self.starts[k + 1] as usize
        })
    }

    /// The position in `members` of block `id`'s entry in the list of `node`.
    pub fn find(&self, node: u32, id: usize) -> Option<usize> {
        self.list(node).find(|&k| self.members[k].id as usize == id)
    }

    /// Calls `f(level, strip, members)` for every level, with the blocks that hold
    /// size index `p` among their rows or columns (`strip`: p's strip at that level).
    #[cfg(test)]
    pub fn each_meeting(&self, p: u64, mut f: impl FnMut(u32, u64, &[Member])) {
        for top in 0..=self.levels {
            let l = self.levels - top;
            let node = (1u32 << top) + (p >> l) as u32;
            f(l, p >> l, &self.members[self.list(node)]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every unordered pair of sizes in exactly one block, and each block found from
    /// each of its sizes.
    #[test]
    fn blocks_cover_each_pair_once() {
        for (levels, min, sep, ll) in [
            (3, 3, 2, false),
            (5, 0, 2, false),
            (6, 2, 2, false),
            (6, 1, 1, false),
            (7, 3, 3, false),
            (7, 2, 1, false),
            (10, 2, 1, true),
            (9, 0, 2, true),
        ] {
            let p = Partition::new(levels, min, sep, ll).unwrap();
            let m = 1u64 << levels;
            let node = |l: u8, s: u32| ((m >> l) + u64::from(s)) as u32;
            let mut seen = alloc::vec![0u32; (m * m) as usize];
            for b in &p.blocks {
                let ((r0, r1), (c0, c1)) = b.ranges();
                assert!(c0 >= r0 && (c0 >= r1 || b.diagonal()), "{b:?}");
                for x in r0..r1 {
                    for y in c0..c1 {
                        if x <= y {
                            seen[(x * m + y) as usize] += 1;
                        }
                    }
                }
            }
            for x in 0..m {
                for y in x..m {
                    assert_eq!(seen[(x * m + y) as usize], 1, "{levels} {min} ({x}, {y})");
                }
            }
            for x in 0..m {
                let mut found = alloc::vec::Vec::new();
                p.each_meeting(x, |l, strip, ms| {
                    for mb in ms {
                        let b = p.blocks[mb.id as usize];
                        let here = (l as u8, strip as u32);
                        let other = if (b.row_level, b.row) == here {
                            node(b.col_level, b.col)
                        } else {
                            assert_eq!((b.col_level, b.col), here);
                            node(b.row_level, b.row)
                        };
                        assert_eq!(mb.other, other);
                        found.push(mb.id as usize);
                    }
                });
                for (id, b) in p.blocks.iter().enumerate() {
                    let ((r0, r1), (c0, c1)) = b.ranges();
                    let meets = (r0..r1).contains(&x) || (c0..c1).contains(&x);
                    assert_eq!(found.contains(&id), meets, "size {x} block {b:?}");
                }
                let mut unique = found.clone();
                unique.sort_unstable();
                unique.dedup();
                assert_eq!(unique.len(), found.len());
            }
            assert_eq!(Partition::count(levels, min, sep, ll), p.blocks.len());
            // twins: each entry's twin is the block's entry in the other strip's list
            for (k, mb) in p.members.iter().enumerate() {
                let t = p.members[mb.twin as usize];
                assert_eq!((t.id, t.twin as usize), (mb.id, k));
                let diagonal = p.blocks[mb.id as usize].diagonal();
                assert_eq!(mb.twin as usize == k, diagonal);
            }
            for node in 1..2 * m as u32 {
                for k in p.list(node) {
                    assert_eq!(p.members[p.members[k].twin as usize].other, node);
                }
            }
        }
    }

    /// The rows of a block hold sizes within a factor 2 of each other (sizes are
    /// indices + 1), apart from the diagonal blocks and their neighbours at the finest
    /// level; columns too.
    #[test]
    fn strips_within_a_factor_two() {
        let p = Partition::new(12, 2, 1, false).unwrap();
        for b in &p.blocks {
            let ((r0, r1), (c0, c1)) = b.ranges();
            if usize::from(b.row_level) > 2 || b.col - b.row > 1 {
                assert!(r1 <= 2 * (r0 + 1), "{b:?}");
                assert!(c1 <= 2 * (c0 + 1), "{b:?}");
            }
        }
    }

    /// What the memory estimate assumes.
    #[test]
    fn blocks_per_size() {
        for levels in 6..=21 {
            let per = Partition::count(
                levels,
                super::super::MIN_LEVEL,
                super::super::SEPARATION,
                false,
            ) as f64
                / (1u64 << levels) as f64;
            assert!(per <= super::super::BLOCKS_PER_SIZE, "{levels}: {per}");
        }
    }

    /// The log-linear partition: every block with rows wider than the finest level
    /// either lies apart from the diagonal or has thin rows (at most 1/32 of their
    /// smallest size, and more than 1/64 of it: the parent strip was not thin); and
    /// the blocks grow as the octaves, not as the sizes.
    #[test]
    fn log_linear_blocks_are_thin_and_few() {
        let (min, sep) = (super::super::MIN_LEVEL, super::super::SEPARATION);
        let p = Partition::new(16, min, sep, true).unwrap();
        let mut thin = 0;
        for b in &p.blocks {
            let ((r0, r1), (c0, _)) = b.ranges();
            let (w, size) = (r1 - r0, r0 + 1);
            // (not apart: the gap to the diagonal below sep sides)
            let near = c0 <= r0 + sep * w;
            if near && u32::from(b.row_level) > min {
                assert!(w << LOG_LINEAR_BITS <= size, "{b:?}");
                // (the parent strip, from at most w sizes lower, was not thin)
                assert!((w << (LOG_LINEAR_BITS + 1)) + w > size, "{b:?}");
                thin += 1;
            }
        }
        assert!(thin > 0);
        for levels in 12..=24 {
            let n = Partition::count(levels, min, sep, true);
            let per_octave = n as f64 / f64::from(levels);
            assert!(per_octave < 160.0, "{levels}: {n} blocks");
            if levels <= 20 {
                assert!(n <= Partition::count(levels, min, sep, false));
            }
        }
    }
}
