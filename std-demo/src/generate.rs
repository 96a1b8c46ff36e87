//! Deterministic test scenes after the paper's experiments (Cho & Forsyth 1999, §6).
//!
//! * [`SceneKind::Grid`] (Fig. 20): `n` random triangles, one per cell of a
//!   ⌈√n⌉ × ⌈√n⌉ grid of square cells, filled row by row.
//! * [`SceneKind::Hall`] (Fig. 21): a hall of mirrors — a square room whose four walls are
//!   thin mirror boxes, apart at the corners so they do not touch, with `n` opaque or
//!   mirror pillars in randomly chosen cells of the room's grid.
//! * [`SceneKind::Mixed`] (Fig. 22): `n` objects — opaque polygons, thin mirror slabs,
//!   refractive discs (η from 1.33 to 1.60) and a few thin screen boxes on grid lines.
//!
//! Every object is built inside its own cell with a margin, and screens lie on grid lines
//! away from the cells' contents, so objects never touch by construction. Coordinates are
//! multiples of 1/64 (exact on the 2⁻¹⁶ grid, short in JSON). Each object is checked on its
//! own and regenerated if the validator rejects it; the whole scene is validated at the end.
//!
//! The output depends only on `(kind, n, seed)`: the generator is `ChaCha8Rng`, integer
//! sampling uses fixed-width types, and trigonometry uses `libm` (the same bits everywhere).

use core::fmt;

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Map, Value};
use vcx::geom::Point;
use vcx::{Eta, Material, Scene, SceneError};

use crate::scene_file::{ObjectSpec, SceneFile};

/// Largest number of objects a generator makes (the grid must fit in the coordinate range).
pub const MAX_OBJECTS: u32 = 1_000_000;

/// Generated coordinates are multiples of 1/`STEPS` scene units.
const STEPS: i32 = 64;
/// Side of a grid cell, in scene units.
const CELL: i32 = 10;
/// Side of a grid cell, in steps.
const CELL_STEPS: i32 = CELL * STEPS;
/// How many times one object is regenerated before giving up (never reached in practice).
const RETRIES: usize = 1000;

/// Which test scene to generate.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum SceneKind {
    /// Fig. 20: random triangles on a grid.
    Grid,
    /// Fig. 21: a hall of mirrors with pillars.
    Hall,
    /// Fig. 22: opaque, mirror, refractive objects and screens.
    Mixed,
}

impl SceneKind {
    /// Name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Grid => "grid",
            SceneKind::Hall => "hall",
            SceneKind::Mixed => "mixed",
        }
    }
}

/// Why a scene could not be generated.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[non_exhaustive]
pub enum GenerateError {
    /// More objects than [`MAX_OBJECTS`]. Ask for fewer.
    TooMany {
        /// What was asked for.
        n: u32,
    },
    /// The generator made an invalid scene: a bug in the generator, please report it.
    Invalid(SceneError),
}

impl fmt::Display for GenerateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GenerateError::TooMany { n } => {
                write!(
                    f,
                    "{n} objects asked, at most {MAX_OBJECTS} can be generated"
                )
            }
            GenerateError::Invalid(e) => {
                write!(f, "internal error: the generated scene is invalid: {e}")
            }
        }
    }
}

impl core::error::Error for GenerateError {}

