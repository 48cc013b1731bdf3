//! Writes the seed corpus of `checkpoint_restore`: a checkpoint of every scheme, fresh
//! and advanced, under both modes (as written, and resealed after the mode byte).
//! Usage: `seed_corpus DIR`.

use coagula::*;
use coagula_fuzz::{KINDS, checkpoint, small_sim};

fn main() {
    let dir = std::env::args().nth(1).expect("usage: seed_corpus DIR");
    std::fs::create_dir_all(&dir).unwrap();
    for kind in 0..KINDS {
        unsafe {
            let s = small_sim(kind);
            for (step, t) in [0.0, 0.3, 1.0].into_iter().enumerate() {
                coag_sim_advance_to(s, t, std::ptr::null_mut());
                let ck = checkpoint(s);
                for reseal in 0..2u8 {
                    let mode = (kind as u8) << 1 | reseal;
                    let mut data = vec![mode];
                    data.extend_from_slice(&ck);
                    std::fs::write(format!("{dir}/seed-{kind}-{step}-{reseal}"), data).unwrap();
                }
            }
            coag_sim_free(s);
        }
    }
}
