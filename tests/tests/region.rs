//! `vcx build --region` (`vcx::partition::region`): a complex pruned to a box of viewpoints.
//! Views from viewpoints in the box — inside, on its edges and at its corners — walked in
//! the pruned complex equal the full complex's and the exact reference's, on random grid
//! scenes and random boxes and on the degenerate scenes of the fuzz generators; outside
//! the box they are a typed error; a walk that meets a missing link stops with an error;
//! the region files (version 4: the whole complex replayed and a kept map; version 2: the
//! kept cylinders stored) round-trip (both decoders), version 4 decodes to the pruned
//! complex of version 3, and their corrupt variants are typed errors, never panics.

mod common;

use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use vcx::format::{
    self, decode, decode_into, encode, encode_region, EncodeOptions, FormatError, Header,
};
use vcx::format::{SceneObject, Scratch, BLANK_CYLINDER, BLANK_VERTEX};
use vcx::geom::predicates::Direction;
use vcx::partition::{
    build_by_sweep, BorderSizes, Complex, ComplexError, Region, RegionError, Slices, ZERO_SLOTS,
};
use vcx::walk::{frame_tree, frame_tree_into, ray_tree, TreeInterval, TreeScratch};
use vcx::walk::{view, view_into, ViewInterval, WalkError};
use vcx::{Material, ObjectId, Point, QueryPoint, Scene, SceneRef, SubScene};
use vcx_demo::{generate, SceneKind};
use vcx_tests::generators::{compare_ray_tree, compare_view};

/// Scale of the randomized checks: `VCX_LONG=1` multiplies it by 20.
fn scale() -> usize {
    if std::env::var_os("VCX_LONG").is_some() {
        20
    } else {
        1
    }
}

/// Views as comparable tuples: exact start direction, object, boundary vertex.
type ViewKey = Vec<((i128, i128), Option<ObjectId>, Option<usize>)>;

fn view_key<S: vcx::partition::Storage>(
    c: &Complex<S>,
    s: &SceneRef<'_>,
    q: QueryPoint,
) -> Result<ViewKey, WalkError> {
    view(c, s, q).map(|v| {
        v.iter()
            .map(|i| (i.start.vector(), i.object, i.start_vertex))
            .collect()
    })
}

/// The scene's bounding box in raw scene units.
fn bbox(s: &SceneRef<'_>) -> (i32, i32, i32, i32) {
    let (mut x0, mut y0, mut x1, mut y1) = (i32::MAX, i32::MAX, i32::MIN, i32::MIN);
    for p in s.vertices() {
        (x0, y0, x1, y1) = (x0.min(p.x()), y0.min(p.y()), x1.max(p.x()), y1.max(p.y()));
    }
    (x0, y0, x1, y1)
}

fn region(x0: i32, y0: i32, x1: i32, y1: i32) -> Region {
    Region::new(
        Point::from_raw(x0, y0).unwrap(),
        Point::from_raw(x1, y1).unwrap(),
    )
    .unwrap()
}

/// A random box inside the scene's bounding box (a margin of one unit around it): any
/// size from a point to the whole, corners on the scene grid, often on whole units.
fn random_box(s: &SceneRef<'_>, rng: &mut ChaCha8Rng) -> Region {
    let (x0, y0, x1, y1) = bbox(s);
    let m = 1 << 16;
    let lim = vcx::geom::point::MAX_ABS_RAW;
    let mut pick = |lo: i32, hi: i32| {
        let v = rng.gen_range((lo - m).max(-lim)..=(hi + m).min(lim));
        if rng.gen_bool(0.5) {
            (v & !0xffff).max(-lim) // on a whole unit: on grid lines and vertices' rows
        } else {
            v
        }
    };
    let (a, b) = (pick(x0, x1), pick(x0, x1));
    let (c, d) = (pick(y0, y1), pick(y0, y1));
    region(a.min(b), c.min(d), a.max(b), c.max(d))
}

/// Viewpoints in the closed box: its corners, points on each edge, random inside points.
fn points_in(r: &Region, inside: usize, rng: &mut ChaCha8Rng) -> Vec<QueryPoint> {
    let (lo, hi) = (r.min().to_query(), r.max().to_query());
    let q = |x, y| QueryPoint::from_raw(x, y).unwrap();
    let mut out = vec![
        q(lo.x(), lo.y()),
        q(hi.x(), lo.y()),
        q(hi.x(), hi.y()),
        q(lo.x(), hi.y()),
    ];
    for _ in 0..2 {
        let (x, y) = (
            rng.gen_range(lo.x()..=hi.x()),
            rng.gen_range(lo.y()..=hi.y()),
        );
        out.extend([q(x, lo.y()), q(x, hi.y()), q(lo.x(), y), q(hi.x(), y)]);
    }
    for _ in 0..inside {
        out.push(q(
            rng.gen_range(lo.x()..=hi.x()),
            rng.gen_range(lo.y()..=hi.y()),
        ));
    }
    out
}

/// Points just outside the box (one query unit past each edge and corner) and far away.
fn points_outside(r: &Region) -> Vec<QueryPoint> {
    let (lo, hi) = (r.min().to_query(), r.max().to_query());
    let (mx, my) = (lo.x() / 2 + hi.x() / 2, lo.y() / 2 + hi.y() / 2);
    let q = |x, y| QueryPoint::from_raw(x, y).unwrap();
    vec![
        q(lo.x() - 1, my),
        q(hi.x() + 1, my),
        q(mx, lo.y() - 1),
        q(mx, hi.y() + 1),
        q(lo.x() - 1, lo.y() - 1),
        q(hi.x() + 1, hi.y() + 1),
        q(hi.x() + (1 << 40), my),
    ]
}

