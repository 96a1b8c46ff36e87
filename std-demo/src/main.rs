//! `vcx`: the command line of vcx — check and generate scenes, build the complex and
//! locate rays in it, views from points (later: render, bench, demo).
//!
//! Errors are one line on stderr, `error: ` first, and exit status 2. A complex that
//! cannot be built or fails its own checks is a bug: one line and exit status 3. A panic
//! would be a bug too; the hook below still turns it into one line and exit status 101.

mod cmd;
mod input;

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
    /// Print the header and the size of each part of a binary complex file (.vcx).
    Inspect(cmd::inspect::Args),
    /// Locate a ray: the objects it sees ahead and behind, and its cylinder.
    Locate(cmd::locate::Args),
    /// The view from a point: the exact angular intervals of what it sees all around.
    View(cmd::view::Args),
    /// Render the extruded-column view (the paper's Fig. 20) to a PNG, exactly anti-aliased.
    Render(cmd::render::Args),
    /// Walk a scene in the terminal: the view, the map and the complex in dual space.
    Demo(cmd::demo::Args),
    /// Measure construction and walking (see BENCHMARKS.md).
    #[command(subcommand)]
    Bench(cmd::bench::Bench),
}

fn main() -> ExitCode {
    cmd::install_panic_hook();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check(args) => cmd::check::run(&args),
        Command::Gen(args) => cmd::gen::run(&args),
        Command::Build(args) => cmd::build::run(&args),
        Command::Inspect(args) => cmd::inspect::run(&args),
        Command::Locate(args) => cmd::locate::run(&args),
        Command::Demo(args) => cmd::demo::run(&args),
        Command::View(args) => cmd::view::run(&args),
        Command::Render(args) => cmd::render::run(&args),
        Command::Bench(bench) => cmd::bench::run(&bench),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => failure.report(),
    }
}
