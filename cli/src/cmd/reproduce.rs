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
            let all = figures.iter().any(|f| f == "all");
            if let Some(bad) = figures
                .iter()
                .find(|f| !matches!(f.as_str(), "all" | "grid" | "dt-ladder"))
            {
                return Err(format!(
                    "--figures {bad}: lecot2019 has the parts grid (Figures 1-2) and dt-ladder"
                ));
            }
            if all || figures.iter().any(|f| f == "grid") {
                reproduce::lecot2019::reproduce(m_max, mc_seeds, rqmc, plot)?;
            }
            if all || figures.iter().any(|f| f == "dt-ladder") {
                use reproduce::lecot2019_dt::{Case, ladder, print};
                let case = Case {
                    m: 14,
                    t_end: 10.0,
                    dts: vec![0.02, 0.01, 0.005, 0.0025],
                    reps: 48,
                };
                print(&case, &ladder(&case)?);
            }
            Ok(())
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