/// Prunes `c` to `r` and checks every viewpoint of `points` (pruned views equal the full
/// complex's; the first `reference` free ones also against the exact reference) and that
/// points outside are refused. Returns how many free viewpoints were compared.
fn check_box(
    s: &SceneRef<'_>,
    c: &Complex,
    r: Region,
    points: &[QueryPoint],
    reference: usize,
) -> usize {
    let p = c.prune_to_region(s, r).unwrap();
    p.validate(s)
        .unwrap_or_else(|e| panic!("pruned complex invalid: {e}"));
    assert_eq!(p.region(), Some(r));
    assert!(p.cylinders().len() <= c.cylinders().len());
    // The θ = 0 cylinders come first.
    let prefix = p
        .cylinders()
        .iter()
        .take_while(|c| c.left == vcx::partition::Wall::Zero)
        .count();
    assert!(p
        .cylinders()
        .iter()
        .skip(prefix)
        .all(|c| c.left != vcx::partition::Wall::Zero));
    let sub = SubScene::new(*s, (0..s.len() as u32).map(ObjectId));
    let mut compared = 0;
    for &q in points {
        assert!(r.contains(q));
        let full = view_key(c, s, q);
        let got = view_key(&p, s, q);
        match (&full, &got) {
            (Err(WalkError::NotFree(a)), Err(WalkError::NotFree(b))) => {
                assert_eq!(a, b);
                continue;
            }
            (Ok(f), Ok(g)) => assert_eq!(f, g, "view from {q:?} in box {r:?}"),
            _ => panic!("q {q:?} in {r:?}: full {full:?}, pruned {got:?}"),
        }
        if compared < reference {
            compare_view(s, &sub, &p, q).unwrap_or_else(|e| panic!("box {r:?}: {e}"));
        }
        compared += 1;
    }
    for q in points_outside(&r) {
        assert_eq!(
            view(&p, s, q).map(|v| v.len()),
            Err(WalkError::OutsideRegion(r)),
            "q {q:?} outside {r:?}"
        );
    }
    compared
}

#[test]
fn grid_views_in_the_box_equal_full_and_reference() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut compared = 0;
    for (n, seed) in [(16, 1), (16, 2), (32, 3), (64, 1), (64, 4)] {
        let f = generate(SceneKind::Grid, n, seed).unwrap();
        let s = f.scene.as_ref();
        let c = build_by_sweep(&s).unwrap();
        for _ in 0..6 * scale() {
            let r = random_box(&s, &mut rng);
            let points = points_in(&r, 12, &mut rng);
            compared += check_box(&s, &c, r, &points, 4);
        }
    }
    assert!(compared > 200, "only {compared} free viewpoints");
}

/// Boxes whose corners and edges lie on the scene's vertices, edges and their extensions.
#[test]
fn boxes_through_vertices() {
    let f = generate(SceneKind::Grid, 16, 9).unwrap();
    let s = f.scene.as_ref();
    let c = build_by_sweep(&s).unwrap();
    let v = s.vertices();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut compared = 0;
    for _ in 0..12 * scale() {
        let (a, b) = (v[rng.gen_range(0..v.len())], v[rng.gen_range(0..v.len())]);
        let r = region(
            a.x().min(b.x()),
            a.y().min(b.y()),
            a.x().max(b.x()),
            a.y().max(b.y()),
        );
        // The vertices themselves are on objects (not free); points on the box's edges
        // pass along the objects' vertices' rows and columns.
        let points = points_in(&r, 6, &mut rng);
        compared += check_box(&s, &c, r, &points, 2);
    }
    // A box that is a single free point, and a segment.
    let (x0, y0, x1, y1) = bbox(&s);
    for r in [
        region(x0 - (1 << 16), y0, x0 - (1 << 16), y0),
        region(x0, (y0 + y1) / 2, x1, (y0 + y1) / 2),
    ] {
        let points = points_in(&r, 6, &mut rng);
        compared += check_box(&s, &c, r, &points, 2);
    }
    assert!(compared > 50, "only {compared}");
}

/// The scene with every object opaque (its polygons as written).
fn opaque(s: &Scene) -> Scene {
    let sr = s.as_ref();
    let polys: Vec<Vec<Point>> = sr
        .objects()
        .iter()
        .map(|o| {
            let p = sr.polygon(o);
            (0..p.len()).map(|j| p[o.written_vertex_id(j)]).collect()
        })
        .collect();
    Scene::new(polys.iter().map(|p| (Material::Opaque, &p[..]))).unwrap()
}

/// The degenerate scenes of the fuzz generators (collinear lattices, slivers, extreme
/// coordinates), made opaque.
#[test]
fn degenerate_scenes() {
    for_degenerate_scenes(21, |sr, c, rng| {
        for _ in 0..2 {
            let r = random_box(sr, rng);
            let points = points_in(&r, 4, rng);
            check_box(sr, c, r, &points, 2);
        }
    });
}

/// Calls `each` on up to 60 (× `scale()`) degenerate scenes of the fuzz generators, made
/// opaque, with their complex, and checks that at least 30 came.
fn for_degenerate_scenes(
    seed: u64,
    mut each: impl FnMut(&SceneRef<'_>, &Complex, &mut ChaCha8Rng),
) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut done = 0;
    for _ in 0..600 * scale() {
        let Some(s) = common::random_spec_scene(&mut rng) else {
            continue;
        };
        let s = opaque(&s);
        let sr = s.as_ref();
        if sr.is_empty() {
            continue;
        }
        let c = build_by_sweep(&sr).unwrap();
        each(&sr, &c, &mut rng);
        done += 1;
        if done == 60 * scale() {
            break;
        }
    }
    assert!(done >= 30, "only {done} degenerate scenes");
}

