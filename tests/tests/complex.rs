//! The visibility complex (cylindrical partition) against its invariants and the exact
//! reference.

use vcx::partition::build_by_sweep;
use vcx::{Material, Point, Scene};
use vcx_demo::generate::{generate, SceneKind};

fn pt(x: i32, y: i32) -> Point {
    Point::from_raw(x << 16, y << 16).unwrap()
}

fn scene(polys: &[Vec<Point>]) -> Scene {
    Scene::new(polys.iter().map(|p| (Material::Opaque, &p[..]))).unwrap()
}

fn boxes(cells: &[(i32, i32)], size: i32, gap: i32) -> Vec<Vec<Point>> {
    cells
        .iter()
        .map(|&(i, j)| {
            let (x, y) = (i * (size + gap), j * (size + gap));
            vec![
                pt(x, y),
                pt(x + size, y),
                pt(x + size, y + size),
                pt(x, y + size),
            ]
        })
        .collect()
}

#[test]
fn empty_scene_has_one_cylinder() {
    let s = scene(&[]);
    let c = build_by_sweep(&s.as_ref()).unwrap();
    assert_eq!(c.cylinders().len(), 1);
    assert_eq!(c.faces(), 1);
    c.validate(&s.as_ref()).unwrap();
}

#[test]
fn one_triangle_has_four_faces() {
    let s = scene(&[vec![pt(0, 0), pt(4, 0), pt(0, 3)]]);
    let c = build_by_sweep(&s.as_ref()).unwrap();
    c.validate(&s.as_ref()).unwrap();
    assert_eq!(c.free_bitangents(), 0);
    // (sky, sky) below and above the sheet, (sky, T) and (T, sky) inside it.
    assert_eq!(c.cylinders().len(), 4);
    assert_eq!(c.faces(), 4);
}

#[test]
fn two_triangles() {
    let s = scene(&[
        vec![pt(0, 0), pt(4, 0), pt(0, 3)],
        vec![pt(10, 1), pt(14, 2), pt(11, 5)],
    ]);
    let c = build_by_sweep(&s.as_ref()).unwrap();
    c.validate(&s.as_ref()).unwrap();
    assert_eq!(c.free_bitangents(), 4);
}

#[test]
fn collinear_lattice_of_boxes_validates() {
    let cells: Vec<(i32, i32)> = (0..4).flat_map(|i| (0..4).map(move |j| (i, j))).collect();
    let s = scene(&boxes(&cells, 2, 1));
    let c = build_by_sweep(&s.as_ref()).unwrap();
    c.validate(&s.as_ref()).unwrap();
    assert!(c.free_bitangents() > 0);
}

#[test]
fn generated_scenes_validate() {
    for (kind, n) in [
        (SceneKind::Grid, 16),
        (SceneKind::Grid, 64),
        (SceneKind::Hall, 8),
        (SceneKind::Mixed, 20),
    ] {
        for seed in 0..3 {
            let f = generate(kind, n, seed).unwrap();
            let s = f.scene.as_ref();
            let c = build_by_sweep(&s).unwrap();
            c.validate(&s)
                .unwrap_or_else(|e| panic!("{kind:?} {n} {seed}: {e}"));
        }
    }
}

/// Directions all around the circle, including the axes and diagonals where axis-aligned
/// scenes are degenerate (the perturbation decides there).
fn sample_directions() -> Vec<vcx::geom::sos::Angle> {
    use vcx::geom::predicates::Direction;
    let mut out = Vec::new();
    for (x, y) in [
        (1, 0),
        (1, 1),
        (0, 1),
        (-1, 1),
        (-1, 0),
        (-1, -1),
        (0, -1),
        (1, -1),
    ] {
        out.push(vcx::geom::sos::Angle::constant(
            Direction::new(x, y).unwrap(),
        ));
    }
    for k in 0..200i64 {
        let x = 1000 - (k * 7919) % 2001;
        let y = 1000 - (k * 104729) % 2001;
        if let Some(d) = Direction::new(x, y) {
            out.push(vcx::geom::sos::Angle::constant(d));
        }
    }
    out
}

