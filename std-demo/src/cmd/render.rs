//! `vcx render SCENE --at X,Y --heading DEG --fov DEG [--width 800 --height 800]
//! [--depth D] -o frame.png`: the paper's extruded-column view (Fig. 20) as a PNG.
//!
//! The view (depth 0: over the scene without its screens, as `vcx view`) or the ray tree
//! (depth D: over the whole scene) is turned into exact per-column coverage
//! ([`vcx::render::coverage`]); every piece of a column is drawn as a vertical band (a wall
//! of constant height extruded from the floor plan, its apparent height from the
//! perpendicular distance of the first hit along the piece's middle ray) over the sky and
//! the floor, and the column's colour at each row is the coverage-weighted sum of its
//! pieces: anti-aliased exactly across the columns, and by the covered share of a pixel
//! at the top and the bottom of a band.
//!
//! Colours, by the last object of the branch (what the ray finally sees):
//! * opaque: [`PALETTE`]`[id % 8]`;
//! * mirror or refractive object at the end of the depth: [`MIRROR`] or [`GLASS`];
//! * a ray that escapes after a mirror or a refractive object: the sky colour;
//!
//! multiplied by a brightness `(0.35 + 0.65·facing) / (1 + length / extent)` (facing: how
//! squarely the last stage meets its edge; length: the unfolded distance; extent: the
//! scene's size) and by 0.85 per bounce. Columns seeing nothing show the sky above the
//! horizon and the floor below. Column 0 is the left of the image; the heading is at the
//! centre; columns are equally spaced on the image line (perspective).

use std::io::BufWriter;
use std::path::PathBuf;

use vcx::geom::sos::Angle;
use vcx::partition::point_in_scene;
use vcx::render::{coverage, Camera, Hits, Interval, Piece};
use vcx::walk::{frame_tree, view};
use vcx::{Material, ObjectId, SceneRef, SubScene};
use vcx_demo::SceneFile;

use super::build::{build_checked, EXIT_INTERNAL};
use super::locate::{in_object, parse_pair, query_point};
use super::Failure;

/// Arguments of `vcx render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene: a scene file (JSON) or a built complex (`.vcx`).
    pub scene: PathBuf,
    /// The viewpoint, `X,Y` in scene units.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub at: String,
    /// Viewing direction, degrees counter-clockwise from +x.
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        default_value_t = 90.0
    )]
    pub heading: f64,
    /// Horizontal field of view in degrees, above 0 and at most 179.
    #[arg(long, value_name = "DEG", default_value_t = 90.0)]
    pub fov: f64,
    /// Image width in pixels (one column per pixel).
    #[arg(long, default_value_t = 800)]
    pub width: usize,
    /// Image height in pixels.
    #[arg(long, default_value_t = 800)]
    pub height: usize,
    /// Ray-tree depth, 0 to 16 (0: what is seen directly).
    #[arg(long, default_value_t = 0)]
    pub depth: usize,
    /// The PNG file to write.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: PathBuf,
    /// Add the bird's-eye map (a square panel right of the frame): the floor plan, the
    /// field of view and the primary ray of every 20th column up to its first hit.
    #[arg(long)]
    pub map: bool,
    /// Add the dual-space panel (a square right of the frame): line space as the (θ, u)
    /// cylinder with the objects' sheets, the walls of the complex's cylinders, the field
    /// of view and the eye's trace with the interval starts on it.
    #[arg(long)]
    pub dual: bool,
}

/// Colours of opaque objects, by id modulo 8.
pub const PALETTE: [[u8; 3]; 8] = [
    [230, 110, 90],
    [110, 190, 110],
    [110, 140, 230],
    [230, 200, 90],
    [190, 110, 210],
    [90, 200, 210],
    [230, 150, 60],
    [180, 180, 180],
];
/// A mirror seen at the end of the depth.
pub const MIRROR: [u8; 3] = [170, 190, 220];
/// A refractive object seen at the end of the depth.
pub const GLASS: [u8; 3] = [120, 210, 190];
/// Sky (above the horizon) and floor (below).
pub const SKY: [u8; 3] = [40, 46, 64];
/// Floor colour.
pub const FLOOR: [u8; 3] = [58, 52, 46];

/// Deepest ray tree.
const MAX_DEPTH: usize = 16;
/// Largest image side.
const MAX_SIDE: usize = 16384;

