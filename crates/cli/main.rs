//! The `iasm` binary: parses the command line and reports the outcome as an exit status
//! (0 success, 1 a threshold failed, 2 an error).

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = iasm::args::Cli::parse();
    match iasm::run(&cli) {
        Ok(iasm::Outcome::Success) => ExitCode::SUCCESS,
        Ok(iasm::Outcome::ThresholdFailed) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
