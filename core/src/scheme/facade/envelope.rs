//! The one checkpoint envelope of every front end (C, Python, the CLI) and family
//! (populations and Langevin batches): what the sim is and was built with, and its
//! state, sealed with a checksum.
//!
//! ```text
//! magic "COAGENV1" | version | scheme tag
//! records: count, then per record its length and words (settings as built, as they stand)
//! physics fingerprint
//! stream: 0, or 1 and the front end's generator (4 words)
//! the scheme's own checkpoint (its header, its fields)
//! checksum of all of the above
//! ```
//!
//! A restore checks, before anything changes: the checksum, the magic and version, the
//! scheme, the records (settings that must match, see [`Key::must_match`](super::Key)),
//! the physics; then the scheme restores its state with the checks its constructor
//! makes. On any error the sim is as it was.

use super::options::{KEYS, Options};
use crate::checkpoint::{Reader, Writer, unseal};
use crate::error::{Error, Result};
use alloc::vec::Vec;

/// The first word of an envelope.
pub const ENVELOPE_MAGIC: u64 = u64::from_le_bytes(*b"COAGENV1");
/// Its format.
const VERSION: u64 = 1;

fn bad(what: &'static str) -> Error {
    Error::Checkpoint { what }
}

/// Writes an envelope (see the module docs) and seals it.
pub fn write_envelope(
    w: &mut Writer,
    tag: u64,
    records: &[&[u64]],
    fingerprint: u64,
    stream: Option<[u64; 4]>,
    state: impl FnOnce(&mut Writer),
) {
    w.u64(ENVELOPE_MAGIC);
    w.u64(VERSION);
    w.u64(tag);
    w.u64(records.len() as u64);
    for r in records {
        w.u64(r.len() as u64);
        for &x in r.iter() {
            w.u64(x);
        }
    }
    w.u64(fingerprint);
    match stream {
        None => w.u64(0),
        Some(p) => {
            w.u64(1);
            for x in p {
                w.u64(x);
            }
        }
    }
    state(w);
    w.seal();
}

/// The front end's stream an envelope carries, read without restoring anything (a
/// front end checks it before it restores; the checksum and the magic are checked).
pub fn peek_stream(buf: &[u8]) -> Result<Option<[u64; 4]>> {
    let mut out = None;
    let r = read_envelope_any(buf, |stream, _| {
        out = stream;
        Ok(())
    });
    r.map(|()| out)
}

fn read_envelope_any(
    buf: &[u8],
    at_stream: impl FnOnce(Option<[u64; 4]>, &mut Reader) -> Result<()>,
) -> Result<()> {
    let body = unseal(buf)?;
    let mut r = Reader::new(body);
    if r.u64()? != ENVELOPE_MAGIC {
        return Err(bad(
            "not a coagula checkpoint envelope (or one of an older format)",
        ));
    }
    if r.u64()? != VERSION {
        return Err(bad("unsupported envelope version"));
    }
    let _tag = r.u64()?;
    let n = r.u64()?;
    if n > 4 {
        return Err(bad("too many records"));
    }
    for _ in 0..n {
        let len = r.u64()?;
        if len > 64 {
            return Err(bad("record too long"));
        }
        for _ in 0..len {
            r.u64()?;
        }
    }
    let _print = r.u64()?;
    let stream = match r.u64()? {
        0 => None,
        1 => Some([r.u64()?, r.u64()?, r.u64()?, r.u64()?]),
        _ => return Err(bad("invalid stream flag")),
    };
    at_stream(stream, &mut r)
}

/// Reads an envelope of scheme `tag` under physics `fingerprint` from `buf` (sealed):
/// `records` checks the records (and keeps what it needs), then `state` restores the
/// state from the reader with the envelope's stream; both run only when everything
/// before them checked out. The state must use up the envelope.
pub fn read_envelope(
    buf: &[u8],
    tag: u64,
    fingerprint: u64,
    records: impl FnOnce(&[Vec<u64>]) -> Result<()>,
    state: impl FnOnce(Option<[u64; 4]>, &mut Reader) -> Result<()>,
) -> Result<()> {
    let body = unseal(buf)?;
    let mut r = Reader::new(body);
    if r.u64()? != ENVELOPE_MAGIC {
        return Err(bad(
            "not a coagula checkpoint envelope (or one of an older format)",
        ));
    }
    if r.u64()? != VERSION {
        return Err(bad("unsupported envelope version"));
    }
    if r.u64()? != tag {
        return Err(bad("checkpoint of another scheme"));
    }
    let n = r.u64()?;
    if n > 4 {
        return Err(bad("too many records"));
    }
    let mut recs = Vec::new();
    for _ in 0..n {
        let len = r.u64()?;
        if len > 64 {
            return Err(bad("record too long"));
        }
        let mut words = Vec::new();
        for _ in 0..len {
            words.push(r.u64()?);
        }
        recs.push(words);
    }
    records(&recs)?;
    if r.u64()? != fingerprint {
        return Err(bad(
            "written under another kernel, fragmentation kernel or model (kind, parameters or declared bounds)",
        ));
    }
    let stream = match r.u64()? {
        0 => None,
        1 => Some([r.u64()?, r.u64()?, r.u64()?, r.u64()?]),
        _ => return Err(bad("invalid stream flag")),
    };
    state(stream, &mut r)
}

/// Checks a population's two settings records against the sim's own (`built`, and
/// `now` as it stands) and returns the settings the restored sim runs with: the
/// records', but this sim's memory budget and capacity (its state was checked against
/// them).
pub(crate) fn check_records(
    built: &Options,
    now: &Options,
    words: &[Vec<u64>],
) -> Result<(Options, Options)> {
    let [b, c] = words else {
        return Err(bad("expected two settings records"));
    };
    let (Ok(b), Ok(c)) = (<[u64; 15]>::try_from(&b[..]), <[u64; 15]>::try_from(&c[..])) else {
        return Err(bad("a settings record of the wrong length"));
    };
    let ours = built.words();
    for (i, k) in KEYS.iter().enumerate() {
        if k.must_match && b[i] != ours[i] {
            return Err(Error::CheckpointOption { key: k.name });
        }
        // what no call changes after the build must be the same in both records
        if k.must_match && k.name != "dt" && c[i] != b[i] {
            return Err(bad(
                "its two settings records disagree on a setting no call changes",
            ));
        }
    }
    let keep = |o: Options, mine: &Options| o.with_budget_of(mine);
    Ok((
        keep(built.with_words(&b)?, built),
        keep(now.with_words(&c)?, now),
    ))
}
