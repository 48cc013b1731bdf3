//! `coagula-mpi` — the `coagula` command line with MPI's world of processes:
//! `mpirun -n P coagula-mpi run SCENARIO ...` shares the replicas' blocks out over the
//! P ranks and prints the bits of a one-process run (docs/design/ensembles.md). Every
//! subcommand is the library's; this crate only opens MPI.

use coagula_cli::ensemble::{self, World};
use mpi::topology::SimpleCommunicator;
use mpi::traits::{Communicator, Destination, Source};

/// The processes `mpirun` started (a singleton when started without it).
struct Mpi {
    _universe: mpi::environment::Universe,
    world: SimpleCommunicator,
}

/// Initialises MPI (once per process). With more than one process a panic ends the
/// whole job (the other ranks would wait for this one forever).
fn open() -> Result<Box<dyn World>, String> {
    let universe = mpi::initialize().ok_or("MPI was initialised already")?;
    let world = universe.world();
    if world.size() < 1 {
        return Err("MPI world of no process".into());
    }
    if world.size() > 1 {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            previous(info);
            SimpleCommunicator::world().abort(101);
        }));
    }
    Ok(Box::new(Mpi {
        _universe: universe,
        world,
    }))
}

impl World for Mpi {
    fn rank(&self) -> usize {
        self.world.rank() as usize
    }
    fn size(&self) -> usize {
        self.world.size() as usize
    }
    fn gather(&self, mine: Vec<u64>) -> Option<Vec<Vec<u64>>> {
        if self.rank() == 0 {
            let mut all = vec![mine];
            for r in 1..self.world.size() {
                let (words, _) = self.world.process_at_rank(r).receive_vec::<u64>();
                all.push(words);
            }
            Some(all)
        } else {
            self.world.process_at_rank(0).send(&mine[..]);
            None
        }
    }
    fn fatal(&self, e: String) -> String {
        if self.world.size() > 1 {
            eprintln!("error (rank {}): {e}", self.rank());
            self.world.abort(1);
        }
        e
    }
}

fn main() -> std::process::ExitCode {
    if let Err(e) = ensemble::set_opener(open) {
        eprintln!("error: {e}");
        return std::process::ExitCode::FAILURE;
    }
    coagula_cli::main()
}
