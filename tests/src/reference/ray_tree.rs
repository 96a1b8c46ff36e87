//! Tracing one primary ray through mirrors and refractive objects (DESIGN.md §6 optics).
//!
//! A traced ray is a list of **stages**: straight pieces, each on a line through its
//! (virtual) eye. Stage 0 is the primary ray from the viewpoint. After a hit:
//! * **mirror**: the next eye is the reflection of the eye across the hit edge's line; the
//!   next stage is the ray from that eye through the hit point, beyond the hit point;
//! * **refractive** (index η, outside 1): tangent law η₁·tanθ₁ = η₂·tanθ₂, i.e. with `F`
//!   the foot of the eye `E` on the interface line the new eye is `F + (η₂/η₁)(E − F)`.
//!   Applied at the entry edge (1 → η) it gives the eye of an *inside* stage, which runs
//!   through the convex object to its exit edge (nothing else is visible inside); applied
//!   again there (η → 1) it gives the eye of the stage that continues outside.
//!
//! The **level** of a stage is the index in the branch of the object it hits: level `k`'s
//! outer stage hits `branch[k]`; the inside stage of a refractive `branch[k]` also has level
//! `k`. A refractive pass is one depth level. Screens are transparent: they are ignored.

use num_rational::BigRational;
use num_traits::{One, Signed};
use vcx::{Eta, Material, ObjectId, SceneRef};

use super::{check_free, chord, objects, RObject, RefError, Vec2};

/// Options of a ray-tree sweep.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct RayTreeOptions {
    /// Largest number of mirror/refraction interactions after the primary hit (`0`: plain
    /// view). A branch has at most `depth + 1` objects.
    pub depth: usize,
    /// Round every virtual eye to the query grid (2^-32, ties away from zero) as soon as it
    /// is built, as the core does. Default: exact optics.
    pub round_eyes: bool,
}

/// Where a stage's ray ends.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Hit {
    /// The object hit (for an inside stage: the refractive object itself).
    pub object: ObjectId,
    /// The edge hit (entry edge, or exit edge for an inside stage), as the index `k` of the
    /// counter-clockwise edge from stored vertex `k` to `k + 1`.
    pub edge: usize,
    /// The exact hit point.
    pub point: Vec2,
}

/// One straight piece of a traced ray.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Stage {
    /// Depth level (index in the branch of the object this stage hits).
    pub level: usize,
    /// Whether this is the inside stage of a refractive object.
    pub inside: bool,
    /// The (virtual) eye: the stage lies on a line through it.
    pub eye: Vec2,
    /// Where the stage starts: the viewpoint, or the previous stage's hit point.
    pub origin: Vec2,
    /// Direction: the primary direction for stage 0, `origin − eye` afterwards.
    pub dir: Vec2,
    /// The first non-screen object hit (excluding the object just left), if any.
    pub hit: Option<Hit>,
}

/// A traced primary ray.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Trace {
    /// The stages, in the order light travels them backwards from the eye.
    pub stages: Vec<Stage>,
    /// Objects hit, primary first, each refractive pass once, screens left out.
    pub branch: Vec<ObjectId>,
    /// Set when a further stage could not be built: a rounded eye fell on or across its
    /// interface line, or the ray entered a refractive object exactly at a vertex and left
    /// at once. The stages listed are valid.
    pub degenerate: bool,
}

/// Traces one primary ray from the free point `q` in direction `dir` (see the module
/// documentation for the optics). Errors if `q` is not free or `dir` is zero.
pub fn trace_ray(
    scene: SceneRef<'_>,
    q: &Vec2,
    dir: &Vec2,
    opts: RayTreeOptions,
) -> Result<Trace, RefError> {
    if dir.is_zero() {
        return Err(RefError::ZeroDirection);
    }
    let objs = objects(scene);
    check_free(&objs, q)?;
    Ok(trace(&objs, q, dir, opts))
}

/// The nearest non-screen object other than `exclude` met by the ray `origin + t·dir`,
/// `t > 0`, with its entry edge and point.
fn nearest(objs: &[RObject], origin: &Vec2, dir: &Vec2, exclude: Option<ObjectId>) -> Option<Hit> {
    objs.iter()
        .filter(|o| !o.is_screen() && Some(o.id) != exclude)
        .filter_map(|o| Some((o, chord(&o.poly, origin, dir)?)))
        // `origin` is outside every candidate, so a chord is entirely before or after it.
        .filter(|(_, c)| c.t_in.is_positive())
        .min_by(|(_, a), (_, b)| a.t_in.cmp(&b.t_in))
        .map(|(o, c)| Hit {
            object: o.id,
            edge: c.edge_in,
            point: origin.add(&dir.scale(&c.t_in)),
        })
}

