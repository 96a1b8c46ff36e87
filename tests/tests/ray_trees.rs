//! Ray trees (`vcx::walk::ray_tree`) against the exact reference with rounded eyes, the
//! exact rounding of virtual eyes against big rationals, and the tangent law's error table.
//!
//! `VCX_LONG=1` multiplies the number of viewpoints.

use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::Signed;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use vcx::partition::{build_by_sweep, Complex};
use vcx::walk::{optics, ray_tree, view, TreeInterval, WalkError};
use vcx::{Eta, Material, ObjectId, Point, QueryPoint, Scene, SceneRef, SubScene};
use vcx_demo::generate::{generate, SceneKind};
use vcx_tests::reference::{self, RayTreeOptions, RefError, Vec2};

mod common;
use common::random_point;

/// A hand-made object: its material and vertices.
type Polygon = (Material, Vec<Point>);

fn scale(n: usize) -> usize {
    if std::env::var_os("VCX_LONG").is_some() {
        n * 20
    } else {
        n
    }
}

/// (object, vertex id as written) of a global vertex index.
fn written(s: &SceneRef<'_>, k: usize) -> (u32, usize) {
    for (i, o) in s.objects().iter().enumerate() {
        if (o.first_vertex()..o.first_vertex() + o.len()).contains(&k) {
            return (i as u32, o.written_vertex_id(k - o.first_vertex()));
        }
    }
    panic!("vertex {k} out of range")
}

fn angle_close(a: f64, b: f64) -> bool {
    let tau = core::f64::consts::TAU;
    let d = (a - b).rem_euclid(tau);
    d.min(tau - d) < 1e-9
}

/// Outcome of one comparison.
#[derive(PartialEq, Eq, Debug)]
enum Checked {
    Compared,
    NotFree,
    Degenerate,
}

/// Compares the core's ray tree with the reference's (rounded eyes).
fn check(name: &str, s: &SceneRef<'_>, c: &Complex, q: QueryPoint, depth: usize) -> Checked {
    let want = reference::ray_tree(
        *s,
        &Vec2::from_query(q),
        RayTreeOptions {
            depth,
            round_eyes: true,
        },
    );
    let got = ray_tree(c, s, q, depth);
    let (want, got) = match (want, got) {
        (Err(RefError::ViewpointNotFree { .. }), Err(WalkError::NotFree(_))) => {
            return Checked::NotFree
        }
        (Err(RefError::DegenerateOptics { .. }), _) => return Checked::Degenerate,
        (Ok(w), Ok(g)) => (w, g),
        (w, g) => panic!("{name} q {q:?} depth {depth}: reference {w:?}, core {g:?}"),
    };
    let show = || {
        let g: Vec<_> = got
            .iter()
            .map(|i| (i.start, &i.branch, i.start_vertex.map(|k| written(s, k))))
            .collect();
        let w: Vec<_> = want
            .iter()
            .map(|i| {
                (
                    i.start_angle,
                    &i.value,
                    i.start_vertex.map(|v| (v.object.0, v.vertex)),
                )
            })
            .collect();
        format!("{name} q {q:?} depth {depth}\n core {g:?}\n reference {w:?}")
    };
    assert_eq!(got.len(), want.len(), "{}", show());
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g.branch, w.value, "{}", show());
        let gv = g.start_vertex.map(|k| written(s, k));
        let wv = w.start_vertex.map(|v| (v.object.0, v.vertex));
        assert_eq!(gv, wv, "{}", show());
        if w.start_vertex.is_some() {
            assert!(angle_close(g.start, w.start_angle), "{}", show());
        }
    }
    Checked::Compared
}

fn pt(x: i32, y: i32) -> Point {
    Point::from_raw(x << 16, y << 16).unwrap()
}

fn rect(x0: i32, y0: i32, x1: i32, y1: i32) -> Vec<Point> {
    vec![pt(x0, y0), pt(x1, y0), pt(x1, y1), pt(x0, y1)]
}

