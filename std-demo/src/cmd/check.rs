//! `vcx check SCENE.json`: validate a scene file and print one summary line.

use std::path::PathBuf;

use vcx::Material;
use vcx_demo::scene_file::{self, SceneFile, SceneFileError, GRID};

use super::{write_stdout, Failure};

/// Arguments of `vcx check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (JSON).
    pub scene: PathBuf,
}

/// Loads and validates the scene; prints the summary.
pub fn run(args: &Args) -> Result<(), Failure> {
    let file = load(&args.scene)?;
    write_stdout(&format!("{}\n", summary(&args.scene, &file)))
}

/// Loads a scene file; the failure names the file.
pub fn load(path: &std::path::Path) -> Result<SceneFile, Failure> {
    scene_file::load(path).map_err(|e| match e {
        SceneFileError::Io { .. } => Failure::bad_input(e.to_string()),
        _ => Failure::bad_input(format!("{}: {e}", path.display())),
    })
}

/// `PATH: N objects (opaque a, mirror b, refractive c, screen d), V vertices,
/// bbox [x0, y0]..[x1, y1], grid 2^-16` and, if any, how many vertices were rounded.
pub fn summary(path: &std::path::Path, file: &SceneFile) -> String {
    let scene = file.scene.as_ref();
    let mut counts = [0usize; 4];
    let mut bbox: Option<(i32, i32, i32, i32)> = None;
    for object in scene.objects() {
        let k = match object.material {
            Material::Opaque => 0,
            Material::Mirror => 1,
            Material::Refractive { .. } => 2,
            _ => 3,
        };
        counts[k] += 1;
        let (lo, hi) = object.bbox();
        bbox = Some(match bbox {
            None => (lo.x(), lo.y(), hi.x(), hi.y()),
            Some((x0, y0, x1, y1)) => (
                x0.min(lo.x()),
                y0.min(lo.y()),
                x1.max(hi.x()),
                y1.max(hi.y()),
            ),
        });
    }
    let unit = |raw: i32| f64::from(raw) / 65536.0;
    let bbox = match bbox {
        Some((x0, y0, x1, y1)) => format!(
            "bbox [{}, {}]..[{}, {}]",
            unit(x0),
            unit(y0),
            unit(x1),
            unit(y1)
        ),
        None => "bbox empty".to_string(),
    };
    let mut line = format!(
        "{}: {} objects (opaque {}, mirror {}, refractive {}, screen {}), {} vertices, {bbox}, \
         grid {GRID}",
        path.display(),
        scene.len(),
        counts[0],
        counts[1],
        counts[2],
        counts[3],
        scene.vertices().len(),
    );
    let rounded = file.rounded_vertices();
    if rounded > 0 {
        line.push_str(&format!(", {rounded} vertices rounded to the grid"));
    }
    super::one_line(&line)
}
