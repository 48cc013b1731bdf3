//! `coagula qmc`: t-values of the digital sequences (rank test on their matrices).

/// `coagula qmc`: the t-values of the digital sequences.
pub fn command(dims: usize, m: u32) -> Result<(), coagula_core::Error> {
    use coagula_core::qmc::{Niederreiter2, Sobol, net};
    let nied = Niederreiter2::<u64>::new(dims)?;
    let sobol = Sobol::<u64>::new(dims)?;
    println!("t-values by the rank test, blocks of 2^m for m <= {m}");
    println!("{:>6} {:>12} {:>8}", "coord", "Nied. poly", "Nied. t");
    for j in 0..dims {
        println!(
            "{:>6} {:>#12b} {:>8}",
            j + 1,
            nied.polynomial(j),
            net::t_value_sequence(&nied, &[j], m)
        );
    }
    for s in 1..=dims.min(6) {
        let c: Vec<usize> = (0..s).collect();
        println!(
            "first {s} dims: Niederreiter t = {} (theory {}), Sobol' t = {}",
            net::t_value_sequence(&nied, &c, m),
            Niederreiter2::<u64>::new(s)?.t_theory(),
            net::t_value_sequence(&sobol, &c, m)
        );
    }
    Ok(())
}
