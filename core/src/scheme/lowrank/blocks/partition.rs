//! The mosaic partition of the size-pair matrix into blocks (Dyachenko, Matveev &
//! Valiakhmetov 2025; `docs/design/block-majorants.md`): a quad-tree over the upper
//! triangle of the `M × M` matrix of size indices, a block kept whole once its gap to
//! the diagonal is at least `separation` times its side, split otherwise down to side
//! `2^min_level`.
//!
//! A block at level ℓ is a pair of aligned strips of `2^ℓ` sizes, rows `a` and columns
//! `c ≥ a` (`c = a`: a diagonal block, which holds both orders of its pairs). Every
//! unordered pair of sizes lies in exactly one block. For each level and strip the
//! partition lists the blocks that meet it (as rows, or as columns off the diagonal), so
//! a count change finds the blocks whose sums it moves.

use crate::error::Result;
use crate::memory::try_reserve;
use alloc::vec::Vec;

/// One block: its level and its row and column strips at that level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Block {
    /// Side `2^level` sizes.
    pub level: u8,
    /// Row strip: sizes (indices) `row·2^level .. (row + 1)·2^level`.
    pub row: u32,
    /// Column strip, `col ≥ row`.
    pub col: u32,
}

impl Block {
    /// Whether the block straddles the diagonal (rows and columns the same strip).
    #[inline]
    pub fn diagonal(&self) -> bool {
        self.row == self.col
    }
}

/// A block in the list of a strip it meets: the block, the strip on its other side
/// (itself on the diagonal) and the block's bound, kept here so that a count change
/// reads its blocks from one run of memory.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Member {
    pub id: u32,
    pub other: u32,
    pub sup: f64,
}

/// The partition of a matrix of `2^levels` sizes (see the module docs). Blocks are
/// numbered by level, row strip and column strip, so that the blocks of a row strip
/// are neighbours.
#[derive(Clone, Debug)]
pub(crate) struct Partition {
    pub blocks: Vec<Block>,
    /// `log2 M`.
    pub levels: u32,
    pub min_level: u32,
    /// Per (level, strip), from `min_level` up, the range of `members` meeting it.
    starts: Vec<u32>,
    members: Vec<Member>,
}

/// Calls `f` for every block of the partition of `2^levels` sizes, in a fixed order.
fn visit(levels: u32, min_level: u32, sep: u64, f: &mut dyn FnMut(Block)) {
    fn go(l: u32, a: u64, c: u64, min: u32, sep: u64, f: &mut dyn FnMut(Block)) {
        // (gap c − a − 1 at least sep)
        let whole = l == min || (c > a && c - a > sep);
        if whole {
            f(Block {
                level: l as u8,
                row: a as u32,
                col: c as u32,
            });
        } else if c == a {
            go(l - 1, 2 * a, 2 * a, min, sep, f);
            go(l - 1, 2 * a, 2 * a + 1, min, sep, f);
            go(l - 1, 2 * a + 1, 2 * a + 1, min, sep, f);
        } else {
            for (da, dc) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                go(l - 1, 2 * a + da, 2 * c + dc, min, sep, f);
            }
        }
    }
    go(levels, 0, 0, min_level.min(levels), sep, f);
}

impl Partition {
    /// The number of blocks of the partition of `2^levels` sizes.
    pub fn count(levels: u32, min_level: u32, sep: u64) -> usize {
        let mut n = 0;
        visit(levels, min_level, sep, &mut |_| n += 1);
        n
    }

    /// Bytes of a partition of `b` blocks over `2^levels` sizes: the blocks, their
    /// members in the lists of their row and their column strip (at most two, a
    /// `Member` each), and the list starts, about `2^levels / 2^min_level · 2` of them.
    pub fn bytes(levels: u32, min_level: u32, b: usize) -> Option<usize> {
        let strips = (2usize << levels) >> min_level.min(levels);
        let per = core::mem::size_of::<Block>() + 2 * core::mem::size_of::<Member>();
        b.checked_mul(per)?
            .checked_add(strips.checked_add(1)?.checked_mul(4)?)
    }