/// Scenes with mirrors, refractive objects and screens are pruned too, keeping every
/// cylinder whose floor is one of them (the walks of ray trees behind it); a pruned
/// complex is not pruned again.
#[test]
fn secondary_sheets_are_kept_and_pruned_complexes_refused() {
    let sq = |x: i32| {
        [
            Point::from_raw(x << 16, 0).unwrap(),
            Point::from_raw((x + 1) << 16, 0).unwrap(),
            Point::from_raw((x + 1) << 16, 1 << 16).unwrap(),
        ]
    };
    let (a, b) = (sq(0), sq(3));
    let r = region(0, 0, 1 << 16, 1 << 16);
    for m in [
        Material::Opaque,
        Material::Mirror,
        Material::Screen,
        Material::Refractive {
            eta: vcx::Eta::from_f64(1.5).unwrap(),
        },
    ] {
        let s = Scene::new([(Material::Opaque, &a[..]), (m, &b[..])]).unwrap();
        let sr = s.as_ref();
        let c = build_by_sweep(&sr).unwrap();
        let p = c.prune_to_region(&sr, r).unwrap();
        let behind = |c: &Complex| {
            c.cylinders()
                .iter()
                .filter(|c| c.floor == Some(ObjectId(1)))
                .count()
        };
        if m != Material::Opaque {
            assert_eq!(behind(&p), behind(&c), "{m:?}");
        }
        assert_eq!(
            p.prune_to_region(&sr, r).unwrap_err(),
            RegionError::AlreadyPruned
        );
    }
}

/// Ray trees as comparable rows: start angle (bits), exact start direction, branch,
/// boundary vertex.
type TreeKey = Vec<(u64, Option<(i128, i128)>, Vec<ObjectId>, Option<usize>)>;

fn tree_key(t: Result<Vec<TreeInterval>, WalkError>) -> Result<TreeKey, WalkError> {
    t.map(|t| {
        t.into_iter()
            .map(|i| {
                (
                    i.start.to_bits(),
                    i.exact_start.map(|a| a.vector()),
                    i.branch,
                    i.start_vertex,
                )
            })
            .collect()
    })
}

/// A random range of primary directions (the full circle when both ends are equal).
fn random_range(rng: &mut ChaCha8Rng) -> (Direction, Direction) {
    let mut d = || loop {
        if let Some(d) = Direction::new(rng.gen_range(-9..=9), rng.gen_range(-9..=9)) {
            return d;
        }
    };
    (d(), d())
}

/// Prunes `c` to `r` and compares, from every viewpoint of `points`, the ray trees of the
/// pruned complex with the whole complex's, errors included: the full tree to `depth`
/// and a frame's (`frame_tree`) over a random range; the first `reference` compared
/// trees also against the exact reference. Points outside are refused. Returns how many
/// trees were compared.
fn check_trees(
    s: &SceneRef<'_>,
    c: &Complex,
    r: Region,
    points: &[QueryPoint],
    depth: usize,
    (reference, rng): (usize, &mut ChaCha8Rng),
) -> usize {
    let p = c.prune_to_region(s, r).unwrap();
    p.validate(s)
        .unwrap_or_else(|e| panic!("pruned complex invalid: {e}"));
    let mut compared = 0;
    for &q in points {
        let full = tree_key(ray_tree(c, s, q, depth));
        assert_eq!(
            tree_key(ray_tree(&p, s, q, depth)),
            full,
            "tree from {q:?} in {r:?}, depth {depth}"
        );
        let (from, to) = random_range(rng);
        assert_eq!(
            tree_key(frame_tree(&p, s, q, depth, from, to)),
            tree_key(frame_tree(c, s, q, depth, from, to)),
            "frame from {q:?} in {r:?}, depth {depth}, {from:?} to {to:?}"
        );
        if full.is_ok() {
            if compared < reference {
                compare_ray_tree(s, &p, q, depth.min(2))
                    .unwrap_or_else(|e| panic!("box {r:?}: {e}"));
            }
            compared += 1;
        }
    }
    for q in points_outside(&r) {
        assert_eq!(
            ray_tree(&p, s, q, depth).map(|t| t.len()),
            Err(WalkError::OutsideRegion(r)),
            "q {q:?} outside {r:?}"
        );
    }
    compared
}

/// Ray trees (depth 1 to 5) from viewpoints in random boxes, walked in the pruned complex
/// of hall-of-mirrors and mixed scenes, equal the whole complex's (which `ray_trees.rs`
/// checks against the reference), and the reference's on the small scenes.
#[test]
fn ray_trees_in_the_box_equal_full_and_reference() {
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let (mut compared, mut kept, mut all) = (0, 0, 0);
    for (kind, n, seed) in [
        (SceneKind::Hall, 6, 1),
        (SceneKind::Hall, 12, 2),
        (SceneKind::Mixed, 12, 1),
        (SceneKind::Mixed, 30, 1),
        (SceneKind::Mixed, 30, 4),
        (SceneKind::Mixed, 60, 2),
    ] {
        let f = generate(kind, n, seed).unwrap();
        let s = f.scene.as_ref();
        let c = build_by_sweep(&s).unwrap();
        for k in 0..5 * scale() {
            let r = random_box(&s, &mut rng);
            let points = points_in(&r, 3, &mut rng);
            let depth = 1 + (k % 5);
            // The big-rational reference is slow: one tree of depth 1 per small scene.
            let reference = usize::from(k == 0 && n <= 12);
            compared += check_trees(&s, &c, r, &points, depth, (reference, &mut rng));
            kept += c.prune_to_region(&s, r).unwrap().cylinders().len();
            all += c.cylinders().len();
        }
    }
    assert!(compared > 100, "only {compared} trees");
    // Opaque floors outside the box's lines are dropped.
    assert!(kept * 10 < all * 9, "kept {kept} of {all}");
}

