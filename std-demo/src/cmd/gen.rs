//! `vcx gen grid|hall|mixed N --seed S [-o FILE]`: write a generated test scene.

use std::path::PathBuf;

use vcx_demo::generate::{self, SceneKind, MAX_OBJECTS};

use super::{write_stdout, Failure};

/// Which scene to generate.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum Kind {
    /// Fig. 20: N random triangles, one per cell of a square grid.
    Grid,
    /// Fig. 21: a hall of mirrors (four mirror walls) with N opaque or mirror pillars.
    Hall,
    /// Fig. 22: N objects: opaque, mirrors, refractive (eta 1.33-1.6) and a few screens.
    Mixed,
}

/// Arguments of `vcx gen`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The kind of scene.
    #[arg(value_enum)]
    pub kind: Kind,
    /// Number of objects (pillars for `hall`).
    #[arg(value_parser = clap::value_parser!(u32).range(0..=i64::from(MAX_OBJECTS)))]
    pub n: u32,
    /// Seed of the random generator: the same seed gives the same scene.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write the scene to this file instead of stdout.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Generates the scene and writes it.
pub fn run(args: &Args) -> Result<(), Failure> {
    let kind = match args.kind {
        Kind::Grid => SceneKind::Grid,
        Kind::Hall => SceneKind::Hall,
        Kind::Mixed => SceneKind::Mixed,
    };
    let file = generate::generate(kind, args.n, args.seed).map_err(|e| match e {
        generate::GenerateError::TooMany { .. } => Failure::bad_input(e.to_string()),
        _ => Failure {
            message: e.to_string(),
            code: super::EXIT_PANIC,
        },
    })?;
    let text = file.to_json();
    match &args.output {
        None => write_stdout(&text),
        Some(path) => std::fs::write(path, text)
            .map_err(|e| Failure::bad_input(format!("cannot write {}: {e}", path.display()))),
    }
}