/// One interval with ids in the whole scene.
#[derive(Clone, Debug)]
pub struct Seen {
    /// Exact start, if the boundary is exact.
    pub exact: Option<Angle>,
    /// Start in radians.
    pub radians: f64,
    /// Objects along the ray, primary first (whole-scene ids).
    pub branch: Vec<ObjectId>,
}

impl Interval for Seen {
    fn exact_start(&self) -> Option<Angle> {
        self.exact
    }
    fn start_radians(&self) -> f64 {
        self.radians
    }
    fn branch(&self) -> &[ObjectId] {
        &self.branch
    }
}

/// The view (depth 0, complex without screens) or ray tree (depth > 0, whole complex)
/// from `q`, with whole-scene ids. `sub_complex` is over the scene without screens.
/// Ray trees are walked over the camera's field of view only.
pub fn intervals(
    scene: &SceneRef<'_>,
    complex: &vcx::partition::Complex,
    camera: &Camera,
    depth: usize,
) -> Result<Vec<Seen>, vcx::walk::WalkError> {
    let q = camera.eye();
    if depth == 0 {
        let sub = non_screens(scene);
        let v = view(complex, &sub.as_ref(), q)?;
        Ok(v.iter()
            .map(|i| Seen {
                exact: Some(i.start),
                radians: i.start.radians(),
                branch: i.object.and_then(|o| sub.original(o)).into_iter().collect(),
            })
            .collect())
    } else {
        let (from, to) = camera.range();
        let mut tree = frame_tree(complex, scene, q, depth, from, to)?;
        vcx::render::angle_order(&mut tree);
        Ok(tree
            .into_iter()
            .map(|t| Seen {
                exact: t.exact_start,
                radians: t.start,
                branch: t.branch,
            })
            .collect())
    }
}

/// The scene without its screens.
pub fn non_screens<'a>(scene: &SceneRef<'a>) -> SubScene<'a> {
    let ids = scene
        .objects()
        .iter()
        .enumerate()
        .filter(|(_, o)| o.material != Material::Screen)
        .map(|(i, _)| ObjectId(i as u32));
    SubScene::new(*scene, ids)
}

/// Runs `vcx render`.
pub fn run(args: &Args) -> Result<(), Failure> {
    if args.depth > MAX_DEPTH {
        return Err(Failure::bad_input(format!(
            "--depth {}: the ray-tree depth must be 0 to {MAX_DEPTH}",
            args.depth
        )));
    }
    for (name, v) in [("--width", args.width), ("--height", args.height)] {
        if v == 0 || v > MAX_SIDE {
            return Err(Failure::bad_input(format!(
                "{name} {v}: must be 1 to {MAX_SIDE} pixels"
            )));
        }
    }
    let (x, y) = parse_pair("--at", &args.at)?;
    let q = query_point("--at", &args.at, x, y)?;
    let camera = Camera::new(
        q,
        args.heading.to_radians(),
        args.fov.to_radians(),
        args.width,
    )
    .map_err(|e| Failure::bad_input(format!("--heading/--fov/--width: {e}")))?;
    let file = super::check::load(&args.scene)?;
    let scene = file.scene.as_ref();
    if let Some(l) = point_in_scene(&scene, q) {
        return Err(in_object(&args.scene, &args.at, &file, l));
    }
    let built = if args.depth == 0 {
        build_checked(&args.scene, &non_screens(&scene).as_ref())?
    } else {
        build_checked(&args.scene, &scene)?
    };
    let seen = intervals(&scene, &built.complex, &camera, args.depth).map_err(|e| Failure {
        message: format!(
            "{}: internal: view from {}: {e}",
            args.scene.display(),
            args.at
        ),
        code: EXIT_INTERNAL,
    })?;
    let image = draw(&file, &camera, &seen, args.depth, args.height);
    let mut panels = Vec::new();
    if args.map {
        panels.push(super::panels::map(&scene, &camera, &seen, args.height));
    }
    if args.dual {
        // The complex is over the scene without screens at depth 0.
        let sub = non_screens(&scene);
        let complex_scene = if args.depth == 0 { sub.as_ref() } else { scene };
        panels.push(super::panels::dual(
            &scene,
            (&built.complex, &complex_scene),
            &camera,
            &seen,
            args.height,
        ));
    }
    let (image, width) = super::panels::beside(&image, args.width, args.height, &panels);
    write_png(&args.output, width, args.height, &image)
}