/// The degenerate scenes of the fuzz generators with their materials: ray trees to depth
/// 2 from random boxes.
#[test]
fn ray_trees_of_degenerate_scenes() {
    let mut rng = ChaCha8Rng::seed_from_u64(29);
    let (mut done, mut compared) = (0, 0);
    for _ in 0..600 * scale() {
        let Some(s) = common::random_spec_scene(&mut rng) else {
            continue;
        };
        let sr = s.as_ref();
        if sr.is_empty() || sr.objects().iter().all(|o| o.material == Material::Opaque) {
            continue;
        }
        let c = build_by_sweep(&sr).unwrap();
        for _ in 0..2 {
            let r = random_box(&sr, &mut rng);
            let points = points_in(&r, 2, &mut rng);
            compared += check_trees(&sr, &c, r, &points, 2, (1, &mut rng));
        }
        done += 1;
        if done == 40 * scale() {
            break;
        }
    }
    assert!(
        done >= 30 && compared > 100,
        "{done} scenes, {compared} trees"
    );
}

/// A region file of a mixed scene: decoded (both decoders), its ray trees equal the whole
/// complex's, walked without a heap by `frame_tree_into` in caller storage.
#[test]
fn ray_trees_from_region_files() {
    let f = generate(SceneKind::Mixed, 30, 3).unwrap();
    let s = f.scene;
    let sr = s.as_ref();
    let c = build_by_sweep(&sr).unwrap();
    let (x0, y0, x1, y1) = bbox(&sr);
    let (w, h) = ((x1 - x0) / 3, (y1 - y0) / 3);
    let r = region(x0 + w, y0 + h, x1 - w, y1 - h);
    let v4 = encode_region(&sr, &c, r, &EncodeOptions::default()).unwrap();
    v4_equals_pruned_v3(&sr, &c, r);
    let loaded = decode(&v4).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let points = points_in(&r, 30, &mut rng);
    let mut walked = 0;
    for &q in &points {
        let want = tree_key(ray_tree(&c, &sr, q, 5));
        assert_eq!(
            tree_key(ray_tree(&loaded.complex, &loaded.scene.as_ref(), q, 5)),
            want
        );
        walked += usize::from(want.is_ok());
    }
    assert!(walked > 20, "only {walked}");
    let (from, to) = (Direction::new(1, 0).unwrap(), Direction::new(0, 1).unwrap());
    with_decoded::<1024, _>(&v4, |ds, slices, region, _| {
        assert_eq!(region, Some(r));
        let mut scratch = Box::new(TreeScratch::<20, 10>::new());
        for &q in &points {
            let mut got = Vec::new();
            let walked = frame_tree_into(slices, ds, q, 5, from, to, &mut scratch, |i| {
                got.push((i.start.to_bits(), i.branch.to_vec()))
            });
            let want = frame_tree(&c, &sr, q, 5, from, to).map(|t| {
                t.into_iter()
                    .map(|i| (i.start.to_bits(), i.branch))
                    .collect::<Vec<_>>()
            });
            assert_eq!(walked.map(|()| got), want, "{q:?}");
        }
    })
    .unwrap();
}

/// The pruned complex of a grid scene, its scene, its region and a free viewpoint in it.
fn pruned_grid(n: u32) -> (Scene, Complex, Complex, Region) {
    let f = generate(SceneKind::Grid, n, 5).unwrap();
    let s = f.scene;
    let c = build_by_sweep(&s.as_ref()).unwrap();
    let (x0, y0, x1, y1) = bbox(&s.as_ref());
    let (w, h) = ((x1 - x0) / 4, (y1 - y0) / 4);
    let r = region(x0 + w, y0 + h, x1 - w, y1 - h);
    let p = c.prune_to_region(&s.as_ref(), r).unwrap();
    (s, c, p, r)
}

/// A link the walk needs, removed from a pruned complex that still validates: the walk
/// stops with `Corrupt` (never a panic, a loop or a wrong view).
#[test]
fn a_missing_link_stops_the_walk() {
    let (s, _, p, r) = pruned_grid(16);
    let sr = s.as_ref();
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let mut cut = 0;
    for q in points_in(&r, 40, &mut rng) {
        // The first secondary wall the walk crosses after its start.
        let (mut crossing, mut steps) = (None, 0);
        let walked = p.walk_trace(&sr, q, |st| {
            if crossing.is_none() && steps > 0 && st.vertex.is_none() {
                crossing = Some(st.cylinder);
            }
            steps += 1;
        });
        let (Ok(()), Some(to)) = (walked, crossing) else {
            continue;
        };
        let mut cylinders = p.cylinders().to_vec();
        let from = cylinders[to.index()].left_neighbour.unwrap();
        cylinders[to.index()].left_neighbour = None;
        cylinders[from.index()].right_neighbour = None;
        let broken = Complex::from_region_parts(&sr, Some(r), p.vertices().to_vec(), cylinders)
            .expect("still a valid pruned complex");
        assert_eq!(
            view(&broken, &sr, q).map(|v| v.len()),
            Err(WalkError::Corrupt)
        );
        cut += 1;
    }
    assert!(cut > 5, "only {cut} walks crossed a secondary wall");
}

/// A cylinder the walk needs, dropped: `Corrupt`, or the view is still right (another
/// walk did not need it).
#[test]
fn a_missing_cylinder_stops_the_walk() {
    let (s, c, p, r) = pruned_grid(16);
    let sr = s.as_ref();
    // Drop the last cylinder (no renumbering needed) and the links to it.
    let mut cylinders = p.cylinders().to_vec();
    let last = cylinders.len() - 1;
    cylinders.pop();
    for c in &mut cylinders {
        for l in [&mut c.left_neighbour, &mut c.right_neighbour] {
            if l.is_some_and(|l| l.index() == last) {
                *l = None;
            }
        }
    }
    let broken = match Complex::from_region_parts(&sr, Some(r), p.vertices().to_vec(), cylinders) {
        Ok(b) => b,
        // A vertex only that cylinder named: the pruned checks see it.
        Err(e) => return assert_eq!(e, ComplexError::Count),
    };
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let mut failed = 0;
    for q in points_in(&r, 200, &mut rng) {
        match view_key(&broken, &sr, q) {
            Ok(v) => assert_eq!(Ok(v), view_key(&c, &sr, q)),
            Err(WalkError::Corrupt) => failed += 1,
            Err(WalkError::NotFree(_)) => {}
            Err(e) => panic!("{e:?}"),
        }
    }
    assert!(failed > 0, "no walk needed the dropped cylinder");
}

