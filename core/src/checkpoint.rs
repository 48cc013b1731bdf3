//! Checkpoint and restore of a scheme's full state into a caller buffer.
//!
//! The format is little-endian: a magic word, a format version, the scheme's tag, the
//! scheme's fields, and a 64-bit checksum of everything before it. Kernels are not
//! stored (user kernels are code): a checkpoint is restored into a scheme built with
//! the same kernel and configuration, and a run split by save and restore is
//! bit-identical to the run without a break.
//!
//! Restoring checks the checksum first (any change of one 8-byte word is detected for
//! certain, other corruption with probability 1 − 2⁻⁶⁴ — a check against storage and
//! transmission errors, not an authentication), then the magic, version and tag, then
//! every value with the checks the scheme's constructor makes and the invariants of its
//! state (a crafted checkpoint with a valid checksum is refused as well), and leaves the
//! target unchanged on any error.
//!
//! # Example
//! ```
//! use coagula_core::checkpoint::Checkpoint;
//! use coagula_core::kernel::Coagulation;
//! use coagula_core::scheme::{Scheme, lowrank::LowRank};
//! let k = Coagulation::brownian();
//! let mut a = LowRank::<_, 2>::monodisperse(k, 1000).unwrap();
//! let mut rng = rand_pcg::Pcg64Mcg::new(1);
//! a.advance_to(0.5, &mut rng).unwrap();
//! let mut buf = vec![0u8; a.checkpoint_len()];
//! a.save_to(&mut buf).unwrap();
//! let mut b = LowRank::<_, 2>::monodisperse(k, 1000).unwrap();
//! b.restore_from(&buf).unwrap();
//! assert_eq!(a.counts(), b.counts());
//! ```

use crate::error::{Error, Result};
use alloc::vec::Vec;

const MAGIC: u64 = u64::from_le_bytes(*b"COAGCKPT");
const VERSION: u64 = 3;

/// Appends little-endian fields to a caller buffer, counting what would not fit.
#[derive(Debug)]
pub struct Writer<'a> {
    buf: &'a mut [u8],
    needed: usize,
}

impl<'a> Writer<'a> {
    /// A writer into `buf` (may be empty to only measure).
    pub fn new(buf: &'a mut [u8]) -> Self {
        Writer { buf, needed: 0 }
    }

    /// Bytes the fields written so far need.
    pub fn needed(&self) -> usize {
        self.needed
    }

    fn bytes(&mut self, b: &[u8]) {
        let end = self.needed + b.len();
        if end <= self.buf.len() {
            self.buf[self.needed..end].copy_from_slice(b);
        }
        self.needed = end;
    }

    /// A `u64`.
    pub fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }

    /// An `f64` (bit pattern).
    pub fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }

    /// A length-prefixed slice of `u64`.
    pub fn u64s(&mut self, v: &[u64]) {
        self.u64(v.len() as u64);
        for &x in v {
            self.u64(x);
        }
    }

    /// A length-prefixed slice of `f64`.
    pub fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        for &x in v {
            self.f64(x);
        }
    }

    /// Appends the checksum of everything written so far (the last field of a
    /// checkpoint; only counted when the buffer is too small).
    pub fn seal(&mut self) {
        let sum = if self.needed <= self.buf.len() {
            checksum(&self.buf[..self.needed])
        } else {
            0
        };
        self.u64(sum);
    }

    /// Fails with [`Error::BufferLength`] if the buffer was too small.
    pub fn finish(&self) -> Result<usize> {
        if self.needed > self.buf.len() {
            Err(Error::BufferLength {
                name: "checkpoint buffer",
                expected: self.needed,
                got: self.buf.len(),
            })
        } else {
            Ok(self.needed)
        }
    }
}

/// Reads the fields of a checkpoint back.
#[derive(Clone, Debug)]
pub struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

fn bad(what: &'static str) -> Error {
    Error::Checkpoint { what }
}

impl<'a> Reader<'a> {
    /// A reader over `buf`.
    pub fn new(buf: &'a [u8]) -> Self {
        Reader { buf, pos: 0 }
    }

    /// A `u64`.
    pub fn u64(&mut self) -> Result<u64> {
        let end = self.pos + 8;
        let b = self.buf.get(self.pos..end).ok_or(bad("truncated"))?;
        self.pos = end;
        Ok(u64::from_le_bytes(
            b.try_into().map_err(|_| bad("truncated"))?,
        ))
    }

