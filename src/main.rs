use std::process::ExitCode;

fn main() -> ExitCode {
    match hdi::cli::main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<hdi::cli::Stale>() => ExitCode::from(1),
        Err(e) => {
            // One line: the whole context chain.
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
