//! `vcx build SCENE.json [--stats-json]`: build the visibility complex of a scene and report
//! its size.
//!
//! The scene is loaded and validated as by `vcx check` (bad input: exit status 2). The
//! complex is then built with the rotational sweep ([`vcx::partition::build_by_sweep`]) and
//! checked with [`vcx::partition::Complex::validate`]. A failure of either is a bug in vcx,
//! not bad input: `error: SCENE: internal: …` and exit status 3 ([`EXIT_INTERNAL`]).
//!
//! Output, one line on stdout:
//!
//! * by default a summary for people: `SCENE: N objects, B free bitangents (V complex
//!   vertices), F faces, C cylinders; built in T s (rotational sweep, no history)`;
//! * with `--stats-json` exactly one JSON object, keys in this order:
//!   `objects`, `free_bitangents` (undirected free bitangent segments), `complex_vertices`
//!   (directed free bitangents, `2 × free_bitangents`), `faces`, `cylinders`
//!   (`3·objects + 1 + 3·complex_vertices`), `build_seconds` (wall time of the build alone,
//!   not of loading or validation), then `history_nodes`, `history_links`, `history_depth`
//!   — all `null` — and `history`, a string saying why: the sweep builds the canonical
//!   partition without the history DAG; the randomized incremental construction will fill
//!   these.
//!
//! Nothing is written to a file yet: options for the randomized construction (`--seed`)
//! and for the complex file format (`-o`) come with them.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::{json, Value};
use vcx::partition::{build_by_sweep, Complex};
use vcx::SceneRef;

use super::{write_stdout, Failure};

/// Exit status when the complex cannot be built or fails its own checks (a bug in vcx).
pub const EXIT_INTERNAL: u8 = 3;

/// Why the history fields of `--stats-json` are `null`.
pub const HISTORY_NOT_BUILT: &str = "not built: the rotational sweep builds the canonical \
     partition without history; the randomized incremental construction will fill these";

/// Arguments of `vcx build`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (JSON).
    pub scene: PathBuf,
    /// Print the statistics as one JSON object instead of a summary line.
    #[arg(long)]
    pub stats_json: bool,
}

/// A built complex and how long building it took.
pub struct Built {
    /// The complex (validated).
    pub complex: Complex,
    /// Wall time of `build_by_sweep` alone, in seconds.
    pub seconds: f64,
}

/// Builds the complex of a validated scene and checks it; any failure is internal
/// (exit status 3) and names the scene file.
pub fn build_checked(path: &Path, scene: &SceneRef<'_>) -> Result<Built, Failure> {
    let internal = |e: vcx::partition::ComplexError| Failure {
        message: format!("{}: internal: {e}", path.display()),
        code: EXIT_INTERNAL,
    };
    let start = Instant::now();
    let complex = build_by_sweep(scene).map_err(internal)?;
    let seconds = start.elapsed().as_secs_f64();
    complex.validate(scene).map_err(internal)?;
    Ok(Built { complex, seconds })
}

/// Loads the scene, builds and validates the complex, prints the statistics.
pub fn run(args: &Args) -> Result<(), Failure> {
    let file = super::check::load(&args.scene)?;
    let scene = file.scene.as_ref();
    let built = build_checked(&args.scene, &scene)?;
    let text = if args.stats_json {
        let mut line = stats_json(scene.len(), &built).to_string();
        line.push('\n');
        line
    } else {
        format!("{}\n", summary(&args.scene, scene.len(), &built))
    };
    write_stdout(&text)
}

/// The `--stats-json` object.
pub fn stats_json(objects: usize, built: &Built) -> Value {
    let c = &built.complex;
    json!({
        "objects": objects,
        "free_bitangents": c.free_bitangents(),
        "complex_vertices": c.vertices().len(),
        "faces": c.faces(),
        "cylinders": c.cylinders().len(),
        "build_seconds": built.seconds,
        "history_nodes": null,
        "history_links": null,
        "history_depth": null,
        "history": HISTORY_NOT_BUILT,
    })
}

/// The one-line summary for people.
pub fn summary(path: &Path, objects: usize, built: &Built) -> String {
    let c = &built.complex;
    super::one_line(&format!(
        "{}: {objects} objects, {} free bitangents ({} complex vertices), {} faces, \
         {} cylinders; built in {:.3} s (rotational sweep, no history)",
        path.display(),
        c.free_bitangents(),
        c.vertices().len(),
        c.faces(),
        c.cylinders().len(),
        built.seconds,
    ))
}
