//! The `mirage` command line: parses the arguments and runs the command
//! ([`mirage::cli`]).

use clap::Parser;
use mirage::cli::Cli;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return mirage::cli::report_parse_error(&e),
    };
    cli.set_threads();
    cli.handle_interrupts();
    match cli.run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
