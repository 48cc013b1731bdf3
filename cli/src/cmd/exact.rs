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

/// `--x` on a solution over integer sizes (it has n_k, `--kmax`) or `--kmax` on one
/// over real sizes (it has c(x, t), `--x`) would print nothing for it: refused.
fn check_columns(e: &Exact, xs: &[f64], kmax: u64) -> Result<(), coagula_core::Error> {
    let what = if e.is_continuous() && kmax > 0 {
        "--kmax: this solution is over real sizes; ask for c(x, t) with --x"
    } else if !e.is_continuous() && !xs.is_empty() {
        "--x: this solution is over integer sizes; ask for n_k with --kmax"
    } else {
        return Ok(());
    };
    Err(coagula_core::Error::Unsupported { what })
}

fn print(
    solution: crate::args::Solution,
    coefficient: f64,
    xs: &[f64],
    times: &[f64],
    kmax: u64,
) -> Result<(), coagula_core::Error> {
    // the name clap parsed is core's name of the solution
    let name = clap::ValueEnum::to_possible_value(&solution)
        .map(|v| v.get_name().to_string())
        .unwrap_or_default();
    let e = Exact::named(&name)?;
    let e = if coefficient != 1.0 {
        e.with_coefficient(coefficient)?
    } else {
        e
    };
    check_columns(&e, xs, kmax)?;
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
        let mut line = num(t);
        for m in 0..=3 {
            line.push_str(&format!(",{}", num(e.moment(m, t)?)));
        }
        line.push_str(&format!(",{}", num(e.gel_mass(t)?)));
        if e.is_continuous() {
            for &x in xs {
                line.push_str(&format!(",{}", num(e.density(x, t)?)));
            }
        } else {
            for k in 1..=kmax {
                line.push_str(&format!(",{}", num(e.number_density(k, t)?)));
            }
        }
        println!("{line}");
    }
    Ok(())
}

/// The shortest decimal that reads back as `x`, in exponent form outside
/// `[1e-5, 1e16)` (not 300 digits for `1e300`).
fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
