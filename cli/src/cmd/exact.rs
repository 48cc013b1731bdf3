//! `coagula exact`: an exact solution's moments, gel mass and concentrations.

use coagula_core::exact::Exact;

/// `coagula exact`.
pub fn command(
    solution: crate::args::Solution,
    coefficient: f64,
    xs: &[f64],
    times: &[f64],
    kmax: u64,
) -> Result<(), String> {
    if times.len() > 100_000 || xs.len() > 100_000 {
        return Err("at most 100000 times and 100000 sizes".into());
    }
    print(solution, coefficient, xs, times, kmax).map_err(|e| e.to_string())
}

fn print(
    solution: crate::args::Solution,
    coefficient: f64,
    xs: &[f64],
    times: &[f64],
    kmax: u64,
) -> Result<(), coagula_core::Error> {
    let e = match solution {
        crate::args::Solution::Constant => Exact::constant(1.0)?,
        crate::args::Solution::Additive => Exact::additive(),
        crate::args::Solution::Multiplicative => Exact::multiplicative(),
        crate::args::Solution::MarcusLushnikov => Exact::marcus_lushnikov(),
        crate::args::Solution::CoagFrag => Exact::coagulation_fragmentation(),
        crate::args::Solution::ConstantExponential => Exact::constant_exponential(1.0)?,
        crate::args::Solution::Golovin => Exact::additive_exponential(),
    };
    let e = if coefficient != 1.0 {
        e.with_coefficient(coefficient)?
    } else {
        e
    };
    let mut header = String::from("t,M0,M1,M2,M3,gel_mass");
    if e.is_continuous() {
        for x in xs {
            header.push_str(&format!(",c({x})"));
        }
    } else {
        for k in 1..=kmax {
            header.push_str(&format!(",n{k}"));
        }
    }
    println!("{header}");
    for &t in times {
        let mut line = format!("{t}");
        for m in 0..=3 {
            line.push_str(&format!(",{}", e.moment(m, t)?));
        }
        line.push_str(&format!(",{}", e.gel_mass(t)?));
        if e.is_continuous() {
            for &x in xs {
                line.push_str(&format!(",{}", e.density(x, t)?));
            }
        } else {
            for k in 1..=kmax {
                line.push_str(&format!(",{}", e.number_density(k, t)?));
            }
        }
        println!("{line}");
    }
    Ok(())
}
