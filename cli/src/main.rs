//! `coagula` — command-line interface of the coagula library (its modules are the
//! `coagula_cli` library's: one per subcommand, the scenario format, the runner and
//! the outputs). Numerics are core's: this crate translates.

fn main() -> std::process::ExitCode {
    coagula_cli::main()
}