fn run(name: &str, s: &Scene, depths: &[usize], points: usize, seed: u64) -> usize {
    let s = s.as_ref();
    let c = build_by_sweep(&s).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut compared = 0;
    for _ in 0..points {
        let q = random_point(&mut rng, &s);
        for &d in depths {
            if check(name, &s, &c, q, d) == Checked::Compared {
                compared += 1;
            }
        }
    }
    compared
}

#[test]
fn depth_zero_is_the_view() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for (n, seed) in [(9, 1), (30, 2)] {
        let s = generate(SceneKind::Grid, n, seed).unwrap().scene;
        let s = s.as_ref();
        let c = build_by_sweep(&s).unwrap();
        for _ in 0..scale(20) {
            let q = random_point(&mut rng, &s);
            let (Ok(t), Ok(v)) = (ray_tree(&c, &s, q, 0), view(&c, &s, q)) else {
                continue;
            };
            assert_eq!(t.len(), v.len());
            for (t, v) in t.iter().zip(&v) {
                assert_eq!(t.branch.first().copied(), v.object);
                assert_eq!(t.start_vertex, v.start_vertex);
                if v.start_vertex.is_some() {
                    assert_eq!(t.start, v.start.radians());
                }
            }
        }
    }
}

#[test]
fn hand_made_scenes_match_the_reference() {
    let eta = Eta::from_f64(1.5).unwrap();
    let scenes: Vec<(&str, Vec<Polygon>)> = vec![
        (
            "one mirror",
            vec![
                (Material::Mirror, rect(0, 0, 10, 1)),
                (Material::Opaque, rect(3, 5, 4, 6)),
            ],
        ),
        (
            "two facing mirrors",
            vec![
                (Material::Mirror, rect(0, 0, 10, 1)),
                (Material::Mirror, rect(0, 8, 10, 9)),
                (Material::Opaque, rect(12, 3, 13, 5)),
            ],
        ),
        (
            "slab",
            vec![
                (Material::Refractive { eta }, rect(0, 0, 10, 2)),
                (Material::Opaque, rect(2, -6, 5, -5)),
                (Material::Opaque, rect(-4, 6, -3, 7)),
            ],
        ),
        (
            "screen",
            vec![
                (Material::Screen, rect(0, 0, 6, 1)),
                (Material::Opaque, rect(2, -5, 3, -4)),
                (Material::Mirror, rect(-3, 4, 5, 5)),
            ],
        ),
    ];
    for (name, objs) in &scenes {
        let s = Scene::new(objs.iter().map(|(m, p)| (*m, &p[..]))).unwrap();
        let compared = run(name, &s, &[0, 1, 2, 3], scale(15), 3);
        assert!(compared > 0, "{name}");
    }
}

fn long() -> bool {
    std::env::var_os("VCX_LONG").is_some()
}

// The reference costs ~0.3 s per hall-of-mirrors tree at depth 1 and ~10 s at depth 5
// (big rationals, release-like test profile), the core well under 10 ms: the default run
// checks a few viewpoints per depth; `VCX_LONG=1` more and larger scenes, sized to finish
// in about 10 minutes (30 viewpoints per larger hall did not finish in 25).

#[test]
fn hall_of_mirrors_matches_the_reference() {
    let mut compared = 0;
    let s = generate(SceneKind::Hall, 2, 1).unwrap().scene;
    compared += run("hall 2/1", &s, &[1, 2, 3], scale(3), 1);
    compared += run("hall 2/1", &s, &[5], if long() { 6 } else { 1 }, 2);
    if long() {
        for (n, seed) in [(5, 2), (8, 3)] {
            let s = generate(SceneKind::Hall, n, seed).unwrap().scene;
            compared += run(&format!("hall {n}/{seed}"), &s, &[1, 2, 3, 4, 5], 6, seed);
        }
    }
    assert!(compared >= 4, "{compared}");
}

