//! `coagula reproduce`: a paper's experiment.

use crate::args::Experiment;
use crate::reproduce;

/// Runs the experiment `which`.
pub fn command(
    which: Experiment,
    m_max: u32,
    mc_seeds: u64,
    rqmc: u32,
    plot: Option<&str>,
    figures: &[String],
    quick: bool,
) -> Result<(), String> {
    match which {
        Experiment::Lecot2019 => {
            if quick {
                return Err("--quick: lecot2019 has no quick form (set --m-max instead)".into());
            }
            reproduce::lecot2019::reproduce(m_max, mc_seeds, rqmc, plot)
        }
        Experiment::Eibeck2000 => reproduce::eibeck2000::reproduce(figures, quick, plot),
        Experiment::Maftei2016 => {
            let parts = if figures.iter().any(|f| f == "all") {
                vec!["all".into()]
            } else {
                figures.to_vec()
            };
            reproduce::maftei2016::reproduce(&parts, quick, plot)
        }
    }
}
