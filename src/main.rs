//! `hdi`: the command line over the library (src/cli/).

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    match cli::main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<cli::Stale>() || e.is::<cli::Differs>() || e.is::<cli::Damaged>() => {
            ExitCode::from(1)
        }
        Err(e) => {
            // One line: the whole context chain.
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
