//! The driver's checkpoint record: a fingerprint of the processes, the pending
//! candidate, the books and the growth grid's origin.

use super::{Driver, GROW, VOID};
use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::process::{Books, Processes};
use alloc::vec::Vec;

/// Words of the checkpoint record: fingerprint, candidate (3), books (9), the growth
/// grid's origin (a record of 13 words, written before it, reads as origin 0).
const RECORD: usize = 14;

/// A checkpoint's process record, read and checked.
pub(crate) struct Record {
    pending: Option<(f64, f64)>,
    books: Books,
    origin: f64,
}

impl Driver {
    /// The checkpoint record: a fingerprint of the processes, the candidate and the
    /// books.
    pub(crate) fn record(&self) -> Vec<u64> {
        let mut words = Vec::new();
        let mut buf = [0u8; 8 * RECORD];
        let mut w = Writer::new(&mut buf);
        w.u64(fingerprint(&self.procs));
        match self.pending {
            Some((at, r)) => {
                w.u64(1);
                w.f64(at);
                w.f64(r);
            }
            None => {
                w.u64(0);
                w.f64(0.0);
                w.f64(0.0);
            }
        }
        self.books.save(&mut w);
        w.f64(self.origin);
        for c in buf.chunks_exact(8) {
            let mut b = [0u8; 8];
            b.copy_from_slice(c);
            words.push(u64::from_le_bytes(b));
        }
        words
    }

    /// The candidate and books of a record written by [`record`](Self::record) for the
    /// same processes (checked; nothing changes here).
    pub(crate) fn read_record(&self, words: &[u64]) -> Result<Record> {
        let bad = |what| Error::Checkpoint { what };
        if words.len() != RECORD && words.len() != RECORD - 1 {
            return Err(bad("a process record of the wrong length"));
        }
        let mut buf = [0u8; 8 * RECORD];
        for (c, w) in buf.chunks_exact_mut(8).zip(words) {
            c.copy_from_slice(&w.to_le_bytes());
        }
        let mut r = Reader::new(&buf);
        if r.u64()? != fingerprint(&self.procs) {
            return Err(bad(
                "written with other processes (source, removal or growth)",
            ));
        }
        let pending = match r.u64()? {
            0 => {
                r.f64()?;
                r.f64()?;
                None
            }
            1 => {
                let (at, b) = (r.f64()?, r.f64()?);
                if !(at.is_finite() || at == f64::INFINITY)
                    || !(b == VOID || b == GROW || (b.is_finite() && b >= 0.0))
                {
                    return Err(bad("a process candidate that is not a time"));
                }
                Some((at, b))
            }
            _ => return Err(bad("invalid process candidate flag")),
        };
        let books = Books::load(&mut r)?;
        let origin = if words.len() == RECORD { r.f64()? } else { 0.0 };
        if !origin.is_finite() {
            return Err(bad("a growth grid origin that is not a time"));
        }
        Ok(Record {
            pending,
            books,
            origin,
        })
    }

    /// Installs what [`read_record`](Self::read_record) returned.
    pub(crate) fn install(&mut self, r: Record) {
        self.pending = r.pending;
        self.books = r.books;
        self.origin = r.origin;
    }
}

/// A fingerprint of the processes' parameters.
fn fingerprint(p: &Processes) -> u64 {
    use crate::initial::Distribution as D;
    let mut words: Vec<u64> = Vec::new();
    if let Some(s) = &p.source {
        words.push(1);
        // (a rate function replaces the constant rate, which then plays no part)
        words.push(if s.rate_function().is_some() {
            0
        } else {
            s.rate().to_bits()
        });
        if !s.schedule().is_empty() {
            words.push(5);
            words.push(crate::checkpoint::fingerprint(
                s.schedule()
                    .iter()
                    .flat_map(|&(t, r)| [t.to_bits(), r.to_bits()]),
            ));
        }
        if let Some(f) = s.rate_function() {
            words.extend([9, f.tag(), f.bound().to_bits()]);
        }
        match s.sizes() {
            D::Monodisperse { size } => words.extend([1, size.to_bits()]),
            D::Exponential { mean } => words.extend([2, mean.to_bits()]),
            D::Lognormal { median, gsd } => words.extend([3, median.to_bits(), gsd.to_bits()]),
            D::Sizes(x) => {
                words.push(4);
                words.push(crate::checkpoint::fingerprint(
                    x.iter().map(|v| v.to_bits()),
                ));
            }
            D::Counts(c) => {
                words.push(5);
                words.push(crate::checkpoint::fingerprint(c.iter().copied()));
            }
        }
    }
    for (tag, q) in [(2, &p.removal), (3, &p.growth)] {
        if let Some(q) = q {
            words.extend([tag, q.coefficient.to_bits(), q.exponent.to_bits()]);
        }
    }
    // a host's function is known by its tag and bound
    for (tag, q) in [(6, &p.user_removal), (7, &p.user_growth)] {
        if let Some(q) = q {
            words.extend([tag, q.tag(), q.bound().to_bits()]);
        }
    }
    if let Some(h) = p.growth_step {
        words.extend([8, h.to_bits()]);
    }
    crate::checkpoint::fingerprint(words)
}