/// Sign of the side of `p` with respect to the line `ab`.
fn side(a: &Vec2, b: &Vec2, p: &Vec2) -> i8 {
    let c = b.sub(a).cross(&p.sub(a));
    if c.is_positive() {
        1
    } else if c.is_negative() {
        -1
    } else {
        0
    }
}

/// The foot of `e` on the line `ab`.
fn foot(e: &Vec2, a: &Vec2, b: &Vec2) -> Vec2 {
    let d = b.sub(a);
    a.add(&d.scale(&(d.dot(&e.sub(a)) / d.dot(&d))))
}

/// New eye `F + k(E − F)`: `k = −1` reflects, `k = η₂/η₁` refracts (tangent law).
fn transform_eye(e: &Vec2, a: &Vec2, b: &Vec2, k: &BigRational, round: bool) -> Vec2 {
    let f = foot(e, a, b);
    let n = f.add(&e.sub(&f).scale(k));
    if round {
        n.round_to_query_grid()
    } else {
        n
    }
}

pub(crate) fn trace(objs: &[RObject], q: &Vec2, dir: &Vec2, opts: RayTreeOptions) -> Trace {
    let mut tr = Trace {
        stages: Vec::new(),
        branch: Vec::new(),
        degenerate: false,
    };
    let (mut eye, mut origin, mut dir) = (q.clone(), q.clone(), dir.clone());
    let mut exclude = None;
    let mut level = 0;
    loop {
        let hit = nearest(objs, &origin, &dir, exclude);
        tr.stages.push(Stage {
            level,
            inside: false,
            eye: eye.clone(),
            origin: origin.clone(),
            dir: dir.clone(),
            hit: hit.clone(),
        });
        let Some(h) = hit else { break };
        tr.branch.push(h.object);
        let obj = &objs[h.object.0 as usize];
        if level == opts.depth {
            break;
        }
        let (a, b) = obj.edge(h.edge);
        let next = match obj.material {
            Material::Opaque | Material::Screen => break,
            Material::Mirror => {
                let e = transform_eye(&eye, a, b, &-BigRational::one(), opts.round_eyes);
                // The reflected eye must be strictly behind the mirror's line.
                (side(a, b, &e) == -side(a, b, &eye) && side(a, b, &e) != 0)
                    .then(|| (e, h.point.clone()))
            }
            Material::Refractive { eta } => {
                let eta = BigRational::new(eta.raw().into(), (1u32 << Eta::FRAC_BITS).into());
                refract(obj, &h, &eye, level, &eta, opts.round_eyes, &mut tr)
            }
        };
        let Some((e, p)) = next else {
            tr.degenerate = true;
            break;
        };
        dir = p.sub(&e);
        if dir.is_zero() {
            tr.degenerate = true;
            break;
        }
        eye = e;
        origin = p;
        exclude = Some(obj.id);
        level += 1;
    }
    tr
}

/// A refractive pass: pushes the inside stage and returns the outside eye and the exit
/// point, or `None` if degenerate.
fn refract(
    obj: &RObject,
    entry: &Hit,
    eye: &Vec2,
    level: usize,
    eta: &BigRational,
    round: bool,
    tr: &mut Trace,
) -> Option<(Vec2, Vec2)> {
    let (a, b) = obj.edge(entry.edge);
    let e_in = transform_eye(eye, a, b, eta, round);
    // The inside eye stays on the viewer's side of the entry line.
    if side(a, b, &e_in) != side(a, b, eye) || side(a, b, &e_in) == 0 {
        return None;
    }
    let d_in = entry.point.sub(&e_in);
    let c = chord(&obj.poly, &entry.point, &d_in)?;
    if !c.t_out.is_positive() {
        return None;
    }
    let exit = entry.point.add(&d_in.scale(&c.t_out));
    tr.stages.push(Stage {
        level,
        inside: true,
        eye: e_in.clone(),
        origin: entry.point.clone(),
        dir: d_in,
        hit: Some(Hit {
            object: obj.id,
            edge: c.edge_out,
            point: exit.clone(),
        }),
    });
    let (a, b) = obj.edge(c.edge_out);
    let e_out = transform_eye(&e_in, a, b, &(BigRational::one() / eta), round);
    // Both inside and outside eyes are on the inner side of the exit line.
    if side(a, b, &e_out) != side(a, b, &e_in) || side(a, b, &e_out) == 0 {
        return None;
    }
    Some((e_out, exit))
}