#[test]
fn mixed_scenes_match_the_reference() {
    let mut compared = 0;
    let s = generate(SceneKind::Mixed, 8, 1).unwrap().scene;
    compared += run("mixed 8/1", &s, &[1, 5], scale(8), 1);
    if long() {
        let s = generate(SceneKind::Mixed, 6, 7).unwrap().scene;
        compared += run("mixed 6/7", &s, &[2, 5], 100, 7);
        let s = generate(SceneKind::Mixed, 12, 4).unwrap().scene;
        compared += run("mixed 12/4", &s, &[1, 2, 3, 4, 5], 40, 4);
    }
    assert!(compared > 10, "{compared}");
}

#[test]
fn screens_never_change_a_ray_tree() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut compared = 0;
    for (n, seed) in [(10, 3), (16, 5)] {
        let whole = generate(SceneKind::Mixed, n, seed).unwrap().scene;
        let whole = whole.as_ref();
        let kept: Vec<ObjectId> = (0..whole.len() as u32)
            .map(ObjectId)
            .filter(|&id| whole.object(id).unwrap().material != Material::Screen)
            .collect();
        assert!(kept.len() < whole.len(), "the scene has screens");
        let sub = SubScene::new(whole, kept);
        let part = sub.as_ref();
        let (cw, cp) = (
            build_by_sweep(&whole).unwrap(),
            build_by_sweep(&part).unwrap(),
        );
        for _ in 0..scale(40) {
            let q = random_point(&mut rng, &whole);
            for depth in [0, 2, 5] {
                let (Ok(a), Ok(b)) = (
                    ray_tree(&cw, &whole, q, depth),
                    ray_tree(&cp, &part, q, depth),
                ) else {
                    continue;
                };
                let map = |t: &[TreeInterval], orig: &dyn Fn(ObjectId) -> ObjectId| {
                    t.iter()
                        .map(|i| {
                            (
                                i.branch.iter().map(|&o| orig(o)).collect::<Vec<_>>(),
                                i.start_vertex,
                            )
                        })
                        .collect::<Vec<_>>()
                };
                let ma = map(&a, &|o| o);
                let mb = map(&b, &|o| sub.original(o).unwrap());
                assert_eq!(ma, mb, "q {q:?} depth {depth}");
                for (x, y) in a.iter().zip(&b) {
                    assert!(angle_close(x.start, y.start), "q {q:?} depth {depth}");
                }
                compared += 1;
            }
        }
    }
    assert!(compared > 20, "{compared}");
}

// ---------------------------------------------------------------------------------------
// Exact rounding of virtual eyes.

fn big(v: i64) -> BigRational {
    BigRational::from_integer(BigInt::from(v))
}

/// `F + k(E − F)` rounded to the query grid, by big rationals (raw query units).
fn eye_exact(e: QueryPoint, a: Point, b: Point, k: &BigRational) -> (BigInt, BigInt) {
    let s = big(1 << 16);
    let (ex, ey) = (big(e.x()), big(e.y()));
    let (ax, ay) = (big(a.x().into()) * &s, big(a.y().into()) * &s);
    let (bx, by) = (big(b.x().into()) * &s, big(b.y().into()) * &s);
    let (dx, dy) = (&bx - &ax, &by - &ay);
    let t = ((&ex - &ax) * &dx + (&ey - &ay) * &dy) / (&dx * &dx + &dy * &dy);
    let (fx, fy) = (&ax + &t * &dx, &ay + &t * &dy);
    let nx = &fx + k * (&ex - &fx);
    let ny = &fy + k * (&ey - &fy);
    (nx.round().to_integer(), ny.round().to_integer())
}

fn check_eye(e: QueryPoint, a: Point, b: Point, kn: i64, kd: i64) {
    let k = BigRational::new(kn.into(), kd.into());
    let (x, y) = eye_exact(e, a, b, &k);
    let lim = BigInt::from(1i64 << 52);
    let got = optics::transform_eye(e, a, b, kn, kd);
    if x.abs() > lim || y.abs() > lim {
        assert_eq!(got, None, "{e:?} {a:?} {b:?} {kn}/{kd}");
    } else {
        let g = got.unwrap_or_else(|| panic!("{e:?} {a:?} {b:?} {kn}/{kd}"));
        assert_eq!(
            (BigInt::from(g.x()), BigInt::from(g.y())),
            (x, y),
            "{e:?} {a:?} {b:?} {kn}/{kd}"
        );
    }
}

