//! The side panels of `vcx render --map --dual` (the paper's Fig. 20 shows both beside the
//! frame), drawn in `f64` for output only:
//!
//! * **map**: the floor plan seen from above — objects filled by material (screens as
//!   outlines), the field of view's two edges, and the primary ray of every 20th column
//!   up to its first hit, coloured by what the column finally sees;
//! * **dual**: line space as the `(θ, u)` cylinder, θ from 0 (left) to 2π (right) and the
//!   offset `u = cos θ·(y − c_y) − sin θ·(x − c_x)` of the line of direction θ through
//!   `(x, y)` upwards (positive: `c` lies to the right of the line; `c` is the centre of
//!   the bounding box of the scene and the eye, and the panel's top is `u = 1.05·r`, `r` the
//!   largest distance from `c` to a vertex or the eye): every object's
//!   sheet as a band between its lower and upper chains, the walls of the cylinders of the
//!   complex (a segment at each wall's θ between the cylinder's bottom and top arcs), the
//!   field of view's θ-range, and the eye's trace `u(θ)` with a mark at every interval
//!   start of the view (where the walk changes what it sees).

use vcx::line_space::Bound;
use vcx::partition::{Complex, Wall};
use vcx::render::{centre_intervals, hit_along, Camera};
use vcx::{Material, ObjectId, SceneRef};

use super::render::{Seen, GLASS, MIRROR, PALETTE, SKY};

/// Columns between two rays drawn on the map.
const RAY_STEP: usize = 20;

