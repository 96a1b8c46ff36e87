//! One ray through the optics, and a frame of `s` stratified rays per column.

use vcx::render::{transform_eye_f64, Branch, Camera, CoverageTable};
use vcx::ObjectId;

use crate::prepared::{Kind, Prepared, RayHit};

/// An acceleration structure: the nearest object a ray enters.
pub trait Caster {
    /// The nearest non-screen object other than `exclude` that the ray `o + t·d` (`d` of
    /// unit length) enters at `t > 0`.
    fn nearest(
        &self,
        scene: &Prepared,
        o: (f64, f64),
        d: (f64, f64),
        exclude: Option<u32>,
    ) -> Option<RayHit>;
}

fn unit(v: (f64, f64)) -> Option<(f64, f64)> {
    // The plain formula, as the complex's renderer (`vcx::render`) does: no overflow at
    // scene magnitudes, and a hardware square root instead of `hypot`'s scaling.
    let l = (v.0 * v.0 + v.1 * v.1).sqrt();
    (l > 0.0 && l.is_finite()).then(|| (v.0 / l, v.1 / l))
}

/// The branch of the ray from `eye` in direction `dir`: the objects hit, primary first, at
/// most `depth + 1`; mirrors reflect the eye across the hit edge, refractive objects move
/// it by the tangent law at the entry and at the exit edge (the exit edge from the object's
/// own edges), screens are passed (they are never hit).
pub fn trace<C: Caster + ?Sized>(
    scene: &Prepared,
    caster: &C,
    eye: (f64, f64),
    dir: (f64, f64),
    depth: usize,
) -> Branch {
    let mut branch = Branch::new();
    let Some(mut d) = unit(dir) else {
        return branch;
    };
    let (mut e, mut o) = (eye, eye);
    let mut exclude = None;
    for level in 0..=depth.min(vcx::render::MAX_BRANCH - 1) {
        let Some(h) = caster.nearest(scene, o, d, exclude) else {
            break;
        };
        if branch.push(ObjectId(h.object)).is_err() || level == depth {
            break;
        }
        let p = (o.0 + h.t * d.0, o.1 + h.t * d.1);
        let Some(edge) = scene.edge(h.edge) else {
            break;
        };
        let (ne, np) = match scene.kind(h.object) {
            Kind::Mirror => (transform_eye_f64(e, p, edge.n, -1.0), p),
            Kind::Refractive(eta) => {
                let e1 = transform_eye_f64(e, p, edge.n, eta);
                let Some(d1) = unit((p.0 - e1.0, p.1 - e1.1)) else {
                    break;
                };
                let Some(x) = scene.exit(h.object, p, d1) else {
                    break;
                };
                let p2 = (p.0 + x.t * d1.0, p.1 + x.t * d1.1);
                let Some(e2) = scene.edge(x.edge) else { break };
                (transform_eye_f64(e1, p2, e2.n, 1.0 / eta), p2)
            }
            Kind::Opaque | Kind::Screen => break,
        };
        let Some(nd) = unit((np.0 - ne.0, np.1 - ne.1)) else {
            break;
        };
        (e, o, d) = (ne, np, nd);
        exclude = Some(h.object);
    }
    branch
}

/// Renders the camera's columns with `samples` rays per column at the centres of equal
/// strata of the column on the image line, into `out` (cleared first): each ray adds
/// `1/samples` of its column to its branch.
pub fn render<C: Caster + ?Sized>(
    scene: &Prepared,
    caster: &C,
    camera: &Camera,
    samples: usize,
    depth: usize,
    out: &mut CoverageTable,
) {
    out.clear();
    render_columns(
        scene,
        caster,
        camera,
        samples,
        depth,
        0..camera.width(),
        out,
    );
}

/// As [`render`] for the columns `columns` only, appended to `out` (not cleared).
pub fn render_columns<C: Caster + ?Sized>(
    scene: &Prepared,
    caster: &C,
    camera: &Camera,
    samples: usize,
    depth: usize,
    columns: core::ops::Range<usize>,
    out: &mut CoverageTable,
) {
    let s = samples.max(1);
    let eye = camera.eye().to_f64();
    let w = 1.0 / s as f64;
    for c in columns.start..columns.end.min(camera.width()) {
        for k in 0..s {
            let dir = camera.direction_at(camera.sample_x(c, k, s));
            let b = trace(scene, caster, eye, dir, depth);
            out.push(&b, w);
        }
        out.end_column();
    }
}