/// Generates a scene of `n` objects (for `Hall`: `n` pillars plus four walls).
pub fn generate(kind: SceneKind, n: u32, seed: u64) -> Result<SceneFile, GenerateError> {
    if n > MAX_OBJECTS {
        return Err(GenerateError::TooMany { n });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let objects = match kind {
        SceneKind::Grid => grid(&mut rng, n),
        SceneKind::Hall => hall(&mut rng, n),
        SceneKind::Mixed => mixed(&mut rng, n),
    }
    .map_err(GenerateError::Invalid)?;
    let mut top = Map::new();
    top.insert(
        "generated_by".into(),
        format!("vcx gen {} {n} --seed {seed}", kind.name()).into(),
    );
    SceneFile::new(objects, top).map_err(GenerateError::Invalid)
}

/// Cells per side of the smallest square grid with at least `n` cells (at least 1).
fn cells_per_side(n: u32) -> i32 {
    let mut c: i32 = 1;
    while i64::from(c) * i64::from(c) < i64::from(n) {
        c += 1;
    }
    c
}

fn named(name: String, material: Material, vertices: Vec<Point>) -> ObjectSpec {
    let mut extra = Map::new();
    extra.insert("name".into(), Value::String(name));
    ObjectSpec {
        material,
        vertices,
        extra,
    }
}

/// A point from coordinates in steps of 1/64.
fn point(x: i32, y: i32) -> Result<Point, SceneError> {
    let scale = 1 << (vcx::geom::point::FRAC_BITS - STEPS.trailing_zeros());
    x.checked_mul(scale)
        .zip(y.checked_mul(scale))
        .and_then(|(x, y)| Point::from_raw(x, y))
        // Cannot happen below MAX_OBJECTS; reported as an invalid scene, not a panic.
        .ok_or(SceneError::CapacityExceeded { object: 0 })
}

/// A point from scene units, rounded to the 1/64 steps.
fn point_f64(x: f64, y: f64) -> Result<Point, SceneError> {
    let s = f64::from(STEPS);
    point(libm::round(x * s) as i32, libm::round(y * s) as i32)
}

/// Builds one object with `make` until the validator accepts it on its own.
fn retry(
    rng: &mut ChaCha8Rng,
    index: usize,
    material: Material,
    mut make: impl FnMut(&mut ChaCha8Rng) -> Result<Vec<Point>, SceneError>,
) -> Result<Vec<Point>, SceneError> {
    let mut last = SceneError::CapacityExceeded { object: index };
    for _ in 0..RETRIES {
        let pts = make(rng)?;
        match Scene::new([(material, pts.as_slice())]) {
            Ok(_) => return Ok(pts),
            Err(e) => last = e,
        }
    }
    Err(last)
}

/// Axis-parallel box `[x0, x1] × [y0, y1]` (steps), counter-clockwise.
fn rect(x0: i32, y0: i32, x1: i32, y1: i32) -> Result<Vec<Point>, SceneError> {
    Ok(vec![
        point(x0, y0)?,
        point(x1, y0)?,
        point(x1, y1)?,
        point(x0, y1)?,
    ])
}

/// Lower-left corner (steps) of cell `k` of a `c × c` grid, row by row from the origin.
fn cell_origin(k: i32, c: i32) -> (i32, i32) {
    ((k % c) * CELL_STEPS, (k / c) * CELL_STEPS)
}

/// A fair coin: reverse the winding, so files exercise both.
fn maybe_reverse(rng: &mut ChaCha8Rng, mut pts: Vec<Point>) -> Vec<Point> {
    if rng.gen_bool(0.5) {
        pts.reverse();
    }
    pts
}

/// Fig. 20: a random triangle per cell, vertices at least 1 unit inside the cell, with
/// inradius at least 0.6 units so it is not a sliver.
fn grid(rng: &mut ChaCha8Rng, n: u32) -> Result<Vec<ObjectSpec>, SceneError> {
    let c = cells_per_side(n);
    let margin = STEPS;
    let mut out = Vec::new();
    for k in 0..n as i32 {
        let (x0, y0) = cell_origin(k, c);
        let pts = retry(rng, out.len(), Material::Opaque, |rng| {
            let mut v = [(0i32, 0i32); 3];
            for _ in 0..RETRIES {
                for p in &mut v {
                    *p = (
                        x0 + rng.gen_range(margin..=CELL_STEPS - margin),
                        y0 + rng.gen_range(margin..=CELL_STEPS - margin),
                    );
                }
                if inradius_steps(v) >= 0.6 * f64::from(STEPS) {
                    break;
                }
            }
            v.iter().map(|&(x, y)| point(x, y)).collect()
        })?;
        out.push(named(format!("triangle {k}"), Material::Opaque, pts));
    }
    Ok(out)
}

/// Inradius of a triangle in steps (for shape quality only, not a decision of the core).
fn inradius_steps(v: [(i32, i32); 3]) -> f64 {
    let [a, b, c] = v.map(|(x, y)| (f64::from(x), f64::from(y)));
    let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
    let d = |p: (f64, f64), q: (f64, f64)| libm::hypot(q.0 - p.0, q.1 - p.1);
    let perimeter = d(a, b) + d(b, c) + d(c, a);
    if perimeter > 0.0 {
        cross.abs() / perimeter
    } else {
        0.0
    }
}

/// A convex polygon with `k` vertices on a circle of radius `r` (units) around `center`,
/// at angles jittered by up to ±`jitter` of the k-th of a turn (jitter < 0.5).
fn circle_polygon(
    rng: &mut ChaCha8Rng,
    center: (f64, f64),
    r: f64,
    k: u32,
    jitter: f64,
) -> Result<Vec<Point>, SceneError> {
    let turn = 2.0 * core::f64::consts::PI;
    let start = f64::from(rng.gen_range(0u32..3600)) / 3600.0 * turn;
    let sector = turn / f64::from(k);
    let max_jitter = (jitter * 1000.0) as i32;
    (0..k)
        .map(|i| {
            let j = f64::from(rng.gen_range(-max_jitter..=max_jitter)) / 1000.0;
            let a = start + (f64::from(i) + j) * sector;
            point_f64(center.0 + r * libm::cos(a), center.1 + r * libm::sin(a))
        })
        .collect()
}

/// The centre of a cell, jittered by up to `jitter` steps on each axis.
fn jittered_center(rng: &mut ChaCha8Rng, x0: i32, y0: i32, jitter: i32) -> (f64, f64) {
    let s = f64::from(STEPS);
    (
        f64::from(x0 + CELL_STEPS / 2 + rng.gen_range(-jitter..=jitter)) / s,
        f64::from(y0 + CELL_STEPS / 2 + rng.gen_range(-jitter..=jitter)) / s,
    )
}

/// A rectangle of `length × width` units centred at `center`, turned by a random angle.
fn slab(
    rng: &mut ChaCha8Rng,
    center: (f64, f64),
    length: f64,
    width: f64,
) -> Result<Vec<Point>, SceneError> {
    let a = f64::from(rng.gen_range(0u32..3600)) / 3600.0 * 2.0 * core::f64::consts::PI;
    let (s, c) = (libm::sin(a), libm::cos(a));
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(u, v)| {
            let (du, dv) = (u * length / 2.0, v * width / 2.0);
            point_f64(center.0 + c * du - s * dv, center.1 + s * du + c * dv)
        })
        .collect()
}