/// `p` without its cylinder `k`: later ids shift down, links to it removed. `None` if a
/// vertex only that cylinder named is left over (the pruned checks refuse it).
fn without_cylinder(sr: &SceneRef<'_>, p: &Complex, k: usize) -> Option<Complex> {
    let mut cylinders = p.cylinders().to_vec();
    cylinders.remove(k);
    for c in &mut cylinders {
        for l in [&mut c.left_neighbour, &mut c.right_neighbour] {
            *l = match *l {
                Some(id) if id.index() == k => None,
                Some(id) if id.index() > k => {
                    vcx::partition::CylinderId::from_index(id.index() - 1)
                }
                other => other,
            };
        }
    }
    Complex::from_region_parts(sr, p.region(), p.vertices().to_vec(), cylinders).ok()
}

/// A cylinder behind a mirror, refractive object or screen dropped from a pruned mixed
/// scene: ray trees that need it fail with an error, never a wrong tree (an anchored
/// walk's start climbs the sheet, whose tilings then have a gap).
#[test]
fn a_missing_cylinder_behind_a_mirror_stops_the_tree() {
    let f = generate(SceneKind::Mixed, 30, 1).unwrap();
    let sr = f.scene.as_ref();
    let c = build_by_sweep(&sr).unwrap();
    let (x0, y0, x1, y1) = bbox(&sr);
    let (w, h) = ((x1 - x0) / 3, (y1 - y0) / 3);
    let r = region(x0 + w, y0 + h, x1 - w, y1 - h);
    let p = c.prune_to_region(&sr, r).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let points = points_in(&r, 40, &mut rng);
    let full: Vec<_> = points
        .iter()
        .map(|&q| tree_key(ray_tree(&c, &sr, q, 3)))
        .collect();
    let behind: Vec<usize> = (0..p.cylinders().len())
        .filter(|&k| {
            let c = &p.cylinders()[k];
            c.left != vcx::partition::Wall::Zero
                && c.floor
                    .is_some_and(|f| sr.objects()[f.0 as usize].material != Material::Opaque)
        })
        .collect();
    let (mut failed, mut broken_complexes) = (0, 0);
    for _ in 0..40 {
        let k = behind[rng.gen_range(0..behind.len())];
        let Some(broken) = without_cylinder(&sr, &p, k) else {
            continue;
        };
        broken_complexes += 1;
        for (&q, want) in points.iter().zip(&full) {
            match tree_key(ray_tree(&broken, &sr, q, 3)) {
                Ok(t) => assert_eq!(Ok(t), *want, "cylinder {k} dropped, tree from {q:?}"),
                Err(_) if want.is_ok() => failed += 1,
                Err(e) => assert_eq!(Err(e), *want),
            }
        }
    }
    assert!(
        broken_complexes > 20 && failed > 0,
        "{broken_complexes} complexes, {failed} failed"
    );
}

/// Encoded as version 4 (default) or 2 (`explicit_cylinders`) with the region; both
/// decoders give it back, and the allocation-free one walks the same views once told the
/// region.
#[test]
fn region_files_round_trip() {
    let explicit = EncodeOptions {
        explicit_cylinders: true,
        ..Default::default()
    };
    let (s, c, p, r) = pruned_grid(32);
    let sr = s.as_ref();
    let v3 = encode(&sr, &c, None, &EncodeOptions::default()).unwrap();
    let v4 = encode(&sr, &p, None, &EncodeOptions::default()).unwrap();
    let v2 = encode(&sr, &p, None, &explicit).unwrap();
    // Version 4 is version 3 with the region, the vertex count and one bit per cylinder.
    let bitmap = c.cylinders().len().div_ceil(8);
    assert!(v4.len() > v3.len() + bitmap && v4.len() < v3.len() + bitmap + 24);
    assert_eq!(u16::from_le_bytes([v4[4], v4[5]]), format::VERSION_PRUNED);
    // From the whole complex directly: the same file (it is the sweep's).
    assert_eq!(
        encode_region(&sr, &c, r, &EncodeOptions::default()).unwrap(),
        v4
    );
    for bytes in [v4, v2] {
        region_file_round_trips(&s, &c, &p, r, &bytes);
    }
}

fn region_file_round_trips(s: &Scene, c: &Complex, p: &Complex, r: Region, bytes: &[u8]) {
    let sr = s.as_ref();
    let bytes = bytes.to_vec();
    // Smaller than the whole complex stored with every cylinder (version 1).
    let explicit = EncodeOptions {
        explicit_cylinders: true,
        ..Default::default()
    };
    let full = encode(&sr, c, None, &explicit).unwrap();
    assert!(bytes.len() < full.len());
    assert_eq!(u16::from_le_bytes([full[4], full[5]]), format::VERSION);
    let h = Header::read(&bytes).unwrap();
    assert!(h.region && !h.has_history());
    assert_eq!(h.cylinders as usize, p.cylinders().len());
    assert_eq!(h.complex_vertices as usize, p.vertices().len());
    let loaded = decode(&bytes).unwrap();
    assert_eq!(loaded.complex.region(), Some(r));
    assert_eq!(loaded.complex.cylinders(), p.cylinders());
    assert_eq!(loaded.complex.vertices(), p.vertices());
    // A history cannot go with a region.
    let history = vcx::partition::History::build(&sr, &Default::default()).unwrap();
    let hc = history
        .complex(&sr)
        .unwrap()
        .prune_to_region(&sr, r)
        .unwrap();
    assert!(matches!(
        encode(&sr, &hc, Some(&history), &EncodeOptions::default()),
        Err(FormatError::NotEncodable(_))
    ));

    // No heap: decode into caller storage, rebuild the derived state, walk.
    with_decoded::<1024, _>(&bytes, |ds, slices, region, out| {
        assert_eq!(region, Some(r));
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut walked = 0;
        for q in points_in(&r, 30, &mut rng) {
            let Ok(k) = view_into(slices, ds, q, out) else {
                continue;
            };
            let got: ViewKey = out[..k]
                .iter()
                .map(|i| (i.start.vector(), i.object, i.start_vertex))
                .collect();
            assert_eq!(Ok(got), view_key(c, &sr, q));
            walked += 1;
        }
        assert!(walked > 10);
        for q in points_outside(&r) {
            assert_eq!(
                view_into(slices, ds, q, out),
                Err(WalkError::OutsideRegion(r))
            );
        }
    })
    .unwrap();
}