#[test]
fn cylinders_crossing_any_direction_are_the_cross_section() {
    let mut scenes: Vec<Scene> = Vec::new();
    let cells: Vec<(i32, i32)> = (0..4).flat_map(|i| (0..3).map(move |j| (i, j))).collect();
    scenes.push(scene(&boxes(&cells, 2, 1)));
    scenes.push(scene(&[
        vec![pt(0, 0), pt(4, 0), pt(0, 3)],
        vec![pt(10, 1), pt(14, 2), pt(11, 5)],
    ]));
    for (kind, n, seed) in [
        (SceneKind::Grid, 25, 1),
        (SceneKind::Mixed, 15, 2),
        (SceneKind::Hall, 6, 3),
    ] {
        scenes.push(generate(kind, n, seed).unwrap().scene);
    }
    for s in &scenes {
        let s = s.as_ref();
        let c = build_by_sweep(&s).unwrap();
        c.validate(&s).unwrap();
        for a in sample_directions() {
            c.validate_at(&s, &a)
                .unwrap_or_else(|e| panic!("{e} at {a:?}"));
        }
    }
}

mod against_reference {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use vcx::geom::predicates::Direction;
    use vcx::geom::sos::{self, RankedPoint};
    use vcx::partition::Location;
    use vcx::QueryPoint;
    use vcx_tests::reference::{free_bitangents, shoot_perturbed, sos_orient, Vec2};

    /// Scale of the randomized checks: `VCX_LONG=1` multiplies it by 20.
    fn scale(n: usize) -> usize {
        if std::env::var_os("VCX_LONG").is_some() {
            n * 20
        } else {
            n
        }
    }

    fn families() -> Vec<(String, Scene)> {
        let mut out = Vec::new();
        for (n, seed) in [(9, 1), (25, 2), (49, 3), (100, 4)] {
            out.push((
                format!("grid {n}"),
                generate(SceneKind::Grid, n, seed).unwrap().scene,
            ));
        }
        out.push((
            "mixed 20".into(),
            generate(SceneKind::Mixed, 20, 5).unwrap().scene,
        ));
        out.push((
            "hall 6".into(),
            generate(SceneKind::Hall, 6, 6).unwrap().scene,
        ));
        // Collinear lattices: shared supporting lines everywhere.
        let cells: Vec<(i32, i32)> = (0..4).flat_map(|i| (0..4).map(move |j| (i, j))).collect();
        out.push(("lattice 4x4".into(), scene(&boxes(&cells, 2, 1))));
        let row: Vec<(i32, i32)> = (0..6).map(|i| (i, 0)).collect();
        out.push(("row of 6".into(), scene(&boxes(&row, 3, 1))));
        // Near-touching pairs: one grid unit (2^-16) apart.
        let t = |x: i32, y: i32| Point::from_raw(x, y).unwrap();
        let u = 1 << 16;
        out.push((
            "near-touching".into(),
            Scene::new(
                [
                    vec![t(0, 0), t(4 * u, 0), t(4 * u, 4 * u), t(0, 4 * u)],
                    vec![
                        t(4 * u + 1, 0),
                        t(8 * u, 0),
                        t(8 * u, 4 * u),
                        t(4 * u + 1, 4 * u),
                    ],
                    vec![t(0, 4 * u + 1), t(4 * u, 4 * u + 1), t(2 * u, 6 * u)],
                ]
                .iter()
                .map(|p| (Material::Opaque, &p[..])),
            )
            .unwrap(),
        ));
        out
    }

    #[test]
    fn free_bitangents_match_the_reference() {
        for (name, s) in families() {
            let s = s.as_ref();
            let c = build_by_sweep(&s).unwrap();
            c.validate(&s).unwrap();
            let want = free_bitangents(s);
            assert_eq!(c.free_bitangents(), want.undirected, "{name}");
            assert_eq!(c.vertices().len(), want.directed, "{name}");
        }
    }

    /// The core's perturbed orientation equals the reference's symbolic expansion on the
    /// vertices of a collinear lattice (most triples are degenerate there).
    #[test]
    fn perturbed_orientation_matches_the_reference() {
        let cells: Vec<(i32, i32)> = (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).collect();
        let s = scene(&boxes(&cells, 2, 2));
        let v = s.as_ref().vertices();
        for i in 0..v.len() {
            for j in 0..v.len() {
                for k in 0..v.len() {
                    if i == j || j == k || i == k {
                        continue;
                    }
                    let core = sos::orient(
                        RankedPoint::vertex(v[i], i),
                        RankedPoint::vertex(v[j], j),
                        RankedPoint::vertex(v[k], k),
                    );
                    let (a, b, c) = (
                        Vec2::from_point(v[i]),
                        Vec2::from_point(v[j]),
                        Vec2::from_point(v[k]),
                    );
                    let r = sos_orient((i as u64 + 1, &a), (j as u64 + 1, &b), (k as u64 + 1, &c));
                    assert_eq!(core, r, "{i} {j} {k}");
                }
            }
        }
    }