/// Fig. 21: four mirror walls around a square room, pillars in random cells of its grid.
fn hall(rng: &mut ChaCha8Rng, n: u32) -> Result<Vec<ObjectSpec>, SceneError> {
    let c = cells_per_side(n);
    let w = c * CELL_STEPS;
    let t = STEPS / 2; // wall thickness 0.5
    let gap = STEPS / 2; // the side walls stop 0.5 short of the corners
    let mut out = vec![
        named("wall south".into(), Material::Mirror, rect(0, -t, w, 0)?),
        named(
            "wall east".into(),
            Material::Mirror,
            rect(w, gap, w + t, w - gap)?,
        ),
        named("wall north".into(), Material::Mirror, rect(0, w, w, w + t)?),
        named(
            "wall west".into(),
            Material::Mirror,
            rect(-t, gap, 0, w - gap)?,
        ),
    ];
    let mut cells: Vec<i32> = (0..c * c).collect();
    cells.shuffle(rng);
    for (i, &cell) in cells.iter().take(n as usize).enumerate() {
        let (x0, y0) = cell_origin(cell, c);
        let material = if rng.gen_bool(0.5) {
            Material::Opaque
        } else {
            Material::Mirror
        };
        let pts = retry(rng, out.len(), material, |rng| {
            // Centre within ±1 unit of the cell's, radius ≤ 3: at least 1 unit inside.
            let center = jittered_center(rng, x0, y0, STEPS);
            let r = f64::from(rng.gen_range(96..=192)) / f64::from(STEPS);
            let k = rng.gen_range(3u32..=8);
            let pts = circle_polygon(rng, center, r, k, 0.0)?;
            Ok(maybe_reverse(rng, pts))
        })?;
        out.push(named(format!("pillar {i}"), material, pts));
    }
    Ok(out)
}