/// `decode_into`, the derived state rebuilt into caller buffers, a view walked (no heap
/// for the walk); any failure is fine, a panic is not.
fn walk_decoded_into(bytes: &[u8], q: QueryPoint) {
    let Ok(h) = Header::read(bytes) else { return };
    if h.objects > 64 || h.scene_vertices > 256 || h.cylinders > 4096 {
        return;
    }
    let _ = with_decoded::<256, _>(bytes, |ds, c, _, out| {
        let _ = view_into(c, ds, q, out);
    });
}

/// `bytes` decoded into caller storage sized from its header (`decode_into`, up to `V`
/// scene vertices and 64 objects), the derived state rebuilt into caller buffers
/// (`Complex::from_slices`, with the file's region), and a view buffer of
/// `view_capacity(objects)`: `f` gets the scene, the complex, the region and the buffer.
/// Any failure before `f` is an `Err` naming it.
fn with_decoded<const V: usize, R>(
    bytes: &[u8],
    f: impl FnOnce(&SceneRef<'_>, &Complex<Slices<'_>>, Option<Region>, &mut [ViewInterval]) -> R,
) -> Result<R, String> {
    let h = Header::read(bytes).map_err(|e| format!("header: {e}"))?;
    let (n, nv) = (h.objects as usize, h.scene_vertices as usize);
    let mut objects = vec![SceneObject::BLANK; n];
    let mut points = vec![Point::default(); nv];
    let mut vertices = vec![BLANK_VERTEX; h.complex_vertices as usize];
    let mut cylinders = vec![BLANK_CYLINDER; h.cylinders as usize];
    let d = decode_into::<V, 64>(
        bytes,
        Scratch {
            objects: &mut objects,
            points: &mut points,
            open: &mut vec![ZERO_SLOTS; Scratch::open_len(n)],
        },
        &mut vertices,
        &mut cylinders,
    )
    .map_err(|e| format!("decode_into: {e}"))?;
    let ds = d.scene.as_ref();
    let sizes = BorderSizes::exact(n, d.vertices.len(), d.cylinders);
    let mut border = common::BorderVecs::new(sizes);
    let c = Complex::from_slices(&ds, d.vertices, d.cylinders, border.buffers())
        .map_err(|e| format!("from_slices: {e:?}"))?
        .with_region(d.region);
    let mut out = vec![
        ViewInterval {
            start: vcx::geom::sos::Angle::ZERO,
            object: None,
            start_vertex: None,
        };
        vcx::walk::view_capacity(n)
    ];
    Ok(f(&ds, &c, d.region, &mut out))
}

fn reseal(bytes: &mut [u8]) {
    let at = bytes.len() - format::CHECKSUM_LEN;
    let crc = format::crc32(&bytes[..at]);
    bytes[at..].copy_from_slice(&crc.to_le_bytes());
}

/// A small region file: every truncation and every single-bit flip (checksum kept, and
/// recomputed so the structural checks are what is tested) is an error or, with the
/// checksum recomputed, a file that loads and walks without panicking; and the specific
/// region errors name what is wrong.
#[test]
fn corrupt_region_files() {
    let f = generate(SceneKind::Grid, 4, 3).unwrap();
    let s = f.scene;
    let sr = s.as_ref();
    let c = build_by_sweep(&sr).unwrap();
    let (x0, y0, x1, y1) = bbox(&sr);
    let r = region(x0, y0, (x0 + x1) / 2, (y0 + y1) / 2);
    let p = c.prune_to_region(&sr, r).unwrap();
    for explicit_cylinders in [false, true] {
        let options = EncodeOptions {
            explicit_cylinders,
            ..Default::default()
        };
        let bytes = encode(&sr, &p, None, &options).unwrap();
        corrupt_region_file(&bytes, &p, (x0, y0));
    }
}

