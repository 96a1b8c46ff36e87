//! `vcx check SCENE.json`: validate a scene file and print one summary line. A binary
//! complex file (`.vcx`) is decoded and validated, scene and complex.

use std::path::PathBuf;

use vcx::Material;
use vcx_demo::scene_file::{SceneFile, GRID};

use super::{write_stdout, Failure};

/// Arguments of `vcx check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (JSON, or a binary complex file `.vcx`).
    pub scene: PathBuf,
}

/// Loads and validates the scene; prints the summary.
pub fn run(args: &Args) -> Result<(), Failure> {
    let input = crate::input::load(&args.scene)?;
    let mut line = summary(&args.scene, &input.file);
    if let Some(s) = &input.stored {
        line.push_str(&format!(
            "; complex file: {} bytes, {} complex vertices, {} cylinders (validated)",
            s.bytes, s.header.complex_vertices, s.header.cylinders
        ));
    }
    write_stdout(&format!("{line}\n"))
}

/// Loads a scene file — JSON, or the scene of a binary complex file (`.vcx`, see
/// [`crate::input`]); the failure names the file.
pub fn load(path: &std::path::Path) -> Result<SceneFile, Failure> {
    crate::input::load(path).map(|input| input.file)
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