/// Fig. 22: a mix of materials in grid cells, and thin screens on cell edges.
fn mixed(rng: &mut ChaCha8Rng, n: u32) -> Result<Vec<ObjectSpec>, SceneError> {
    let screens = if n >= 4 { (n / 10).max(1) } else { 0 };
    let cells_used = n - screens;
    let c = cells_per_side(cells_used);
    let mut out = Vec::new();

    // Materials: the first three cover opaque, mirror, refractive; the rest are random.
    let mut cells: Vec<i32> = (0..c * c).collect();
    cells.shuffle(rng);
    for (i, &cell) in cells.iter().take(cells_used as usize).enumerate() {
        let (x0, y0) = cell_origin(cell, c);
        let pick = match i {
            0..=2 => i as u32 * 4,
            _ => rng.gen_range(0u32..10),
        };
        let (name, material) = match pick {
            0..=3 => ("block", Material::Opaque),
            4..=6 => ("mirror", Material::Mirror),
            _ => {
                let eta = f64::from(rng.gen_range(133u32..=160)) / 100.0;
                let eta = Eta::from_f64(eta).ok_or(SceneError::CapacityExceeded { object: i })?;
                ("lens", Material::Refractive { eta })
            }
        };
        let pts = retry(rng, out.len(), material, |rng| {
            let pts = match material {
                Material::Mirror => {
                    // A thin slab: half-diagonal ≤ 3.26, centre within ±0.5: inside [1, 9].
                    let center = jittered_center(rng, x0, y0, STEPS / 2);
                    let length = f64::from(rng.gen_range(192..=416)) / f64::from(STEPS);
                    slab(rng, center, length, 0.375)?
                }
                Material::Refractive { .. } => {
                    let center = jittered_center(rng, x0, y0, STEPS);
                    let r = f64::from(rng.gen_range(96..=192)) / f64::from(STEPS);
                    let k = rng.gen_range(6u32..=12);
                    circle_polygon(rng, center, r, k, 0.0)?
                }
                _ => {
                    let center = jittered_center(rng, x0, y0, STEPS);
                    let r = f64::from(rng.gen_range(96..=192)) / f64::from(STEPS);
                    let k = rng.gen_range(3u32..=7);
                    circle_polygon(rng, center, r, k, 0.3)?
                }
            };
            Ok(maybe_reverse(rng, pts))
        })?;
        out.push(named(format!("{name} {i}"), material, pts));
    }

    // Screens: boxes 0.25 thick on one cell edge each, stopping 0.5 short of the grid
    // corners, so screens on crossing lines never meet and cell contents stay 0.85 away.
    // Edges: vertical ones (line x = kx, row r) then horizontal ones (line y = ky, column r).
    let half = STEPS / 8;
    let end = STEPS / 2;
    let vertical = (c + 1) * c;
    let mut edges: Vec<i32> = (0..2 * vertical).collect();
    edges.shuffle(rng);
    for (i, &e) in edges.iter().take(screens as usize).enumerate() {
        let (line, along) = ((e % vertical) / c, (e % vertical) % c);
        let (l, a) = (line * CELL_STEPS, along * CELL_STEPS);
        let pts = if e < vertical {
            rect(l - half, a + end, l + half, a + CELL_STEPS - end)?
        } else {
            rect(a + end, l - half, a + CELL_STEPS - end, l + half)?
        };
        out.push(named(format!("screen {i}"), Material::Screen, pts));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts(f: &SceneFile) -> [usize; 4] {
        let mut c = [0; 4];
        for o in f.scene.as_ref().objects() {
            c[match o.material {
                Material::Opaque => 0,
                Material::Mirror => 1,
                Material::Refractive { .. } => 2,
                _ => 3,
            }] += 1;
        }
        c
    }

    #[test]
    fn generated_scenes_are_valid_for_many_seeds_and_sizes() {
        for kind in [SceneKind::Grid, SceneKind::Hall, SceneKind::Mixed] {
            for n in [0, 1, 2, 3, 4, 5, 16, 30, 100] {
                for seed in 0..20 {
                    let f = generate(kind, n, seed)
                        .unwrap_or_else(|e| panic!("{kind:?} n={n} seed={seed}: {e}"));
                    let expected = n as usize + if kind == SceneKind::Hall { 4 } else { 0 };
                    assert_eq!(f.scene.as_ref().len(), expected);
                    assert_eq!(f.meta.len(), expected);
                    assert!(f.meta.iter().all(|m| m.name().is_some()));
                }
            }
            for seed in 0..3 {
                let f = generate(kind, 1000, seed).unwrap();
                let expected = if kind == SceneKind::Hall { 1004 } else { 1000 };
                assert_eq!(f.scene.as_ref().len(), expected);
            }
        }
    }

    #[test]
    fn output_is_deterministic_and_round_trips() {
        for kind in [SceneKind::Grid, SceneKind::Hall, SceneKind::Mixed] {
            let a = generate(kind, 40, 7).unwrap().to_json();
            let b = generate(kind, 40, 7).unwrap().to_json();
            assert_eq!(a, b);
            assert_ne!(a, generate(kind, 40, 8).unwrap().to_json());
            let back = crate::scene_file::parse(&a).unwrap();
            assert_eq!(back.to_json(), a);
            assert_eq!(back.rounded_vertices(), 0);
        }
    }

    #[test]
    fn materials_are_as_described() {
        assert_eq!(
            counts(&generate(SceneKind::Grid, 64, 1).unwrap()),
            [64, 0, 0, 0]
        );
        let hall = counts(&generate(SceneKind::Hall, 12, 1).unwrap());
        assert_eq!(hall[0] + hall[1], 16);
        assert_eq!(hall[2] + hall[3], 0);
        for n in 4..40 {
            let mixed = counts(&generate(SceneKind::Mixed, n, 3).unwrap());
            assert!(mixed.iter().all(|&k| k > 0), "n={n}: {mixed:?}");
        }
    }

    #[test]
    fn too_many_is_an_error() {
        assert_eq!(
            generate(SceneKind::Grid, MAX_OBJECTS + 1, 0).unwrap_err(),
            GenerateError::TooMany { n: MAX_OBJECTS + 1 }
        );
    }
}
