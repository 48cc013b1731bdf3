//! The library behind the `coagula` command: the scenario format and its checks
//! (`scenario`), the plans a command runs (`plans`), the replica runner and the
//! ensembles over processes (`runner`, `ensemble`), the outputs (`output`, `plot`) and
//! one module per subcommand (`cmd`). The binary and the Python package both call it,
//! so `coagula.run` in Python runs what `coagula run` runs, bit for bit. Numerics are
//! core's: this crate translates.

#[cfg(feature = "app")]
pub mod args;
#[cfg(feature = "app")]
pub mod cases;
#[cfg(feature = "app")]
pub mod cmd;
pub mod ensemble;
pub mod examples;
pub mod output;
pub mod plans;
#[cfg(feature = "app")]
pub mod plot;
#[cfg(feature = "app")]
pub mod reproduce;
pub mod runner;
pub mod scenario;

/// The `coagula` command: parses the command line and runs the subcommand.
#[cfg(feature = "app")]
pub fn main() -> std::process::ExitCode {
    use clap::Parser;
    cmd::exit(cmd::dispatch(args::Cli::parse().command))
}