    /// An `f64`.
    pub fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_bits(self.u64()?))
    }

    /// A length (checked against the remaining bytes, `elem` bytes per element).
    fn len(&mut self, elem: usize) -> Result<usize> {
        let n = self.u64()?;
        let left = (self.buf.len() - self.pos) / elem;
        if n > left as u64 {
            return Err(bad("length beyond the buffer"));
        }
        Ok(n as usize)
    }

    /// A length-prefixed `Vec<u64>`.
    pub fn u64s(&mut self) -> Result<Vec<u64>> {
        let n = self.len(8)?;
        (0..n).map(|_| self.u64()).collect()
    }

    /// A length-prefixed `Vec<f64>`.
    pub fn f64s(&mut self) -> Result<Vec<f64>> {
        let n = self.len(8)?;
        (0..n).map(|_| self.f64()).collect()
    }

    /// A length-prefixed run of `f64` read into `out`, whose length it must have (no
    /// allocation).
    pub fn f64s_into(&mut self, out: &mut [f64]) -> Result<()> {
        let n = self.len(8)?;
        if n != out.len() {
            return Err(bad("different number of values"));
        }
        for o in out {
            *o = self.f64()?;
        }
        Ok(())
    }

    /// A `usize` stored as `u64`.
    pub fn usize(&mut self) -> Result<usize> {
        usize::try_from(self.u64()?).map_err(|_| bad("size does not fit"))
    }

    /// Fails unless every byte was consumed.
    pub fn finish(&self) -> Result<()> {
        if self.pos == self.buf.len() {
            Ok(())
        } else {
            Err(bad("trailing bytes"))
        }
    }
}

/// The checksum of a checkpoint: each 8-byte word (the last one zero-padded) is mixed
/// in by a bijection of the running state, so a change in any single word always
/// changes the result; the length and a final avalanche (splitmix64's) follow.
pub fn checksum(bytes: &[u8]) -> u64 {
    const K: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut h: u64 = 0x436f_6167_756c_6121; // "Coagula!"
    for chunk in bytes.chunks(8) {
        let mut w = [0u8; 8];
        w[..chunk.len()].copy_from_slice(chunk);
        h = (h ^ u64::from_le_bytes(w)).wrapping_mul(K);
        h ^= h >> 29;
    }
    h ^= bytes.len() as u64;
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^ (h >> 31)
}

/// The body of a sealed checkpoint (everything before its checksum), or
/// [`Error::Checkpoint`] when the checksum does not match (a corrupted or truncated
/// checkpoint).
pub fn unseal(buf: &[u8]) -> Result<&[u8]> {
    let Some(at) = buf.len().checked_sub(8) else {
        return Err(bad("truncated"));
    };
    let (body, sum) = buf.split_at(at);
    let sum = u64::from_le_bytes(sum.try_into().map_err(|_| bad("truncated"))?);
    if checksum(body) != sum {
        return Err(bad(
            "checksum mismatch (the checkpoint is corrupted, truncated or not a checkpoint)",
        ));
    }
    Ok(body)
}

/// Writes the header of a checkpoint of the scheme `tag`.
pub(crate) fn header(w: &mut Writer, tag: u64) {
    w.u64(MAGIC);
    w.u64(VERSION);
    w.u64(tag);
}

/// Checks the header.
pub(crate) fn check_header(r: &mut Reader, tag: u64) -> Result<()> {
    if r.u64()? != MAGIC {
        return Err(bad("not a coagula checkpoint"));
    }
    if r.u64()? != VERSION {
        return Err(bad("unsupported checkpoint version"));
    }
    if r.u64()? != tag {
        return Err(bad("checkpoint of a different scheme"));
    }
    Ok(())
}

/// A scheme whose state can be saved and restored.
pub trait Checkpoint {
    /// Writes the full state.
    fn save(&self, w: &mut Writer);

    /// Replaces the state by the one in `r`, which must hold nothing after it; on error
    /// the state is unchanged.
    fn restore(&mut self, r: &mut Reader) -> Result<()>;

    /// Bytes a checkpoint needs now.
    fn checkpoint_len(&self) -> usize {
        let mut w = Writer::new(&mut []);
        self.save(&mut w);
        w.seal();
        w.needed()
    }

    /// Saves into `buf` (the state, then its checksum), returning the bytes written;
    /// errors if `buf` is too small (nothing is promised about `buf` then).
    fn save_to(&self, buf: &mut [u8]) -> Result<usize> {
        let mut w = Writer::new(buf);
        self.save(&mut w);
        w.seal();
        w.finish()
    }

    /// Restores from a buffer written by [`save_to`](Self::save_to): the checksum is
    /// verified before anything is read.
    fn restore_from(&mut self, buf: &[u8]) -> Result<()> {
        let mut r = Reader::new(unseal(buf)?);
        self.restore(&mut r)
    }
}

/// FNV-1a over 64-bit words: a fingerprint of configuration that is not stored but must
/// match on restore (e.g. the scrambling of a point sequence, a kernel's parameters).
pub fn fingerprint(words: impl IntoIterator<Item = u64>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for w in words {
        for b in w.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}
