//! The `hmdist` command: argument parsing, progress bars and files. The work is in the library.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("hmdist: error: {err}");
            ExitCode::from(2)
        }
    }
}
