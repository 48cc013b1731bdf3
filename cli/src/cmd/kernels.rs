//! `coagula kernels`: the built-in kernels and how tight their bounds are.

use coagula_core::kernel::builtin::BUILTINS;
use coagula_core::kernel::{Coagulation, check_low_rank, check_majorant, log_grid};

/// `coagula kernels`: core's table of built-in kernels, and the bounds of the
/// coagulation kernels checked on a log grid.
pub fn command(min: f64, max: f64, points: usize) -> Result<(), String> {
    if max <= min {
        return Err(format!("--max {max} must be above --min {min}"));
    }
    println!("built-in kernels (coag_kernel_new, [kernel] kind, coagula.Kernel):");
    for b in BUILTINS {
        let params: Vec<String> = b
            .params
            .iter()
            .map(|p| match p.default {
                Some(d) => format!("{} = {d}", p.name),
                None => format!("{} (required)", p.name),
            })
            .collect();
        println!(
            "  {:<26} {:?}: {} [{}]",
            b.name,
            b.family,
            b.formula,
            params.join(", ")
        );
    }
    println!();
    bounds(min, max, points).map_err(|e| e.to_string())
}

fn bounds(min: f64, max: f64, points: usize) -> Result<(), coagula_core::Error> {
    let grid = log_grid(min, max, points);
    let narrow = if min >= 1.0 { 1.0 } else { 0.0 };
    let all = [
        ("constant", Coagulation::constant(1.0)?),
        ("additive", Coagulation::additive()),
        ("multiplicative", Coagulation::multiplicative()),
        ("product a=0.8", Coagulation::product(0.8)?),
        ("homogeneous g=1.5", Coagulation::homogeneous(1.5)?),
        ("free-molecular", Coagulation::free_molecular()),
        ("brownian", Coagulation::brownian()),
    ];
    println!("grid {min:e}..{max:e}, {points} points; bounds for sizes >= {narrow}");
    println!(
        "{:<18} {:>9} {:>11} {:>11} {:>9} {:>11} {:>11}",
        "kernel", "maj.viol", "maj.max", "maj.worst", "lr.viol", "lr.max", "lr.worst"
    );
    println!(
        "(max = largest K/bound, 1 when tight; worst = smallest K/bound, the worst acceptance)"
    );
    for (name, k) in all {
        let k = k.with_min_size(narrow)?;
        let m = check_majorant(&k, &grid)?;
        let l = check_low_rank(&k, &grid)?;
        println!(
            "{name:<18} {:>9} {:>11.6} {:>11.3e} {:>9} {:>11.6} {:>11.3e}",
            m.violations + m.monotonicity_violations,
            m.max_ratio,
            m.worst_acceptance,
            l.violations,
            l.max_ratio,
            l.worst_acceptance
        );
    }
    Ok(())
}
