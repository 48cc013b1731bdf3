//! Writes the seed corpus of `checkpoint_restore` ([`coagula_fuzz::seeds`]).
//! Usage: `seed_corpus DIR`.

fn main() {
    let dir = std::env::args().nth(1).expect("usage: seed_corpus DIR");
    std::fs::create_dir_all(&dir).unwrap();
    for (name, data) in coagula_fuzz::seeds() {
        std::fs::write(format!("{dir}/{name}"), data).unwrap();
    }
}