    pub fn new(levels: u32, min_level: u32, sep: u64) -> Result<Partition> {
        let min_level = min_level.min(levels);
        let mut blocks = Vec::new();
        try_reserve(&mut blocks, Self::count(levels, min_level, sep))?;
        visit(levels, min_level, sep, &mut |b| blocks.push(b));
        blocks.sort_unstable_by_key(|b| (b.level, b.row, b.col));
        // the strips of each level, from min_level up
        let mut base = Vec::new();
        let mut strips = 0usize;
        for l in min_level..=levels {
            base.push(strips);
            strips += 1usize << (levels - l);
        }
        let key = |l: u32, s: u32| base[(l - min_level) as usize] + s as usize;
        let mut starts = Vec::new();
        try_reserve(&mut starts, strips + 1)?;
        starts.resize(strips + 1, 0u32);
        let meets = |b: &Block, f: &mut dyn FnMut(usize, u32)| {
            f(key(u32::from(b.level), b.row), b.col);
            if !b.diagonal() {
                f(key(u32::from(b.level), b.col), b.row);
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
            sup: 0.0,
        };
        members.resize(starts[strips] as usize, none);
        let mut fill = starts.clone();
        for (id, b) in blocks.iter().enumerate() {
            meets(b, &mut |k, other| {
                members[fill[k] as usize] = Member {
                    id: id as u32,
                    other,
                    sup: 0.0,
                };
                fill[k] += 1;
            });
        }
        Ok(Partition {
            blocks,
            levels,
            min_level,
            starts,
            members,
        })
    }

    /// Sets every member's bound from the blocks' (`sup[id]`).
    pub fn set_sups(&mut self, sup: &[f64]) {
        for m in &mut self.members {
            m.sup = sup[m.id as usize];
        }
    }

    /// Calls `f(level, strip, members)` for every level, with the blocks that hold
    /// size index `p` among their rows or columns (`strip`: p's strip at that level).
    #[inline]
    pub fn each_meeting(&self, p: u64, mut f: impl FnMut(u32, u64, &[Member])) {
        let mut base = 0usize;
        for l in self.min_level..=self.levels {
            let strip = p >> l;
            let k = base + strip as usize;
            f(
                l,
                strip,
                &self.members[self.starts[k] as usize..self.starts[k + 1] as usize],
            );
            base += 1usize << (self.levels - l);
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
        for (levels, min, sep) in [(3, 3, 2), (5, 0, 2), (6, 2, 2), (6, 1, 1), (7, 3, 3)] {
            let p = Partition::new(levels, min, sep).unwrap();
            let m = 1u64 << levels;
            let mut seen = alloc::vec![0u32; (m * m) as usize];
            for b in &p.blocks {
                let s = 1u64 << b.level;
                assert!(b.col >= b.row);
                for i in 0..s {
                    for j in 0..s {
                        let (x, y) = (u64::from(b.row) * s + i, u64::from(b.col) * s + j);
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
                    for m in ms {
                        let b = p.blocks[m.id as usize];
                        assert_eq!(u32::from(b.level), l);
                        let (mine, other) = if u64::from(b.row) == strip {
                            (b.row, b.col)
                        } else {
                            (b.col, b.row)
                        };
                        assert_eq!((u64::from(mine), m.other), (strip, other));
                        found.push(m.id as usize);
                    }
                });
                for (id, b) in p.blocks.iter().enumerate() {
                    let s = 1u64 << b.level;
                    let holds =
                        |strip: u32| (u64::from(strip) * s..u64::from(strip + 1) * s).contains(&x);
                    let meets = holds(b.row) || holds(b.col);
                    assert_eq!(found.contains(&id), meets, "size {x} block {b:?}");
                }
                let mut unique = found.clone();
                unique.sort_unstable();
                unique.dedup();
                assert_eq!(unique.len(), found.len());
            }
            assert_eq!(Partition::count(levels, min, sep), p.blocks.len());
        }
        // what the memory estimate assumes
        for levels in [10, 14, 17] {
            let per = Partition::count(levels, super::super::MIN_LEVEL, super::super::SEPARATION)
                as f64
                / (1u64 << levels) as f64;
            assert!(
                per <= super::super::BLOCKS_PER_SIZE && per > 0.95 * super::super::BLOCKS_PER_SIZE,
                "{per}"
            );
        }
    }
}
