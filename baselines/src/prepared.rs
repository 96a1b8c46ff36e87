//! The scene in `f64`, prepared once for ray casting: per object its material, box and
//! edges; per edge a point, the outward unit normal and the line's offset.

use vcx::{Material, SceneRef};

/// What a ray does at an object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// Stops the ray.
    Opaque,
    /// Reflects it (the eye is mirrored across the hit edge).
    Mirror,
    /// Refracts it by the tangent law, with this index inside.
    Refractive(f64),
    /// Transparent; never hit (left out of the acceleration structures).
    Screen,
}

/// One object: its material, bounding box and edge range.
#[derive(Clone, Copy, Debug)]
pub struct Obj {
    /// What a ray does here.
    pub kind: Kind,
    /// `(min x, min y, max x, max y)`.
    pub bbox: [f64; 4],
    /// Its edges are `edges[first..first + len]`, counter-clockwise.
    pub first: u32,
    /// Number of edges.
    pub len: u32,
}

/// One edge: `n · p = c` on its line, `n` the outward unit normal.
#[derive(Clone, Copy, Debug)]
pub struct EdgeData {
    /// Outward unit normal.
    pub n: (f64, f64),
    /// Offset of the line: `n · a` for its start `a`.
    pub c: f64,
    /// Start vertex.
    pub a: (f64, f64),
}

/// Where a ray meets an object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// The object (id in the scene).
    pub object: u32,
    /// Ray parameter of the hit (the ray's direction has unit length: the distance).
    pub t: f64,
    /// The edge (global index in [`Prepared::edges`]).
    pub edge: u32,
}

/// The scene prepared for `f64` ray casting.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// Objects by id.
    pub objects: Vec<Obj>,
    /// All edges, grouped by object.
    pub edges: Vec<EdgeData>,
    /// Bounding box of the non-screen objects (a unit box if there are none).
    pub bbox: [f64; 4],
}

impl Prepared {
    /// Converts a validated scene (vertices are stored counter-clockwise).
    pub fn new(scene: &SceneRef<'_>) -> Prepared {
        let mut objects = Vec::with_capacity(scene.len());
        let mut edges = Vec::with_capacity(scene.vertices().len());
        let mut all: Option<[f64; 4]> = None;
        for o in scene.objects() {
            let poly: Vec<(f64, f64)> = scene.polygon(o).iter().map(|p| p.to_f64()).collect();
            let first = edges.len() as u32;
            let mut bb = [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ];
            for (k, &a) in poly.iter().enumerate() {
                let b = poly[(k + 1) % poly.len()];
                let (nx, ny) = (b.1 - a.1, a.0 - b.0);
                let l = nx.hypot(ny);
                let n = (nx / l, ny / l);
                edges.push(EdgeData {
                    n,
                    c: n.0 * a.0 + n.1 * a.1,
                    a,
                });
                bb = [
                    bb[0].min(a.0),
                    bb[1].min(a.1),
                    bb[2].max(a.0),
                    bb[3].max(a.1),
                ];
            }
            let kind = match o.material {
                Material::Opaque => Kind::Opaque,
                Material::Mirror => Kind::Mirror,
                Material::Refractive { eta } => Kind::Refractive(eta.to_f64()),
                Material::Screen => Kind::Screen,
            };
            if kind != Kind::Screen {
                all = Some(match all {
                    None => bb,
                    Some(a) => [
                        a[0].min(bb[0]),
                        a[1].min(bb[1]),
                        a[2].max(bb[2]),
                        a[3].max(bb[3]),
                    ],
                });
            }
            objects.push(Obj {
                kind,
                bbox: bb,
                first,
                len: poly.len() as u32,
            });
        }
        Prepared {
            objects,
            edges,
            bbox: all.unwrap_or([0.0, 0.0, 1.0, 1.0]),
        }
    }

    fn edges_of(&self, object: u32) -> &[EdgeData] {
        let Some(o) = self.objects.get(object as usize) else {
            return &[];
        };
        let (a, n) = (o.first as usize, o.len as usize);
        self.edges.get(a..a + n).unwrap_or(&[])
    }

    /// The ray `o + t·d` against the convex object (Cyrus–Beck): the entry parameter and
    /// edge if the ray enters it at `t > 0`.
    #[inline]
    pub fn enter(&self, object: u32, o: (f64, f64), d: (f64, f64)) -> Option<RayHit> {
        let first = self.objects.get(object as usize)?.first;
        let (mut t_in, mut e_in, mut t_out) = (f64::NEG_INFINITY, 0usize, f64::INFINITY);
        for (k, e) in self.edges_of(object).iter().enumerate() {
            let den = e.n.0 * d.0 + e.n.1 * d.1;
            let num = e.c - (e.n.0 * o.0 + e.n.1 * o.1);
            if den < 0.0 {
                let t = num / den;
                if t > t_in {
                    t_in = t;
                    e_in = k;
                }
            } else if den > 0.0 {
                t_out = t_out.min(num / den);
            } else if num < 0.0 {
                return None;
            }
            if t_in > t_out {
                return None;
            }
        }
        (t_in > 0.0 && t_in <= t_out).then_some(RayHit {
            object,
            t: t_in,
            edge: first + e_in as u32,
        })
    }

    /// The ray `o + t·d` from inside (or on the boundary of) the object: where it leaves.
    pub fn exit(&self, object: u32, o: (f64, f64), d: (f64, f64)) -> Option<RayHit> {
        let first = self.objects.get(object as usize)?.first;
        let (mut t_out, mut e_out) = (f64::INFINITY, None);
        for (k, e) in self.edges_of(object).iter().enumerate() {
            let den = e.n.0 * d.0 + e.n.1 * d.1;
            if den > 0.0 {
                let t = (e.c - (e.n.0 * o.0 + e.n.1 * o.1)) / den;
                if t < t_out {
                    t_out = t;
                    e_out = Some(k);
                }
            }
        }
        e_out.map(|k| RayHit {
            object,
            t: t_out.max(0.0),
            edge: first + k as u32,
        })
    }

    /// The edge with global index `k`.
    pub fn edge(&self, k: u32) -> Option<&EdgeData> {
        self.edges.get(k as usize)
    }

    /// What a ray does at the object.
    pub fn kind(&self, object: u32) -> Kind {
        self.objects
            .get(object as usize)
            .map_or(Kind::Opaque, |o| o.kind)
    }
}