/// An RGB image, rows top first.
#[derive(Clone, Debug)]
pub struct Canvas {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width · height · 3` bytes.
    pub rgb: Vec<u8>,
}

impl Canvas {
    fn new(width: usize, height: usize, background: [u8; 3]) -> Canvas {
        let rgb = (0..width * height).flat_map(|_| background).collect();
        Canvas { width, height, rgb }
    }

    /// Blends `colour` over pixel `(x, y)` with opacity `alpha` (outside: nothing).
    fn blend(&mut self, x: i64, y: i64, colour: [u8; 3], alpha: f64) {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return;
        }
        let at = (y as usize * self.width + x as usize) * 3;
        if let Some(px) = self.rgb.get_mut(at..at + 3) {
            for (p, c) in px.iter_mut().zip(colour) {
                *p = (f64::from(*p) * (1.0 - alpha) + f64::from(c) * alpha).round() as u8;
            }
        }
    }

    /// A line from `a` to `b` (pixel coordinates), one pixel wide.
    fn line(&mut self, a: (f64, f64), b: (f64, f64), colour: [u8; 3], alpha: f64) {
        let steps = (b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil().min(1e5) as usize;
        for k in 0..=steps {
            let t = if steps == 0 {
                0.0
            } else {
                k as f64 / steps as f64
            };
            let (x, y) = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            self.blend(x.round() as i64, y.round() as i64, colour, alpha);
        }
    }

    /// A filled square of side `2r + 1` centred at `p`.
    fn dot(&mut self, p: (f64, f64), r: i64, colour: [u8; 3]) {
        let (x, y) = (p.0.round() as i64, p.1.round() as i64);
        for dy in -r..=r {
            for dx in -r..=r {
                self.blend(x + dx, y + dy, colour, 1.0);
            }
        }
    }
}

/// Places `panels` to the right of the frame `rgb` (`width × height`), top-aligned on a
/// dark background: the combined image and its width.
pub fn beside(rgb: &[u8], width: usize, height: usize, panels: &[Canvas]) -> (Vec<u8>, usize) {
    let h = panels.iter().map(|p| p.height).fold(height, usize::max);
    let w = width + panels.iter().map(|p| p.width).sum::<usize>();
    let mut out = Canvas::new(w, h, [0, 0, 0]);
    let mut x0 = 0;
    for (src, sw, sh) in core::iter::once((rgb, width, height))
        .chain(panels.iter().map(|p| (&p.rgb[..], p.width, p.height)))
    {
        for y in 0..sh {
            let (from, to) = ((y * sw) * 3, (y * w + x0) * 3);
            if let (Some(s), Some(d)) = (
                src.get(from..from + sw * 3),
                out.rgb.get_mut(to..to + sw * 3),
            ) {
                d.copy_from_slice(s);
            }
        }
        x0 += sw;
    }
    (out.rgb, w)
}

/// The colour of an object on the map and in the dual panel.
fn colour(scene: &SceneRef<'_>, id: ObjectId) -> [u8; 3] {
    match scene.object(id).map(|o| o.material) {
        Some(Material::Mirror) => MIRROR,
        Some(Material::Refractive { .. }) => GLASS,
        Some(Material::Screen) => [200, 200, 200],
        _ => PALETTE[id.0 as usize % PALETTE.len()],
    }
}

/// The bounding box of the scene's vertices and `extra`.
fn bounds(scene: &SceneRef<'_>, extra: (f64, f64)) -> ((f64, f64), (f64, f64)) {
    scene
        .vertices()
        .iter()
        .map(|p| p.to_f64())
        .fold((extra, extra), |(lo, hi), (x, y)| {
            ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y)))
        })
}

/// The bird's-eye map, `size × size` pixels.
pub fn map(scene: &SceneRef<'_>, camera: &Camera, seen: &[Seen], size: usize) -> Canvas {
    let mut c = Canvas::new(size, size, [24, 26, 34]);
    let eye = camera.eye().to_f64();
    let (lo, hi) = bounds(scene, eye);
    let span = (hi.0 - lo.0).max(hi.1 - lo.1).max(1e-9) * 1.1;
    let centre = ((lo.0 + hi.0) / 2.0, (lo.1 + hi.1) / 2.0);
    let scale = size as f64 / span;
    // Scene to pixels, y up.
    let px = |(x, y): (f64, f64)| {
        (
            size as f64 / 2.0 + (x - centre.0) * scale,
            size as f64 / 2.0 - (y - centre.1) * scale,
        )
    };
    for (i, obj) in scene.objects().iter().enumerate() {
        let id = ObjectId(i as u32);
        let poly: Vec<(f64, f64)> = scene.polygon(obj).iter().map(|p| px(p.to_f64())).collect();
        let col = colour(scene, id);
        if obj.material != Material::Screen {
            fill_convex(&mut c, &poly, col);
        }
        for k in 0..poly.len() {
            c.line(poly[k], poly[(k + 1) % poly.len()], col, 1.0);
        }
    }
    let e = px(eye);
    let reach = span * 2.0;
    for col in [0, camera.width().saturating_sub(1)] {
        let (dx, dy) = unit(camera.centre(col).direction());
        c.line(
            e,
            px((eye.0 + reach * dx, eye.1 + reach * dy)),
            [255, 255, 255],
            0.35,
        );
    }
    let mut columns = vec![0usize; camera.width()];
    centre_intervals(camera, seen, &mut columns);
    for (col, &k) in columns.iter().enumerate().step_by(RAY_STEP) {
        let branch = seen.get(k).map_or(&[][..], |s| &s.branch[..]);
        let d = unit(camera.centre(col).direction());
        let (len, colour) = match hit_along(scene, camera.eye(), d, branch) {
            Some(hit) => (
                hit.first,
                branch.last().map_or(SKY, |&id| colour(scene, id)),
            ),
            None => (reach, [120, 120, 140]),
        };
        c.line(e, px((eye.0 + len * d.0, eye.1 + len * d.1)), colour, 0.8);
    }
    c.dot(e, 2, [255, 255, 255]);
    c
}

/// Fills the convex polygon `poly` (pixel coordinates, either orientation): pixel centres
/// on one side of every edge.
fn fill_convex(c: &mut Canvas, poly: &[(f64, f64)], colour: [u8; 3]) {
    let (x0, x1) = poly
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.0), b.max(p.0))
        });
    let (y0, y1) = poly
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
    let n = poly.len();
    let side = |k: usize, q: (f64, f64)| {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        (b.0 - a.0) * (q.1 - a.1) - (b.1 - a.1) * (q.0 - a.0)
    };
    for y in y0.floor().max(0.0) as i64..=y1.ceil().min(c.height as f64) as i64 {
        for x in x0.floor().max(0.0) as i64..=x1.ceil().min(c.width as f64) as i64 {
            let q = (x as f64 + 0.5, y as f64 + 0.5);
            let s: Vec<f64> = (0..n).map(|k| side(k, q)).collect();
            if s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0) {
                c.blend(x, y, colour, 0.85);
            }
        }
    }
}

fn unit((x, y): (f64, f64)) -> (f64, f64) {
    let l = x.hypot(y).max(1e-300);
    (x / l, y / l)
}

/// The offset at `theta` of a chain of object `id`: the lowest (lower chain) or highest
/// (upper chain) of the offsets of its vertices' lines.
fn chain_offset(
    scene: &SceneRef<'_>,
    theta: f64,
    id: ObjectId,
    bound: Bound,
    centre: (f64, f64),
) -> Option<f64> {
    let us = scene
        .polygon(scene.object(id)?)
        .iter()
        .map(|p| offset(theta, p.to_f64(), centre));
    Some(match bound {
        Bound::Lower => us.fold(f64::INFINITY, f64::min),
        Bound::Upper => us.fold(f64::NEG_INFINITY, f64::max),
    })
}

/// The offset of the line of direction `theta` through `p`, relative to `centre`.
pub fn offset(theta: f64, p: (f64, f64), centre: (f64, f64)) -> f64 {
    theta.cos() * (p.1 - centre.1) - theta.sin() * (p.0 - centre.0)
}

/// The dual-space panel, `size × size` pixels (θ across, u up).
pub fn dual(
    scene: &SceneRef<'_>,
    (complex, complex_scene): (&Complex, &SceneRef<'_>),
    camera: &Camera,
    seen: &[Seen],
    size: usize,
) -> Canvas {
    let mut c = Canvas::new(size, size, [18, 18, 24]);
    let eye = camera.eye().to_f64();
    let (lo, hi) = bounds(scene, eye);
    let centre = ((lo.0 + hi.0) / 2.0, (lo.1 + hi.1) / 2.0);
    let radius = scene
        .vertices()
        .iter()
        .map(|p| p.to_f64())
        .chain([eye])
        .map(|(x, y)| (x - centre.0).hypot(y - centre.1))
        .fold(1e-9, f64::max)
        * 1.05;
    let tau = core::f64::consts::TAU;
    let x_of = |theta: f64| theta.rem_euclid(tau) / tau * size as f64;
    let y_of = |u: f64| size as f64 / 2.0 - u / radius * (size as f64 / 2.0);
    // The field of view's θ-range, lighter.
    let half = camera.tan_half().atan();
    let heading = camera.heading();
    for x in 0..size {
        let theta = (x as f64 + 0.5) / size as f64 * tau;
        let off = (theta - heading + core::f64::consts::PI).rem_euclid(tau) - core::f64::consts::PI;
        if off.abs() <= half {
            for y in 0..size {
                c.blend(x as i64, y as i64, [60, 60, 80], 1.0);
            }
        }
    }
    // The sheets: for every column, the band of offsets of each object's lines, lightly
    // filled, with its two chains drawn.
    for x in 0..size {
        let theta = (x as f64 + 0.5) / size as f64 * tau;
        for i in 0..scene.len() {
            let id = ObjectId(i as u32);
            let chain = |bound| chain_offset(scene, theta, id, bound, centre);
            if let (Some(a), Some(b)) = (chain(Bound::Lower), chain(Bound::Upper)) {
                let (xf, col) = (x as f64, colour(scene, id));
                c.line((xf, y_of(a)), (xf, y_of(b)), col, 0.12);
                c.blend(x as i64, y_of(a).round() as i64, col, 0.9);
                c.blend(x as i64, y_of(b).round() as i64, col, 0.9);
            }
        }
    }
    // The walls of the cylinders, between their bottom and top arcs (`complex` is over
    // `complex_scene`, the scene without screens for a view).
    for cyl in complex.cylinders() {
        let Wall::Vertex(_) = cyl.left else { continue };
        let Some(theta) = complex
            .wall_angle(complex_scene, cyl.left)
            .map(|a| a.radians())
        else {
            continue;
        };
        let arc = |chain: Option<vcx::line_space::Chain>, none: f64| {
            chain
                .and_then(|ch| chain_offset(complex_scene, theta, ch.object, ch.bound, centre))
                .unwrap_or(none)
        };
        let (bottom, top) = (arc(cyl.bottom, -radius), arc(cyl.top, radius));
        let x = x_of(theta);
        c.line((x, y_of(bottom)), (x, y_of(top)), [150, 150, 160], 0.25);
    }
    // The eye's trace and the interval starts on it.
    for x in 0..size {
        let theta = (x as f64 + 0.5) / size as f64 * tau;
        c.dot(
            (x as f64, y_of(offset(theta, eye, centre))),
            1,
            [255, 255, 255],
        );
    }
    for s in seen {
        c.dot(
            (x_of(s.radians), y_of(offset(s.radians, eye, centre))),
            2,
            [250, 210, 60],
        );
    }
    c
}

#[cfg(test)]
mod tests {
    use super::offset;

    /// The lines through a point and a vertex have equal offsets in their direction, and a
    /// point to the left of a direction has the larger offset (`u` up in the panel).
    #[test]
    fn offsets_follow_the_documented_convention() {
        let (c, e, v) = ((3.0, -2.0), (1.5, 0.25), (-4.0, 7.5));
        let theta = f64::atan2(v.1 - e.1, v.0 - e.0);
        assert!((offset(theta, e, c) - offset(theta, v, c)).abs() < 1e-12);
        let left = (e.0 - theta.sin(), e.1 + theta.cos());
        assert!((offset(theta, left, c) - offset(theta, e, c) - 1.0).abs() < 1e-12);
    }
}