#[test]
fn virtual_eyes_round_exactly_at_the_extremes() {
    let m = (1i32 << 30) - 1;
    let qm = 1i64 << 52;
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let ks = [
        (-1i64, 1i64),
        (1 << 22, 1 << 16),
        (1 << 16, 1 << 22),
        (1 << 10, 1 << 16),
        (1 << 16, 1 << 10),
        (98304, 65536),
        (65536, 87163),
        // A last quotient of 4 and more, or negative (the division after the comparisons).
        (229376, 65536),
        (-98304, 65536),
    ];
    let corners = [-m, -m + 1, -1, 0, 1, m - 1, m];
    let qcorners = [-qm, -qm + 1, -1, 0, 1, qm - 1, qm];
    // Extremes.
    for &ax in &corners {
        for &by in &corners {
            let (a, b) = (
                Point::from_raw(ax, -m).unwrap(),
                Point::from_raw(-ax, by).unwrap(),
            );
            if a == b {
                continue;
            }
            for &ex in &qcorners {
                for &ey in &[-qm, 3, qm] {
                    let e = QueryPoint::from_raw(ex, ey).unwrap();
                    for &(kn, kd) in &ks {
                        check_eye(e, a, b, kn, kd);
                    }
                }
            }
        }
    }
    // Random, including tiny edges (N = 1) and half-way cases near the grid.
    for i in 0..scale(4000) {
        let r = |rng: &mut ChaCha8Rng| rng.gen_range(-m..=m);
        let a = Point::from_raw(r(&mut rng), r(&mut rng)).unwrap();
        let b = if i % 3 == 0 {
            Point::from_raw(
                a.x() + rng.gen_range(-1..=1).max(if a.x() < m { 1 } else { -1 }),
                a.y(),
            )
            .unwrap()
        } else {
            Point::from_raw(r(&mut rng), r(&mut rng)).unwrap()
        };
        if a == b {
            continue;
        }
        let e = QueryPoint::from_raw(rng.gen_range(-qm..=qm), rng.gen_range(-qm..=qm)).unwrap();
        let (kn, kd) = ks[i % ks.len()];
        check_eye(e, a, b, kn, kd);
        // Small coordinates, where exact halves occur.
        let e = QueryPoint::from_raw(rng.gen_range(-64..=64), rng.gen_range(-64..=64)).unwrap();
        let a = Point::from_raw(rng.gen_range(-4..=4), rng.gen_range(-4..=4)).unwrap();
        let b = Point::from_raw(rng.gen_range(-4..=4), rng.gen_range(-4..=4)).unwrap();
        if a != b {
            check_eye(e, a, b, kn, kd);
        }
    }
}

// ---------------------------------------------------------------------------------------
// The tangent law against Snell's law (output only: f64).

#[test]
fn tangent_law_error_table() {
    println!("incidence θ1 [deg] | η | Snell θ2 [deg] | tangent law θ2 [deg] | error [deg]");
    let mut worst: f64 = 0.0;
    for eta in [1.33f64, 1.5, 1.6] {
        for deg in [
            0.0f64, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 85.0, 89.0,
        ] {
            let t1 = deg.to_radians();
            let snell = (t1.sin() / eta).asin();
            let tangent = (t1.tan() / eta).atan();
            let err = (tangent - snell).to_degrees();
            worst = worst.max(err.abs());
            println!(
                "{deg:5.1} | {eta:.2} | {:8.3} | {:8.3} | {err:+8.3}",
                snell.to_degrees(),
                tangent.to_degrees()
            );
        }
    }
    // Sanity: the laws agree at normal incidence and the tangent law bends more at grazing.
    assert!(worst > 10.0 && worst < 60.0, "{worst}");
}

