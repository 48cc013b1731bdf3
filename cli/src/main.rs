//! `coagula` — command-line interface of the coagula library: one module per
//! subcommand (`cmd`), the scenario format and its checks (`scenario`), the replica
//! runner and the outputs. Numerics are core's: this crate translates.

use clap::Parser;
use std::process::ExitCode;

mod args;
mod cases;
mod cmd;
mod ensemble;
mod examples;
mod output;
mod plans;
mod plot;
mod reproduce;
mod runner;
mod scenario;

fn main() -> ExitCode {
    cmd::exit(cmd::dispatch(args::Cli::parse().command))
}
