//! `vcx`: the command line of vcx — check and generate scenes, build the complex and
//! locate rays in it (later: view, render, bench, demo).
//!
//! Errors are one line on stderr, `error: ` first, and exit status 2. A complex that
//! cannot be built or fails its own checks is a bug: one line and exit status 3. A panic
//! would be a bug too; the hook below still turns it into one line and exit status 101.

mod cmd;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Exact 2D visibility with the visibility complex (Cho & Forsyth 1999).
#[derive(Debug, Parser)]
#[command(name = "vcx", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Validate a scene file and print a one-line summary.
    Check(cmd::check::Args),
    /// Generate a test scene (the paper's Figs. 20-22) as a scene file.
    Gen(cmd::gen::Args),
    /// Build the visibility complex of a scene and print its statistics.
    Build(cmd::build::Args),
    /// Locate a ray: the objects it sees ahead and behind, and its cylinder.
    Locate(cmd::locate::Args),
}

fn main() -> ExitCode {
    cmd::install_panic_hook();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check(args) => cmd::check::run(&args),
        Command::Gen(args) => cmd::gen::run(&args),
        Command::Build(args) => cmd::build::run(&args),
        Command::Locate(args) => cmd::locate::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => failure.report(),
    }
}