/// Ray trees walk any storage: over caller slices (`Complex::as_slices`, as a complex
/// decoded by `format::decode_into` is) they equal those over the owned complex, and a
/// complex loaded from the binary format (the randomized construction's numbering) gives
/// the same trees as the sweep's.
#[test]
fn ray_trees_over_slices_and_loaded_files_are_the_same() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let s = generate(SceneKind::Mixed, 10, 2).unwrap().scene;
    let s = s.as_ref();
    let c = build_by_sweep(&s).unwrap();
    let h = vcx::partition::History::build(&s, &Default::default()).unwrap();
    let bytes =
        vcx::format::encode(&s, &h.complex(&s).unwrap(), None, &Default::default()).unwrap();
    let loaded = vcx::format::decode(&bytes).unwrap().complex;
    let key = |t: &[TreeInterval]| {
        t.iter()
            .map(|i| (i.branch.clone(), i.start_vertex, i.start.to_bits()))
            .collect::<Vec<_>>()
    };
    let mut compared = 0;
    for _ in 0..scale(30) {
        let q = random_point(&mut rng, &s);
        for depth in [1, 3] {
            let Ok(owned) = ray_tree(&c, &s, q, depth) else {
                continue;
            };
            let slices = ray_tree(&c.as_slices(), &s, q, depth).unwrap();
            let from_file = ray_tree(&loaded, &s, q, depth).unwrap();
            assert_eq!(key(&owned), key(&slices), "q {q:?} depth {depth}");
            assert_eq!(key(&owned), key(&from_file), "q {q:?} depth {depth}");
            compared += 1;
        }
    }
    assert!(compared > 20, "{compared}");
}

/// `ray_tree_range` is exactly the restriction of the full tree (itself judged against the
/// reference above) to the range: ends at random directions, on exact primary boundaries
/// (the tree's own), along scene vertices, and the full circle. Deep boundaries carry
/// `f64` angles only: a range end within 10⁻⁹ rad of one is skipped as undecidable here.
#[test]
fn ray_tree_ranges_are_restrictions_of_the_full_tree() {
    use vcx::geom::predicates::Direction;
    use vcx_tests::generators::compare_tree_ranges;
    let mut rng = ChaCha8Rng::seed_from_u64(33);
    let (mut compared, mut on_boundary) = (0, 0);
    for (kind, n, seed) in [
        (SceneKind::Hall, 4, 1),
        (SceneKind::Mixed, 10, 2),
        (SceneKind::Mixed, 16, 5),
    ] {
        let s = generate(kind, n, seed).unwrap().scene;
        let s = s.as_ref();
        let c = build_by_sweep(&s).unwrap();
        for _ in 0..scale(12) {
            let q = random_point(&mut rng, &s);
            for depth in [1, 3, 5] {
                let Ok(full) = ray_tree(&c, &s, q, depth) else {
                    continue;
                };
                let exact: Vec<_> = full.iter().filter_map(|i| i.exact_start).collect();
                let mut ranges = Vec::new();
                for case in 0..6 {
                    let random = |rng: &mut ChaCha8Rng| loop {
                        let v = (
                            rng.gen_range(-1 << 20..1 << 20),
                            rng.gen_range(-1 << 20..1 << 20),
                        );
                        if let Some(d) = Direction::new(v.0, v.1) {
                            break d;
                        }
                    };
                    let toward = |rng: &mut ChaCha8Rng| {
                        let v = s.vertices()[rng.gen_range(0..s.vertices().len())].to_query();
                        Direction::new(v.x() - q.x(), v.y() - q.y())
                    };
                    let from = match case {
                        0 | 1 => Some(random(&mut rng)),
                        2 | 3 if !exact.is_empty() => {
                            let (x, y) = exact[rng.gen_range(0..exact.len())].vector();
                            Direction::new(x as i64, y as i64)
                        }
                        _ => toward(&mut rng),
                    };
                    let to = match case {
                        1 | 3 => from,
                        _ if rng.gen_bool(0.5) => toward(&mut rng),
                        _ => Some(random(&mut rng)),
                    };
                    let (Some(from), Some(to)) = (from, to) else {
                        continue;
                    };
                    let fa = vcx::geom::sos::Angle::constant(from);
                    if full.len() > 1
                        && full
                            .iter()
                            .any(|i| i.exact_start.is_some_and(|a| a.cmp_exact(&fa).is_eq()))
                    {
                        on_boundary += 1;
                    }
                    ranges.push((from, to));
                }
                let n = compare_tree_ranges(&s, &c, q, depth, &full, ranges)
                    .unwrap_or_else(|e| panic!("{e}\n full {full:?}"));
                compared += n;
            }
        }
    }
    eprintln!("ranges compared {compared}, starting on a boundary {on_boundary}");
    assert!(
        compared > 300 && on_boundary > 20,
        "{compared} {on_boundary}"
    );
}