fn corrupt_region_file(bytes: &[u8], p: &Complex, (x0, y0): (i32, i32)) {
    let bytes = bytes.to_vec();
    assert_eq!(decode(&bytes).unwrap().complex.cylinders(), p.cylinders());
    let q = QueryPoint::from_raw((i64::from(x0) << 16) + 3, (i64::from(y0) << 16) + 5).unwrap();
    for len in 0..bytes.len() {
        assert!(decode(&bytes[..len]).is_err(), "truncated to {len}");
    }
    for bit in 0..bytes.len() * 8 {
        let mut b = bytes.clone();
        b[bit / 8] ^= 1 << (bit % 8);
        assert!(decode(&b).is_err(), "bit {bit} flipped");
        reseal(&mut b);
        if let Ok(l) = decode(&b) {
            let _ = view(&l.complex, &l.scene.as_ref(), q);
        }
        // The device path checks less (no cross-section or count checks): walks of what
        // it accepts must still end, with a view or an error.
        walk_decoded_into(&b, q);
    }

    // The region's upper corner below its lower one (x1 < x0): x0 is the first varint of
    // the complex part.
    let h = Header::read(&bytes).unwrap();
    let at = h.part_range(format::Part::Complex).start;
    let b = bytes.clone();
    // Rewrite the region as (0, 0, -1, 0): zigzag 0, 0, 1, 0 in one byte each, then the
    // rest of the part as it was after the original region.
    let mut pos = at;
    for _ in 0..4 {
        while b[pos] & 0x80 != 0 {
            pos += 1;
        }
        pos += 1;
    }
    let mut edited = bytes[..at].to_vec();
    edited.extend_from_slice(&[0, 0, 1, 0]);
    edited.extend_from_slice(&b[pos..]);
    let shrink = (pos - at - 4) as u32;
    let complex_bytes = h.complex_bytes - shrink;
    edited[format::offset::COMPLEX_BYTES..format::offset::COMPLEX_BYTES + 4]
        .copy_from_slice(&complex_bytes.to_le_bytes());
    reseal(&mut edited);
    let e = decode(&edited).unwrap_err();
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: format::Arena::Region,
                field: "x1",
                ..
            }
        ),
        "{e:?}"
    );

    // Version 2 without the region flag; version 1 with it.
    let mut v = bytes.clone();
    v[format::offset::FLAGS] &= !(format::FLAG_REGION as u8);
    reseal(&mut v);
    assert_eq!(decode(&v).unwrap_err(), FormatError::RegionFlagMissing);
    let mut v = bytes.clone();
    v[format::offset::VERSION] = 1;
    reseal(&mut v);
    assert!(matches!(
        decode(&v).unwrap_err(),
        FormatError::UnknownFlags { .. }
    ));
    // More cylinders than 3n + 1 + 3V.
    let mut v = bytes.clone();
    let full = 3 * h.objects + 1 + 3 * h.complex_vertices;
    v[format::offset::CYLINDERS..format::offset::CYLINDERS + 4]
        .copy_from_slice(&(full + 1).to_le_bytes());
    reseal(&mut v);
    assert!(matches!(
        decode(&v).unwrap_err(),
        FormatError::Count {
            field: "cylinders",
            ..
        }
    ));
}

/// How tight the conservative pruning is: kept cylinders against a lower bound of the
/// needed ones (the cylinders walked from many viewpoints in the box). Prints a table;
/// run with `--ignored --nocapture`.
#[test]
#[ignore]
fn tightness_table() {
    for n in [64, 256] {
        let f = generate(SceneKind::Grid, n, 1).unwrap();
        let s = f.scene.as_ref();
        let c = build_by_sweep(&s).unwrap();
        let (x0, y0, x1, y1) = bbox(&s);
        for k in [4, 16, 64] {
            let f = (k as f64).sqrt();
            let (w, h) = (
                ((x1 - x0) as f64 / f / 2.0) as i32,
                ((y1 - y0) as f64 / f / 2.0) as i32,
            );
            let (cx, cy) = (x0 / 2 + x1 / 2, y0 / 2 + y1 / 2);
            let r = region(cx - w, cy - h, cx + w, cy + h);
            let p = c.prune_to_region(&s, r).unwrap();
            let mut rng = ChaCha8Rng::seed_from_u64(1);
            let mut seen = vec![false; c.cylinders().len()];
            let mut points = points_in(&r, 20_000, &mut rng);
            // Dense points along the edges too.
            let (lo, hi) = (r.min().to_query(), r.max().to_query());
            for i in 0..=2000i64 {
                let (x, y) = (
                    lo.x() + (hi.x() - lo.x()) * i / 2000,
                    lo.y() + (hi.y() - lo.y()) * i / 2000,
                );
                for (a, b) in [(x, lo.y()), (x, hi.y()), (lo.x(), y), (hi.x(), y)] {
                    points.push(QueryPoint::from_raw(a, b).unwrap());
                }
            }
            for q in points {
                let _ = c.walk_trace(&s, q, |st| seen[st.cylinder.index()] = true);
            }
            let walked = seen.iter().filter(|&&b| b).count();
            println!(
                "n {n}, 1/{k} of the area: {} cylinders, kept {}, walked from 28,004 points {walked} ({:.1}% more kept)",
                c.cylinders().len(),
                p.cylinders().len(),
                100.0 * (p.cylinders().len() as f64 / walked as f64 - 1.0)
            );
        }
    }
}

/// Decode of a version-4 file, in both decoders, against `prune_to_region` of the version-3
/// decode of the same whole complex: field for field, same numbering.
fn v4_equals_pruned_v3(sr: &SceneRef<'_>, c: &Complex, r: Region) {
    let v3 = encode(sr, c, None, &EncodeOptions::default()).unwrap();
    let expected = decode(&v3).unwrap().complex.prune_to_region(sr, r).unwrap();
    let v4 = encode_region(sr, c, r, &EncodeOptions::default()).unwrap();
    let h = Header::read(&v4).unwrap();
    assert_eq!(h.version, format::VERSION_PRUNED);
    let got = decode(&v4).unwrap().complex;
    assert_eq!(got.region(), Some(r));
    assert_eq!(got.vertices(), expected.vertices());
    assert_eq!(got.cylinders(), expected.cylinders());
    // The allocation-free decoder, in storage of exactly the kept counts.
    let (n, nv) = (h.objects as usize, h.scene_vertices as usize);
    let mut vertices = vec![BLANK_VERTEX; h.complex_vertices as usize];
    let mut cylinders = vec![BLANK_CYLINDER; h.cylinders as usize];
    let d = decode_into::<4096, 512>(
        &v4,
        Scratch {
            objects: &mut vec![SceneObject::BLANK; n],
            points: &mut vec![Point::default(); nv],
            open: &mut vec![ZERO_SLOTS; Scratch::open_len(n)],
        },
        &mut vertices,
        &mut cylinders,
    )
    .unwrap();
    assert_eq!(d.region, Some(r));
    assert_eq!(d.vertices, expected.vertices());
    assert_eq!(d.cylinders, expected.cylinders());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48 * scale() as u32))]
    /// Random grid scenes built by the randomized construction (numbered unlike the
    /// replay) and random boxes.
    #[test]
    fn v4_decodes_to_the_pruned_v3(n in 1u32..40, seed in any::<u64>(), boxes in any::<u64>()) {
        let f = generate(SceneKind::Grid, n, seed % 1000).unwrap();
        let sr = f.scene.as_ref();
        let c = vcx::partition::History::build(&sr, &Default::default())
            .unwrap()
            .complex(&sr)
            .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(boxes);
        for _ in 0..3 {
            v4_equals_pruned_v3(&sr, &c, random_box(&sr, &mut rng));
        }
    }
}