    /// Random rays from free points: forward and backward objects of the located cylinder
    /// agree with exact ray shooting (q perturbed to q + (ε, ε²), as in the core) — for the
    /// brute-force `Complex::locate`, the history's `locate`, and the history's
    /// sheet-anchored `locate_on_sheet` of the backward object from the same point and from
    /// virtual points moved back along the ray (behind or inside that object: the same
    /// perturbed line, so the same segment); both history locates also on the history built
    /// without search path compaction, on the same rays. Origins and directions are drawn to hit
    /// degeneracies: vertices, edge extensions, bitangents. 16 000 rays per family, over
    /// 10⁵ from free points in all.
    #[test]
    fn locate_matches_ray_shooting() {
        use vcx::partition::{BuildOptions, History};
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (mut checked, mut on_sheet) = (0usize, 0usize);
        let families = families();
        for (name, s) in &families {
            let s = s.as_ref();
            let c = build_by_sweep(&s).unwrap();
            let h = History::build(
                &s,
                &BuildOptions {
                    seed: checked as u64,
                    ..Default::default()
                },
            )
            .unwrap();
            h.validate(&s).unwrap();
            // The same without search path compaction (§4.4): judged on the same rays.
            let hu = History::build(
                &s,
                &BuildOptions {
                    seed: checked as u64,
                    compaction: false,
                    ..Default::default()
                },
            )
            .unwrap();
            hu.validate(&s).unwrap();
            let v = s.vertices();
            let (mut lo, mut hi) = ((i32::MAX, i32::MAX), (i32::MIN, i32::MIN));
            for p in v {
                lo = (lo.0.min(p.x()), lo.1.min(p.y()));
                hi = (hi.0.max(p.x()), hi.1.max(p.y()));
            }
            let rays = scale(16_000);
            for ray in 0..rays {
                let kind = rng.gen_range(0..4);
                let (a, b) = (v[rng.gen_range(0..v.len())], v[rng.gen_range(0..v.len())]);
                let (q, d) = match kind {
                    // Through two vertices: from a point on the line a-b beyond a.
                    0 if a != b => {
                        let (dx, dy) = (b.x() as i64 - a.x() as i64, b.y() as i64 - a.y() as i64);
                        let k = rng.gen_range(-3i64..=3);
                        let q = QueryPoint::from_raw(
                            (a.x() as i64 + k * dx) << 16,
                            (a.y() as i64 + k * dy) << 16,
                        );
                        (q, Direction::new(dx, dy))
                    }
                    // Axis-aligned rays through grid points (floor-plan degeneracies).
                    1 => {
                        let q = QueryPoint::from_raw(
                            (rng.gen_range(lo.0 - 65536..=hi.0 + 65536) as i64 & !0xffff) << 16,
                            (rng.gen_range(lo.1 - 65536..=hi.1 + 65536) as i64 & !0xffff) << 16,
                        );
                        let d = [(1, 0), (0, 1), (-1, 0), (0, -1)][rng.gen_range(0..4)];
                        (q, Direction::new(d.0, d.1))
                    }
                    // Aimed at a vertex from a random point.
                    2 => {
                        let q = (
                            rng.gen_range(lo.0..=hi.0) as i64,
                            rng.gen_range(lo.1..=hi.1) as i64,
                        );
                        (
                            QueryPoint::from_raw(q.0 << 16, q.1 << 16),
                            Direction::new(a.x() as i64 - q.0, a.y() as i64 - q.1),
                        )
                    }
                    _ => {
                        let q = QueryPoint::from_raw(
                            rng.gen_range(lo.0 as i64..=hi.0 as i64) << 16,
                            rng.gen_range(lo.1 as i64..=hi.1 as i64) << 16,
                        );
                        (
                            q,
                            Direction::new(
                                rng.gen_range(-1000..=1000),
                                rng.gen_range(-1000..=1000),
                            ),
                        )
                    }
                };
                let (Some(q), Some(d)) = (q, d) else { continue };
                let rq = Vec2::from_query(q);
                let rd = Vec2::from_i64(d.x, d.y);
                // The brute-force locate scans every cylinder: judge it on a quarter of
                // the rays, the history on all.
                let brute = (ray % 4 == 0).then(|| c.locate(&s, q, d));
                match (brute, shoot_perturbed(s, &rq, &rd)) {
                    (None | Some(Some(Location::Free { .. })), Ok(want)) => {
                        let wanted = (want.forward, want.backward);
                        if let Some(Some(Location::Free { cylinder })) = brute {
                            let cyl = c.cylinder(cylinder).unwrap();
                            assert_eq!((cyl.ceiling, cyl.floor), wanted, "{name}: {q:?} {d:?}");
                        }
                        let (_, hc) = h.locate(&s, q, d).expect("history locate");
                        assert_eq!(
                            (hc.ceiling, hc.floor),
                            wanted,
                            "history: {name} {q:?} {d:?}"
                        );
                        let (_, uc) = hu.locate(&s, q, d).expect("uncompacted locate");
                        assert_eq!(
                            (uc.ceiling, uc.floor),
                            wanted,
                            "uncompacted history: {name} {q:?} {d:?}"
                        );
                        if let Some(m) = want.backward {
                            // Virtual eyes k·d/256 behind q on the same line.
                            let k = rng.gen_range(0i64..=64);
                            let back =
                                QueryPoint::from_raw(q.x() - k * d.x * 256, q.y() - k * d.y * 256);
                            for e in [Some(q), back].into_iter().flatten() {
                                let (_, sc) = h
                                    .locate_on_sheet(&s, m, e, d)
                                    .unwrap_or_else(|| panic!("sheet: {name} {e:?} {d:?}"));
                                assert_eq!(
                                    (sc.ceiling, sc.floor),
                                    wanted,
                                    "sheet of {m:?}: {name} eye {e:?} (q {q:?}) d {d:?}"
                                );
                                let (_, su) =
                                    hu.locate_on_sheet(&s, m, e, d).unwrap_or_else(|| {
                                        panic!("uncompacted sheet: {name} {e:?} {d:?}")
                                    });
                                assert_eq!(
                                    (su.ceiling, su.floor),
                                    wanted,
                                    "uncompacted, sheet of {m:?}: {name} eye {e:?} d {d:?}"
                                );
                                on_sheet += 1;
                            }
                        }
                        checked += 1;
                    }
                    (
                        None | Some(Some(Location::Inside { .. } | Location::OnBoundary { .. })),
                        Err(_),
                    ) => {}
                    (got, want) => {
                        panic!("{name}: q {q:?} d {d:?}: core {got:?}, reference {want:?}")
                    }
                }
            }
        }
        assert!(
            checked > scale(100_000),
            "too few free rays: {checked} of {}",
            families.len() * scale(16_000)
        );
        assert!(on_sheet > scale(50_000), "too few sheet rays: {on_sheet}");
        println!("{checked} rays, {on_sheet} sheet-anchored");
    }
}

