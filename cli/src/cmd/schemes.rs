//! `coagula schemes`: core's registry — every scheme with its capabilities and the
//! options it takes (what `[scheme]` in a scenario, `coag_sim_new_*` and
//! `coagula.Simulation` accept).

use coagula_core::scheme::facade::{GENERAL, KEYS};
use coagula_core::scheme::registry::{self, SCHEMES};

/// Lists the schemes, or describes the one named (with its options).
pub fn command(name: Option<&str>) -> Result<(), String> {
    match name {
        None => {
            println!("schemes of the registry (coagula schemes NAME for one):");
            for s in SCHEMES {
                println!("  {:<22} {}", s.name, s.summary);
            }
            Ok(())
        }
        Some(n) => {
            let s = registry::find(n).map_err(|e| format!("{n:?}: {e}"))?;
            println!("{}: {}", s.name, s.summary);
            println!("paper: {}", s.paper);
            println!(
                "model: {:?}; initial states: {:?}; sizes are samples of: {:?}",
                s.model, s.inits, s.sizes
            );
            println!(
                "fragmentation: {}; memory: {:?}; law: {:?}",
                s.fragmentation, s.memory, s.law
            );
            if !s.observables.is_empty() {
                println!("named observables: {}", s.observables.join(", "));
            }
            println!("options:");
            for k in KEYS
                .iter()
                .filter(|k| s.options.contains(&k.name) || GENERAL.contains(&k.name))
            {
                println!("  {:<14} (default {}) {}", k.name, k.default, k.doc);
            }
            Ok(())
        }
    }
}