/// The degenerate scenes of the fuzz generators, made opaque, in version 4.
#[test]
fn v4_of_degenerate_scenes() {
    for_degenerate_scenes(23, |sr, c, rng| {
        for _ in 0..2 {
            v4_equals_pruned_v3(sr, c, random_box(sr, rng));
        }
    });
}

/// Views walked in a decoded version-4 file equal the exact reference's for the scene as
/// read from its JSON file, from viewpoints in the box.
#[test]
fn v4_views_equal_the_json_scene() {
    let f = generate(SceneKind::Grid, 24, 7).unwrap();
    let json = f.to_json();
    let s = vcx_demo::scene_file::parse(&json).unwrap().scene;
    let sr = s.as_ref();
    let c = build_by_sweep(&sr).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let sub = SubScene::new(sr, (0..sr.len() as u32).map(ObjectId));
    let mut compared = 0;
    for _ in 0..4 {
        let r = random_box(&sr, &mut rng);
        let v4 = encode_region(&sr, &c, r, &EncodeOptions::default()).unwrap();
        let loaded = decode(&v4).unwrap();
        let (ls, lc) = (loaded.scene.as_ref(), &loaded.complex);
        for q in points_in(&r, 8, &mut rng) {
            if view(lc, &ls, q).is_err() {
                continue;
            }
            compare_view(&sr, &sub, lc, q).unwrap_or_else(|e| panic!("box {r:?}: {e}"));
            compared += 1;
        }
    }
    assert!(compared > 10, "only {compared}");
}

/// A version-4 kept map of the wrong length, with bits past the end, or keeping a count
/// other than the header's: typed errors naming the map.
#[test]
fn wrong_kept_maps_are_named() {
    let f = generate(SceneKind::Grid, 4, 3).unwrap();
    let sr = f.scene.as_ref();
    let c = build_by_sweep(&sr).unwrap();
    let (x0, y0, x1, y1) = bbox(&sr);
    let r = region(x0, y0, (x0 + x1) / 2, (y0 + y1) / 2);
    let bytes = encode_region(&sr, &c, r, &EncodeOptions::default()).unwrap();
    let h = Header::read(&bytes).unwrap();
    let replayed = c.cylinders().len();
    let len = replayed.div_ceil(8);
    let end = bytes.len() - format::CHECKSUM_LEN;
    let map_at = end - len;
    assert_eq!(bytes[map_at - 1] as usize, len, "the map's length prefix");
    // One bit more: the count of kept cylinders is wrong.
    let free_bit = (0..replayed)
        .find(|&i| bytes[map_at + i / 8] & (1 << (i % 8)) == 0)
        .unwrap();
    let mut b = bytes.clone();
    b[map_at + free_bit / 8] |= 1 << (free_bit % 8);
    reseal(&mut b);
    assert!(matches!(
        decode(&b).unwrap_err(),
        FormatError::Count {
            field: "cylinders",
            ..
        }
    ));
    // A padding bit set.
    if !replayed.is_multiple_of(8) {
        let mut b = bytes.clone();
        b[end - 1] |= 0x80;
        reseal(&mut b);
        let e = decode(&b).unwrap_err();
        assert!(
            matches!(
                e,
                FormatError::Element {
                    arena: format::Arena::KeptMap,
                    ..
                }
            ),
            "{e:?}"
        );
    }
    // A map one byte short (the part shrunk with it) or one byte long.
    for grow in [-1i64, 1] {
        let mut b = bytes[..end].to_vec();
        if grow < 0 {
            b.pop();
        } else {
            b.push(0);
        }
        b[map_at - 1] = (len as i64 + grow) as u8;
        let cb = (h.complex_bytes as i64 + grow) as u32;
        b[format::offset::COMPLEX_BYTES..format::offset::COMPLEX_BYTES + 4]
            .copy_from_slice(&cb.to_le_bytes());
        b.extend_from_slice(&[0; 4]);
        reseal(&mut b);
        let e = decode(&b).unwrap_err();
        assert!(
            matches!(
                e,
                FormatError::Element {
                    arena: format::Arena::KeptMap,
                    field: "length",
                    ..
                }
            ),
            "{e:?}"
        );
    }
    // A bit moved from a kept cylinder to a dropped one: an error at load (the replay
    // keeps a vertex count other than the header's, or the pruned checks refuse it) or a
    // complex whose walks end in a view or an error.
    let kept_bit = (0..replayed)
        .find(|&i| bytes[map_at + i / 8] & (1 << (i % 8)) != 0)
        .unwrap();
    let mut b = bytes.clone();
    b[map_at + kept_bit / 8] &= !(1 << (kept_bit % 8));
    b[map_at + free_bit / 8] |= 1 << (free_bit % 8);
    reseal(&mut b);
    if let Ok(l) = decode(&b) {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for q in points_in(&r, 8, &mut rng) {
            let _ = view(&l.complex, &l.scene.as_ref(), q);
        }
    }
}