mod views {
    use super::*;

    /// Viewpoints per scene: `VCX_LONG=1` multiplies them by 20.
    fn scale_views(n: usize) -> usize {
        if std::env::var_os("VCX_LONG").is_some() {
            n * 20
        } else {
            n
        }
    }
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use vcx::walk::view;
    use vcx::QueryPoint;
    use vcx_tests::reference::{self, Vec2};

    /// (object, vertex id as written) of a global vertex index.
    fn written(s: &vcx::SceneRef<'_>, k: usize) -> (u32, usize) {
        for (i, o) in s.objects().iter().enumerate() {
            if (o.first_vertex()..o.first_vertex() + o.len()).contains(&k) {
                return (i as u32, o.written_vertex_id(k - o.first_vertex()));
            }
        }
        panic!("vertex {k} out of range")
    }

    fn same_direction(v: (i128, i128), r: &Vec2) -> bool {
        let d = Vec2::from_i64(v.0 as i64, v.1 as i64);
        use num_traits::{Signed, Zero};
        d.cross(r).is_zero() && d.dot(r).is_positive()
    }

    /// Compares the walked view with the reference; returns false if the viewpoint is not free.
    fn check(
        name: &str,
        s: &vcx::SceneRef<'_>,
        c: &vcx::partition::Complex,
        q: QueryPoint,
    ) -> bool {
        let want = reference::view(*s, &Vec2::from_query(q));
        let got = view(c, s, q);
        let (want, got) = match (want, got) {
            (Err(_), Err(_)) => return false,
            (Ok(w), Ok(g)) => (w, g),
            (w, g) => panic!("{name} q {q:?}: reference {w:?}, core {g:?}"),
        };
        let show = || format!("{name} q {q:?}\n core {got:#?}\n reference {want:#?}");
        assert_eq!(got.len(), want.len(), "{}", show());
        for (g, w) in got.iter().zip(&want) {
            assert_eq!(g.object, w.value, "{}", show());
            if w.start_vertex.is_some() {
                assert!(same_direction(g.start.vector(), &w.start), "{}", show());
            }
            let gv = g.start_vertex.map(|k| written(s, k));
            let wv = w.start_vertex.map(|v| (v.object.0, v.vertex));
            assert_eq!(gv, wv, "{}", show());
        }
        true
    }

