//! Free bitangents of the perturbed scene, by checking every pair of vertices.
//!
//! Vertices `a` of object `A` and `b` of object `B ≠ A` (screens included) form a free
//! bitangent iff, with [`sos_orient`] (ranks = global vertex index + 1):
//! * line `ab` is tangent to `A` at `a`: both neighbours of `a` are on the same side of it;
//! * likewise tangent to `B` at `b`;
//! * the segment `ab` meets no other object `C`. `C` misses it iff all vertices of `C` are
//!   strictly on one side of line `ab`, or else the exact chord of `C` on line `ab` lies
//!   outside the closed segment. The exact chord suffices: if the perturbed line crosses
//!   `C`, the exact line meets the closed `C`; `C` is disjoint from `A` and `B`, so it
//!   contains neither `a` nor `b` and its chord (parameter `t`, `a` at 0, `b` at 1) avoids
//!   0 and 1 — it lies in `(0, 1)` or outside `[0, 1]` with room to spare, and an
//!   infinitesimal perturbation cannot move it across.
//!
//! Tangency at both ends keeps the segment out of `A` and `B` themselves.
//!
//! **Directed count.** An undirected free bitangent is a segment; orienting it gives two
//! directed free bitangents (from `a` to `b` and from `b` to `a`), each a vertex of the
//! visibility complex. So `directed = 2 × undirected` (two disjoint convex objects alone:
//! 4 undirected, 8 directed).

use num_rational::BigRational;
use num_traits::{One, Signed};
use vcx::{SceneRef, Sign};

use super::{chord, objects, sos_orient, RObject, Vec2, VertexRef};

/// One undirected free bitangent; `a` is on the object with the smaller id.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct Bitangent {
    /// Tangent vertex on the first object.
    pub a: VertexRef,
    /// Tangent vertex on the second object.
    pub b: VertexRef,
}

/// All free bitangents of the perturbed scene.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Bitangents {
    /// Undirected free bitangents, sorted.
    pub list: Vec<Bitangent>,
    /// `list.len()`.
    pub undirected: usize,
    /// `2 × undirected`: each segment, oriented both ways.
    pub directed: usize,
}

/// A vertex with its perturbation rank.
struct Ranked<'a> {
    rank: u64,
    p: &'a Vec2,
}

fn ranked(o: &RObject, k: usize) -> Ranked<'_> {
    let k = k % o.poly.len();
    Ranked {
        rank: (o.first + k + 1) as u64,
        p: &o.poly[k],
    }
}

fn orient(a: &Ranked<'_>, b: &Ranked<'_>, c: &Ranked<'_>) -> Sign {
    sos_orient((a.rank, a.p), (b.rank, b.p), (c.rank, c.p))
}

/// Whether the line through `a` (vertex `k` of `o`) and `b` is tangent to `o` at `a`.
fn tangent(o: &RObject, k: usize, b: &Ranked<'_>) -> bool {
    let n = o.poly.len();
    let a = ranked(o, k);
    orient(&a, b, &ranked(o, k + n - 1)) == orient(&a, b, &ranked(o, k + 1))
}

/// Whether the segment `ab` meets `c` (disjoint from the objects of `a` and `b`).
fn meets(c: &RObject, a: &Ranked<'_>, b: &Ranked<'_>) -> bool {
    let first = orient(a, b, &ranked(c, 0));
    if (1..c.poly.len()).all(|k| orient(a, b, &ranked(c, k)) == first) {
        return false;
    }
    let d = b.p.sub(a.p);
    chord(&c.poly, a.p, &d).is_some_and(|ch| ch.t_in.is_positive() && ch.t_out < BigRational::one())
}

/// The free bitangents of the perturbed scene (all objects, screens included).
pub fn free_bitangents(scene: SceneRef<'_>) -> Bitangents {
    let objs = objects(scene);
    let mut list = Vec::new();
    for (i, oa) in objs.iter().enumerate() {
        for ob in &objs[i + 1..] {
            for ka in 0..oa.poly.len() {
                for kb in 0..ob.poly.len() {
                    let (a, b) = (ranked(oa, ka), ranked(ob, kb));
                    if tangent(oa, ka, &b)
                        && tangent(ob, kb, &a)
                        && !objs
                            .iter()
                            .filter(|c| c.id != oa.id && c.id != ob.id)
                            .any(|c| meets(c, &a, &b))
                    {
                        list.push(Bitangent {
                            a: oa.vertex_ref(ka),
                            b: ob.vertex_ref(kb),
                        });
                    }
                }
            }
        }
    }
    list.sort();
    Bitangents {
        undirected: list.len(),
        directed: 2 * list.len(),
        list,
    }
}
