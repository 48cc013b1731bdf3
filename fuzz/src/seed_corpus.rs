//! Writes the seed corpora: `seed_corpus DIR` for `checkpoint_restore`
//! ([`coagula_fuzz::seeds`]), `seed_corpus DIR langevin` for `langevin_restore`
//! ([`coagula_fuzz::langevin_seeds`]).

fn main() {
    let dir = std::env::args().nth(1).expect("usage: seed_corpus DIR [langevin]");
    let langevin = std::env::args().nth(2).is_some_and(|a| a == "langevin");
    std::fs::create_dir_all(&dir).unwrap();
    let seeds = if langevin {
        coagula_fuzz::langevin_seeds()
    } else {
        coagula_fuzz::seeds()
    };
    for (name, data) in seeds {
        std::fs::write(format!("{dir}/{name}"), data).unwrap();
    }
}