    #[test]
    fn views_match_the_reference() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut scenes: Vec<(String, Scene)> = Vec::new();
        for (n, seed) in [(9, 1), (25, 2), (64, 3)] {
            scenes.push((
                format!("grid {n}"),
                generate(SceneKind::Grid, n, seed).unwrap().scene,
            ));
        }
        let cells: Vec<(i32, i32)> = (0..4).flat_map(|i| (0..4).map(move |j| (i, j))).collect();
        scenes.push(("lattice".into(), scene(&boxes(&cells, 2, 2))));
        let mut checked = 0;
        for (name, s) in &scenes {
            let s = s.as_ref();
            let c = build_by_sweep(&s).unwrap();
            let v = s.vertices();
            let (lo, hi) = v.iter().fold(
                ((i32::MAX, i32::MAX), (i32::MIN, i32::MIN)),
                |(lo, hi), p| {
                    (
                        (lo.0.min(p.x()), lo.1.min(p.y())),
                        (hi.0.max(p.x()), hi.1.max(p.y())),
                    )
                },
            );
            for k in 0..scale_views(90) {
                let q = match k % 3 {
                    // Random points.
                    0 => QueryPoint::from_raw(
                        (rng.gen_range(lo.0 - 65536..=hi.0 + 65536) as i64) << 16,
                        (rng.gen_range(lo.1 - 65536..=hi.1 + 65536) as i64) << 16,
                    ),
                    // On the line through two vertices (edge extensions, bitangents).
                    1 => {
                        let (a, b) = (v[rng.gen_range(0..v.len())], v[rng.gen_range(0..v.len())]);
                        let t = rng.gen_range(-2i64..=3);
                        QueryPoint::from_raw(
                            (a.x() as i64 + t * (b.x() as i64 - a.x() as i64)) << 16,
                            (a.y() as i64 + t * (b.y() as i64 - a.y() as i64)) << 16,
                        )
                    }
                    // Grid points: axis-aligned degeneracies.
                    _ => QueryPoint::from_raw(
                        (rng.gen_range(lo.0..=hi.0) as i64 & !0xffff) << 16,
                        (rng.gen_range(lo.1..=hi.1) as i64 & !0xffff) << 16,
                    ),
                };
                if let Some(q) = q {
                    checked += usize::from(check(name, &s, &c, q));
                }
            }
        }
        assert!(checked > scale_views(90) * 3, "{checked}");
    }
}

/// Crossing a chain from a cylinder (`across_from`, which scans from a precomputed start)
/// finds the same cylinder as the search over the whole chain (`across`).
#[test]
fn across_from_a_cylinder_agrees_with_the_chain_search() {
    use vcx::partition::{Layer, Side};
    let mut checked = 0;
    for (kind, n, seed) in [
        (SceneKind::Grid, 25, 1),
        (SceneKind::Mixed, 15, 2),
        (SceneKind::Hall, 6, 3),
    ] {
        let f = generate(kind, n, seed).unwrap();
        let s = f.scene.as_ref();
        let c = build_by_sweep(&s).unwrap();
        for a in sample_directions().iter().take(60) {
            for (id, cyl) in c.cylinders_at(&s, a) {
                for (chain, side) in [(cyl.bottom, Side::Below), (cyl.top, Side::Above)] {
                    let Some(chain) = chain else { continue };
                    for layer in [Layer::Around, Layer::Before, Layer::After] {
                        let want = c.across(&s, chain, side, layer, a);
                        let got = c.across_from(&s, id, side, layer, a);
                        if want.is_some() {
                            assert_eq!(got, want, "{kind:?} cylinder {id:?} {side:?} {layer:?}");
                            checked += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(checked > 1000, "{checked}");
}