/// The opt-in arc-vertex index (`Complex::with_arc_vertices`, which `vcx bench` and the demo
/// walk with) changes no walk: views, ray trees to depth 5 and ray trees over a field of view
/// equal those of the same complex without it, in full (exact angles included, through
/// `Debug`), on halls, mixed scenes and grids, from random viewpoints and from points on
/// lines through two vertices. The walks without it are judged by the reference above.
#[test]
fn arc_vertices_change_no_walk() {
    use vcx::geom::predicates::Direction;
    use vcx::walk::frame_tree;
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let mut compared = 0;
    for (kind, n, seed) in [
        (SceneKind::Hall, 5, 2),
        (SceneKind::Hall, 8, 3),
        (SceneKind::Mixed, 8, 1),
        (SceneKind::Mixed, 12, 4),
        (SceneKind::Grid, 64, 5),
    ] {
        let s = generate(kind, n, seed).unwrap().scene;
        let s = s.as_ref();
        let c = build_by_sweep(&s).unwrap();
        let arcs = c.clone().with_arc_vertices(&s);
        let v = s.vertices();
        for k in 0..scale(200) {
            let q = if k % 2 == 0 {
                Some(random_point(&mut rng, &s))
            } else {
                // On the line through two vertices (edge extensions, bitangents).
                let (a, b) = (v[rng.gen_range(0..v.len())], v[rng.gen_range(0..v.len())]);
                let t = rng.gen_range(-2i64..=3);
                QueryPoint::from_raw(
                    (a.x() as i64 + t * (b.x() as i64 - a.x() as i64)) << 16,
                    (a.y() as i64 + t * (b.y() as i64 - a.y() as i64)) << 16,
                )
            };
            let Some(q) = q else { continue };
            let same = |what: &str, plain: String, indexed: String| {
                assert_eq!(plain, indexed, "{kind:?} {n}/{seed} q {q:?}: {what}");
            };
            same(
                "view",
                format!("{:?}", view(&c, &s, q)),
                format!("{:?}", view(&arcs, &s, q)),
            );
            if view(&c, &s, q).is_err() {
                continue;
            }
            compared += 1;
            for depth in [0, 1, 3, 5] {
                same(
                    &format!("ray tree depth {depth}"),
                    format!("{:?}", ray_tree(&c, &s, q, depth)),
                    format!("{:?}", ray_tree(&arcs, &s, q, depth)),
                );
            }
            let (from, to) = (
                Direction::new(rng.gen_range(-9..=9), rng.gen_range(-9..=9)),
                Direction::new(rng.gen_range(-9..=9), rng.gen_range(-9..=9)),
            );
            if let (Some(from), Some(to)) = (from, to) {
                same(
                    "frame tree depth 5",
                    format!("{:?}", frame_tree(&c, &s, q, 5, from, to)),
                    format!("{:?}", frame_tree(&arcs, &s, q, 5, from, to)),
                );
            }
        }
    }
    assert!(compared > scale(200) * 3, "{compared}");
}