/// The scene's size (largest side of its bounding box, at least 1).
fn extent(scene: &SceneRef<'_>) -> f64 {
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for p in scene.vertices() {
        let (x, y) = p.to_f64();
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    (hi.0 - lo.0).max(hi.1 - lo.1).max(1.0)
}

/// The colour of a piece's wall (`None`: no wall, the background shows) and the half
/// height of its band in pixels.
#[allow(clippy::too_many_arguments)]
fn shade(
    hits: &mut Hits,
    scene: &SceneRef<'_>,
    camera: &Camera,
    piece: &Piece,
    branch: &[ObjectId],
    depth: usize,
    extent: f64,
    height: usize,
) -> Option<([f64; 3], f64)> {
    let last = *branch.last()?;
    let mid = (piece.from + piece.to) / 2.0;
    let hit = hits.along(scene, camera.eye(), camera.direction_at(mid), branch)?;
    let material = scene.object(last).map(|o| o.material)?;
    let base = match material {
        Material::Mirror | Material::Refractive { .. } if branch.len() <= depth => SKY,
        Material::Mirror => MIRROR,
        Material::Refractive { .. } => GLASS,
        _ => PALETTE[last.0 as usize % PALETTE.len()],
    };
    let bounces = branch.len().saturating_sub(1) as i32;
    let b = (0.35 + 0.65 * hit.facing) / (1.0 + hit.length / extent) * 0.85f64.powi(bounces);
    // Perpendicular distance of the first hit (no fish-eye): the ray f + x·r has length
    // √(1 + x²) per unit ahead.
    let perp = (hit.first / (1.0 + mid * mid).sqrt()).max(1e-9);
    let tan_v = camera.tan_half() * height as f64 / camera.width() as f64;
    let wall_half = 0.03 * extent;
    let half = (height as f64 / 2.0 * wall_half / (perp * tan_v)).max(1.0);
    Some((base.map(|c| f64::from(c) * b), half))
}

/// Draws the frame: RGB rows, top first.
pub fn draw(
    file: &SceneFile,
    camera: &Camera,
    seen: &[Seen],
    depth: usize,
    height: usize,
) -> Vec<u8> {
    let scene = file.scene.as_ref();
    let w = camera.width();
    let ext = extent(&scene);
    let mut img = vec![0u8; w * height * 3];
    let mut col = vec![[0f64; 3]; height];
    let mut pieces: Vec<Piece> = Vec::new();
    coverage(camera, seen, |p| pieces.push(p));
    let horizon = height as f64 / 2.0;
    // Neighbouring pieces mostly meet the same edges: one `Hits` for the frame.
    let mut hits = Hits::new();
    let mut k = 0;
    for c in 0..w {
        col.iter_mut().for_each(|p| *p = [0.0; 3]);
        while let Some(p) = pieces.get(k).filter(|p| p.column == c) {
            k += 1;
            let branch = seen.get(p.interval).map_or(&[][..], |s| &s.branch);
            let wall = shade(&mut hits, &scene, camera, p, branch, depth, ext, height);
            for (row, px) in col.iter_mut().enumerate() {
                let bg = if (row as f64) < horizon { SKY } else { FLOOR };
                // Share of the pixel row [row, row + 1] inside the band.
                let (cover, colour) = match wall {
                    Some((colour, half)) => {
                        let (top, bottom) = (horizon - half, horizon + half);
                        let a = (row as f64).max(top);
                        let b = (row as f64 + 1.0).min(bottom);
                        ((b - a).clamp(0.0, 1.0), colour)
                    }
                    None => (0.0, [0.0; 3]),
                };
                for ch in 0..3 {
                    px[ch] += p.fraction * (cover * colour[ch] + (1.0 - cover) * f64::from(bg[ch]));
                }
            }
        }
        for (row, px) in col.iter().enumerate() {
            let at = (row * w + c) * 3;
            if let Some(out) = img.get_mut(at..at + 3) {
                for ch in 0..3 {
                    out[ch] = px[ch].round().clamp(0.0, 255.0) as u8;
                }
            }
        }
    }
    img
}

fn write_png(path: &std::path::Path, w: usize, h: usize, rgb: &[u8]) -> Result<(), Failure> {
    let fail = |e: &dyn core::fmt::Display| {
        Failure::bad_input(format!("{}: cannot write: {e}", path.display()))
    };
    let f = std::fs::File::create(path).map_err(|e| fail(&e))?;
    let mut enc = png::Encoder::new(BufWriter::new(f), w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().map_err(|e| fail(&e))?;
    writer.write_image_data(rgb).map_err(|e| fail(&e))?;
    writer.finish().map_err(|e| fail(&e))
}
