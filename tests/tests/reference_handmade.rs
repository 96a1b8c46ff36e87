//! The exact reference checked on scenes whose answers are worked out by hand (in the
//! comments). All coordinates are integers in scene units; boxes are written
//! counter-clockwise from the lower-left corner, so a box's vertex ids are
//! 0 = lower-left, 1 = lower-right, 2 = upper-right, 3 = upper-left.

use vcx::{Eta, Material, ObjectId, Point, QueryPoint, Scene, Sign};
use vcx_tests::{
    free_bitangents, ray_tree, scene_orient, shoot, shoot_perturbed, sos_orient, trace_ray, view,
    Bitangent, Interval, RayObjects, RayTreeOptions, RefError, Vec2, VertexRef,
};

fn pt(x: i32, y: i32) -> Point {
    Point::from_raw(x << 16, y << 16).unwrap()
}

fn scene(objects: &[(Material, &[(i32, i32)])]) -> Scene {
    let polys: Vec<Vec<Point>> = objects
        .iter()
        .map(|(_, p)| p.iter().map(|&(x, y)| pt(x, y)).collect())
        .collect();
    Scene::new(objects.iter().zip(&polys).map(|((m, _), p)| (*m, &p[..]))).unwrap()
}

/// Counter-clockwise box `[x0, x1] × [y0, y1]`.
fn bx(x0: i32, y0: i32, x1: i32, y1: i32) -> [(i32, i32); 4] {
    [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
}

fn v(x: i64, y: i64) -> Vec2 {
    Vec2::from_i64(x, y)
}

fn id(i: u32) -> ObjectId {
    ObjectId(i)
}

fn vr(object: u32, vertex: usize) -> VertexRef {
    VertexRef {
        object: ObjectId(object),
        vertex,
    }
}

/// `(start direction, value, start vertex)` per interval, after checking that the list is
/// cyclic (each end is the next start) and sorted by start angle.
fn rows<T: Clone>(ivs: &[Interval<T>]) -> Vec<((i64, i64), T, Option<VertexRef>)> {
    let n = ivs.len();
    for i in 0..n {
        assert_eq!(
            ivs[i].end,
            ivs[(i + 1) % n].start,
            "interval {i} not followed"
        );
        if i + 1 < n {
            assert!(ivs[i].start_angle < ivs[i + 1].start_angle);
        }
    }
    let int = |r: &num_rational::BigRational| -> i64 {
        assert!(r.is_integer());
        r.to_integer().try_into().unwrap()
    };
    ivs.iter()
        .map(|i| {
            (
                (int(&i.start.x), int(&i.start.y)),
                i.value.clone(),
                i.start_vertex,
            )
        })
        .collect()
}

fn opts(depth: usize) -> RayTreeOptions {
    RayTreeOptions {
        depth,
        round_eyes: false,
    }
}

// A = (0,0) (2,0) (1,2), B = (5,1) (7,1) (6,3): disjoint triangles, ids 0 and 1.
const TRI_A: [(i32, i32); 3] = [(0, 0), (2, 0), (1, 2)];
const TRI_B: [(i32, i32); 3] = [(5, 1), (7, 1), (6, 3)];

#[test]
fn two_triangles_view() {
    let s = scene(&[(Material::Opaque, &TRI_A), (Material::Opaque, &TRI_B)]);
    // From q = (3, 2): directions to A: (0,0) → (−3,−2) 213.7°, (2,0) → (−1,−2) 243.4°,
    // (1,2) → (−2,0) 180°; A is seen from (1,2) at 180° to (2,0) at 243.4°.
    // To B: (5,1) → (2,−1) 333.4°, (7,1) → (4,−1) 346.0°, (6,3) → (3,1) 18.4°; B is seen
    // from (5,1) at 333.4° through 0° to (6,3) at 18.4°.
    let got = view(s.as_ref(), &v(3, 2)).unwrap();
    assert_eq!(
        rows(&got),
        vec![
            ((3, 1), None, Some(vr(1, 2))),
            ((-1, 0), Some(id(0)), Some(vr(0, 2))),
            ((-1, -2), None, Some(vr(0, 1))),
            ((2, -1), Some(id(1)), Some(vr(1, 0))),
        ]
    );
    assert!((got[0].start_angle - (1.0f64 / 3.0).atan()).abs() < 1e-12);
    assert!((got[1].start_angle - core::f64::consts::PI).abs() < 1e-12);
    // The same viewpoint given on the query grid.
    let qp = QueryPoint::from_raw(3 << 32, 2 << 32).unwrap();
    assert_eq!(Vec2::from_query(qp), v(3, 2));
    assert_eq!(view(s.as_ref(), &Vec2::from_query(qp)).unwrap(), got);
}

#[test]
fn two_triangles_bitangents() {
    let s = scene(&[(Material::Opaque, &TRI_A), (Material::Opaque, &TRI_B)]);
    // The four common tangents, each checked by the signs of the other vertices:
    // * outer lower (2,0)–(7,1), direction (5,1): (0,0) +2, (1,2) +11, (5,1) +2, (6,3) +11;
    // * outer upper (1,2)–(6,3), direction (5,1): all of −9, −11, −9, −11;
    // * inner (1,2)–(5,1), direction (4,−1): A's others −9, −7; B's others +2, +9;
    // * inner (2,0)–(6,3), direction (4,3): A's others +6, +11; B's others −5, −11.
    // No third object, so all are free; no other pair is tangent at both ends.
    let b = free_bitangents(s.as_ref());
    let bt = |ka, kb| Bitangent {
        a: vr(0, ka),
        b: vr(1, kb),
    };
    assert_eq!(b.list, vec![bt(1, 1), bt(1, 2), bt(2, 0), bt(2, 2)]);
    assert_eq!((b.undirected, b.directed), (4, 8));
}

#[test]
fn screen_between_triangles_blocks_their_bitangents() {
    // A tall screen [3,4] × [−10,10] separates A (x ≤ 2) from B (x ≥ 5): every segment
    // from A to B crosses it, so A–B has no free bitangent. A–screen and screen–B have
    // their 4 each (their segments stay in x ≤ 4, resp. x ≥ 3, away from the third object).
    let s = scene(&[
        (Material::Opaque, &TRI_A),
        (Material::Opaque, &TRI_B),
        (Material::Screen, &bx(3, -10, 4, 10)),
    ]);
    let b = free_bitangents(s.as_ref());
    assert_eq!((b.undirected, b.directed), (8, 16));
    assert!(b.list.iter().all(|t| t.b.object == id(2)));
    assert_eq!(b.list.iter().filter(|t| t.a.object == id(0)).count(), 4);
}

#[test]
fn aligned_boxes_have_four_bitangents_after_perturbation() {
    // [0,1]² and [2,3] × [0,1]: lines y = 0 and y = 1 each hold an edge of both boxes.
    // The perturbed scene is two disjoint strictly convex polygons in general position,
    // which have exactly 4 common tangents whatever the perturbation decides.
    let s = scene(&[
        (Material::Opaque, &bx(0, 0, 1, 1)),
        (Material::Opaque, &bx(2, 0, 3, 1)),
    ]);
    let b = free_bitangents(s.as_ref());
    assert_eq!((b.undirected, b.directed), (4, 8));
}

#[test]
fn sos_orient_by_hand() {
    // p = (0,0) rank 1, q = (1,0) rank 2, r = (2,0) rank 3: collinear. Variables
    // px 2, py 3, qx 4, qy 5, rx 6, ry 7. orient = (1 + e4 − e2)(e7 − e3) − (e5 − e3)(2 + e6 − e2)
    // = e7 − e3 − 2e5 + 2e3 + (quadratic terms) : constant 0, e2 coefficient 0,
    // e3 coefficient +1 → Positive (p moves up, so r is left of p → q).
    let (p, q, r) = (v(0, 0), v(1, 0), v(2, 0));
    assert_eq!(sos_orient((1, &p), (2, &q), (3, &r)), Sign::Positive);
    assert_eq!(sos_orient((2, &q), (1, &p), (3, &r)), Sign::Negative);
    // Non-degenerate: the exact sign.
    assert_eq!(sos_orient((1, &p), (2, &q), (3, &v(0, 1))), Sign::Positive);
    // Two coincident points of different ranks: p = q = (0,0) (ranks 1, 2), r = (1,0) rank 3.
    // orient = (e4 − e2)(e7 − e3) − (e5 − e3)(1 + e6 − e2): linear terms −e5 + e3,
    // most significant e3 (+1) → Positive.
    assert_eq!(sos_orient((1, &p), (2, &p), (3, &q)), Sign::Positive);
    // Scene vertices: rank = global index + 1. TRI_A's vertices are 0, 1, 2: exact.
    let s = scene(&[(Material::Opaque, &TRI_A)]);
    assert_eq!(scene_orient(s.as_ref(), 0, 1, 2), Sign::Positive);
}

#[test]
fn box_seen_from_inside_a_ring_of_boxes() {
    // Viewpoint (0,0). Ring: right R [3,4]×[−1,1] (0), top T [−1,1]×[3,4] (1),
    // left L [−4,−3]×[−1,1] (2), bottom B [−1,1]×[−4,−3] (3), corners C1 [3,4]² (4),
    // C2 [−4,−3]×[3,4] (5), C3 [−4,−3]² (6), C4 [3,4]×[−4,−3] (7), and a box O [1,2]² (8)
    // near the viewpoint. O spans (2,1) 26.6° to (1,2) 63.4° and hides C1 (36.9°–53.1°,
    // farther away). Silhouettes: R (3,−1)–(3,1); T (1,3)–(−1,3); L (−3,1)–(−3,−1);
    // B (−1,−3)–(1,−3); C2 (−3,4)–(−4,3); C3 (−4,−3)–(−3,−4); C4 (3,−4)–(4,−3).
    let s = scene(&[
        (Material::Opaque, &bx(3, -1, 4, 1)),
        (Material::Opaque, &bx(-1, 3, 1, 4)),
        (Material::Opaque, &bx(-4, -1, -3, 1)),
        (Material::Opaque, &bx(-1, -4, 1, -3)),
        (Material::Opaque, &bx(3, 3, 4, 4)),
        (Material::Opaque, &bx(-4, 3, -3, 4)),
        (Material::Opaque, &bx(-4, -4, -3, -3)),
        (Material::Opaque, &bx(3, -4, 4, -3)),
        (Material::Opaque, &bx(1, 1, 2, 2)),
    ]);
    let got = view(s.as_ref(), &v(0, 0)).unwrap();
    assert_eq!(
        rows(&got),
        vec![
            ((3, 1), None, Some(vr(0, 3))),          // 18.4°
            ((2, 1), Some(id(8)), Some(vr(8, 1))),   // 26.6°
            ((1, 2), None, Some(vr(8, 3))),          // 63.4°
            ((1, 3), Some(id(1)), Some(vr(1, 1))),   // 71.6°
            ((-1, 3), None, Some(vr(1, 0))),         // 108.4°
            ((-3, 4), Some(id(5)), Some(vr(5, 2))),  // 126.9°
            ((-4, 3), None, Some(vr(5, 0))),         // 143.1°
            ((-3, 1), Some(id(2)), Some(vr(2, 2))),  // 161.6°
            ((-3, -1), None, Some(vr(2, 1))),        // 198.4°
            ((-4, -3), Some(id(6)), Some(vr(6, 3))), // 216.9°
            ((-3, -4), None, Some(vr(6, 1))),        // 233.1°
            ((-1, -3), Some(id(3)), Some(vr(3, 3))), // 251.6°
            ((1, -3), None, Some(vr(3, 2))),         // 288.4°
            ((3, -4), Some(id(7)), Some(vr(7, 0))),  // 306.9°
            ((4, -3), None, Some(vr(7, 2))),         // 323.1°
            ((3, -1), Some(id(0)), Some(vr(0, 0))),  // 341.6°
        ]
    );
}

/// Mirror M = [4,5] × [−1,1] (0), opaque A = [−6,−5] × [1,2] (1), viewpoint (0,0).
fn mirror_scene() -> Scene {
    scene(&[
        (Material::Mirror, &bx(4, -1, 5, 1)),
        (Material::Opaque, &bx(-6, 1, -5, 2)),
    ])
}

#[test]
fn mirror_shows_the_object_over_the_right_range() {
    // Primary rays (4, y0), |y0| < 1, hit M's face x = 4 at (4, y0). The virtual eye is
    // E1 = (8, 0); the reflected ray from (4, y0) has direction (−4, y0), slope y0/4 seen
    // from E1. A's vertices from E1: (−6,1) → (−14,1), (−5,1) → (−13,1), (−5,2) → (−13,2),
    // (−6,2) → (−14,2): A spans slopes 1/14 (vertex (−6,1)) to 2/13 (vertex (−5,2)), so A
    // is seen in the mirror for y0 ∈ (2/7, 8/13): primary directions (14,1) to (13,2).
    // A is seen directly from (−5,2) at 158.2° to (−6,1) at 170.5°; M from (4,−1) to (4,1).
    let s = mirror_scene();
    let got = ray_tree(s.as_ref(), &v(0, 0), opts(1)).unwrap();
    assert_eq!(
        rows(&got),
        vec![
            ((14, 1), vec![id(0), id(1)], Some(vr(1, 0))), // level-1 ray through (−6,1)
            ((13, 2), vec![id(0)], Some(vr(1, 2))),        // level-1 ray through (−5,2)
            ((4, 1), vec![], Some(vr(0, 3))),
            ((-5, 2), vec![id(1)], Some(vr(1, 2))),
            ((-6, 1), vec![], Some(vr(1, 0))),
            ((4, -1), vec![id(0)], Some(vr(0, 0))),
        ]
    );
    // Depth 0 is the plain view: the mirror is just an object.
    let flat = ray_tree(s.as_ref(), &v(0, 0), opts(0)).unwrap();
    let plain = view(s.as_ref(), &v(0, 0)).unwrap();
    assert_eq!(
        rows(&plain),
        vec![
            ((4, 1), None, Some(vr(0, 3))),
            ((-5, 2), Some(id(1)), Some(vr(1, 2))),
            ((-6, 1), None, Some(vr(1, 0))),
            ((4, -1), Some(id(0)), Some(vr(0, 0))),
        ]
    );
    assert_eq!(flat.len(), plain.len());
    // One ray inside the mirrored range: E1 = (8,0), hit point (4, 1/2).
    let tr = trace_ray(s.as_ref(), &v(0, 0), &v(8, 1), opts(1)).unwrap();
    assert_eq!(tr.branch, vec![id(0), id(1)]);
    assert_eq!(tr.stages[1].eye, v(8, 0));
    assert_eq!(tr.stages[1].origin, Vec2::from_ratios(4, 1, 1, 2));
}

#[test]
fn viewpoint_on_the_extension_of_an_edge() {
    // Viewpoint (0,0) on the line y = 0 of box P = [2,3] × [0,1]'s bottom edge (0) and of
    // box Q = [5,6] × [−1,0]'s top edge (1). P is seen from angle 0 (its vertices (2,0) and
    // (3,0)) to (2,1) at 26.6°; Q from (5,−1) at 348.7° to angle 0 ((5,0) and (6,0)).
    // At angle 0 the vertices of the objects seen on either side are (2,0), (3,0), (5,0),
    // (6,0): the nearest, (2,0) = P's vertex 0, causes the boundary.
    let s = scene(&[
        (Material::Opaque, &bx(2, 0, 3, 1)),
        (Material::Opaque, &bx(5, -1, 6, 0)),
    ]);
    let got = view(s.as_ref(), &v(0, 0)).unwrap();
    assert_eq!(
        rows(&got),
        vec![
            ((1, 0), Some(id(0)), Some(vr(0, 0))),
            ((2, 1), None, Some(vr(0, 3))),
            ((5, -1), Some(id(1)), Some(vr(1, 0))),
        ]
    );
    assert_eq!(got[0].start_angle, 0.0);
    // P alone: the boundary at angle 0 is still P's nearer endpoint (2,0).
    let s = scene(&[(Material::Opaque, &bx(2, 0, 3, 1))]);
    assert_eq!(
        rows(&view(s.as_ref(), &v(0, 0)).unwrap()),
        vec![
            ((1, 0), Some(id(0)), Some(vr(0, 0))),
            ((2, 1), None, Some(vr(0, 3))),
        ]
    );
}

#[test]
fn refractive_slab_shifts_the_eye() {
    // Slab S = [2,4] × [−10,10] (thickness d = 2, η = 2) (0), opaque O = [6,7] × [−1,1] (1).
    // Eye (0,0). Entry face x = 2: foot F = (2,0), inside eye F + 2(E − F) = (−2,0).
    // Exit face x = 4: foot (4,0), outside eye (4,0) + ½((−2,0) − (4,0)) = (1,0): shifted by
    // d(1 − 1/η) = 1 toward the slab.
    let eta = Eta::from_raw(2 << 16).unwrap();
    let s = scene(&[
        (Material::Refractive { eta }, &bx(2, -10, 4, 10)),
        (Material::Opaque, &bx(6, -1, 7, 1)),
    ]);
    let tr = trace_ray(s.as_ref(), &v(0, 0), &v(10, 1), opts(1)).unwrap();
    assert_eq!(tr.branch, vec![id(0), id(1)]);
    let eyes: Vec<Vec2> = tr.stages.iter().map(|st| st.eye.clone()).collect();
    assert_eq!(eyes, vec![v(0, 0), v(-2, 0), v(1, 0)]);
    assert_eq!(
        tr.stages
            .iter()
            .map(|st| (st.level, st.inside))
            .collect::<Vec<_>>(),
        vec![(0, false), (0, true), (1, false)]
    );
    // Primary slope m: entry (2, 2m), inside slope m/2, exit (4, 3m), then slope m from
    // (1,0) again. O's silhouette from (1,0) is (6,±1), slopes ±1/5: seen for m ∈ (−1/5, 1/5)
    // (without the slab it would be ±1/6). For 10/3 < |m| < 5 the inside ray leaves through
    // the top or bottom face (branch [S] either way). S is seen from (2,−10) to (2,10),
    // directions (1,−5) and (1,5).
    let got = ray_tree(s.as_ref(), &v(0, 0), opts(1)).unwrap();
    assert_eq!(
        rows(&got),
        vec![
            ((5, 1), vec![id(0)], Some(vr(1, 3))),
            ((1, 5), vec![], Some(vr(0, 3))),
            ((1, -5), vec![id(0)], Some(vr(0, 0))),
            ((5, -1), vec![id(0), id(1)], Some(vr(1, 0))),
        ]
    );
    // Depth 0: the slab hides O.
    let flat = view(s.as_ref(), &v(0, 0)).unwrap();
    assert_eq!(flat.len(), 2);
    assert!(flat.iter().all(|i| i.value != Some(id(1))));
}

#[test]
fn refractive_eye_rounding() {
    // η = 3: inside eye (2,0) + 3(−2,0) = (−4,0); outside eye (4,0) + ⅓(−8,0) = (4/3, 0),
    // the shift d(1 − 1/η) = 4/3. Rounded to 2^-32: 4/3 · 2^32 = 5726623061.33… → 5726623061.
    let eta = Eta::from_raw(3 << 16).unwrap();
    let s = scene(&[(Material::Refractive { eta }, &bx(2, -10, 4, 10))]);
    let exact = trace_ray(s.as_ref(), &v(0, 0), &v(1, 0), opts(1)).unwrap();
    assert_eq!(exact.stages[2].eye, Vec2::from_ratios(4, 3, 0, 1));
    let rounded = RayTreeOptions {
        depth: 1,
        round_eyes: true,
    };
    let tr = trace_ray(s.as_ref(), &v(0, 0), &v(1, 0), rounded).unwrap();
    assert_eq!(tr.stages[1].eye, v(-4, 0));
    assert_eq!(
        tr.stages[2].eye,
        Vec2::from_query(QueryPoint::from_raw(5726623061, 0).unwrap())
    );
    assert_eq!(tr.branch, vec![id(0)]);
    assert!(!tr.degenerate);
    // Depth 0 stops at the slab.
    let tr = trace_ray(s.as_ref(), &v(0, 0), &v(1, 0), opts(0)).unwrap();
    assert_eq!((tr.stages.len(), tr.branch.clone()), (1, vec![id(0)]));
}

/// Screen S = [2,3] × [−1,1] (0), opaque A = [5,6] × [−1,1] (1).
fn screen_scene() -> Scene {
    scene(&[
        (Material::Screen, &bx(2, -1, 3, 1)),
        (Material::Opaque, &bx(5, -1, 6, 1)),
    ])
}

#[test]
fn screens_are_transparent_in_views() {
    // From (0,0) the screen is ignored: A is seen from (5,−1) at 348.7° to (5,1) at 11.3°.
    let s = screen_scene();
    let got = view(s.as_ref(), &v(0, 0)).unwrap();
    assert_eq!(
        rows(&got),
        vec![
            ((5, 1), None, Some(vr(1, 3))),
            ((5, -1), Some(id(1)), Some(vr(1, 0))),
        ]
    );
    let tree = ray_tree(s.as_ref(), &v(0, 0), opts(3)).unwrap();
    assert_eq!(tree[1].value, vec![id(1)]);
    // Only screens: one full-circle interval.
    let only = scene(&[(Material::Screen, &bx(2, -1, 3, 1))]);
    let got = view(only.as_ref(), &v(0, 0)).unwrap();
    assert_eq!(got.len(), 1);
    assert_eq!(
        (got[0].start.clone(), got[0].end.clone()),
        (v(1, 0), v(1, 0))
    );
    assert_eq!((got[0].value, got[0].start_vertex), (None, None));
}

#[test]
fn screens_count_in_forward_and_backward() {
    let s = screen_scene();
    let s = s.as_ref();
    let ray = |f: Option<u32>, b: Option<u32>| RayObjects {
        forward: f.map(ObjectId),
        backward: b.map(ObjectId),
    };
    assert_eq!(shoot(s, &v(0, 0), &v(1, 0)), Ok(ray(Some(0), None)));
    assert_eq!(shoot(s, &v(4, 0), &v(1, 0)), Ok(ray(Some(1), Some(0))));
    assert_eq!(shoot(s, &v(4, 0), &v(-1, 0)), Ok(ray(Some(0), Some(1))));
    assert_eq!(shoot(s, &v(4, 5), &v(0, 1)), Ok(ray(None, None)));
    // Along the top edges y = 1: exactly, the ray touches S first. Perturbed, q moves to
    // (ε, 1 + ε²): the line is above both objects. cross((1,0), v − q') = (vy − 1) − ε²:
    // vertices with vy = 1 get c0 = 0, c1 = d.y = 0, c2 = −d.x = −1 → below; the others are
    // below anyway, so nothing is crossed.
    assert_eq!(shoot(s, &v(0, 1), &v(1, 0)), Ok(ray(Some(0), None)));
    assert_eq!(shoot_perturbed(s, &v(0, 1), &v(1, 0)), Ok(ray(None, None)));
    // Along the bottom edges y = −1 the perturbed line is just above them: inside.
    assert_eq!(
        shoot_perturbed(s, &v(0, -1), &v(1, 0)),
        Ok(ray(Some(0), None))
    );
    assert_eq!(
        shoot_perturbed(s, &v(7, -1), &v(1, 0)),
        Ok(ray(None, Some(1)))
    );
    // Up along S's left edge x = 2: q' = (2 + ε, …) is inside S's x-range → crossed
    // (c0 = 2 − vx: 0 then c1 = d.y = 1 > 0 for x = 2; −1 for x = 3).
    assert_eq!(shoot(s, &v(2, -5), &v(0, 1)), Ok(ray(Some(0), None)));
    assert_eq!(
        shoot_perturbed(s, &v(2, -5), &v(0, 1)),
        Ok(ray(Some(0), None))
    );
    // Up along S's right edge x = 3: q' is to the right of it → missed.
    assert_eq!(shoot(s, &v(3, -5), &v(0, 1)), Ok(ray(Some(0), None)));
    assert_eq!(shoot_perturbed(s, &v(3, -5), &v(0, 1)), Ok(ray(None, None)));
    // Down along A's left edge x = 5: c0 = vx − 5, c1 = d.y = −1 → crossed.
    assert_eq!(
        shoot_perturbed(s, &v(5, 5), &v(0, -1)),
        Ok(ray(Some(1), None))
    );
    assert_eq!(
        shoot_perturbed(s, &v(5, 5), &v(0, 1)),
        Ok(ray(None, Some(1)))
    );
}

#[test]
fn viewpoint_inside_or_on_an_object_is_an_error() {
    let s = screen_scene();
    let s = s.as_ref();
    let not_free = |o| {
        Err(RefError::ViewpointNotFree {
            object: ObjectId(o),
        })
    };
    assert_eq!(view(s, &v(5, 0)).map(|_| ()), not_free(1)); // on A's left edge
    assert_eq!(
        view(s, &Vec2::from_ratios(11, 2, 0, 1)).map(|_| ()),
        not_free(1)
    ); // inside
    assert_eq!(view(s, &v(6, 1)).map(|_| ()), not_free(1)); // at a vertex
    assert_eq!(view(s, &v(2, 0)).map(|_| ()), not_free(0)); // on the screen
    assert_eq!(ray_tree(s, &v(3, 1), opts(2)).map(|_| ()), not_free(0));
    assert_eq!(shoot(s, &v(5, 1), &v(1, 0)).map(|_| ()), not_free(1));
    assert_eq!(
        shoot_perturbed(s, &v(5, 1), &v(1, 0)).map(|_| ()),
        not_free(1)
    );
    assert_eq!(
        trace_ray(s, &v(5, -1), &v(1, 0), opts(1)).map(|_| ()),
        not_free(1)
    );
    assert_eq!(
        shoot(s, &v(0, 0), &v(0, 0)).map(|_| ()),
        Err(RefError::ZeroDirection)
    );
}

/// Self-check of the sweep's refinement on small random grid scenes (many degeneracies:
/// integer vertices, viewpoints on edge extensions, all materials): every random primary
/// direction traces to the branch of the interval containing it, and neighbouring
/// intervals differ.
#[test]
fn random_directions_agree_with_their_interval() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let eta = |r: u32| Eta::from_raw(r).unwrap();
    for _ in 0..150 {
        // Objects in distinct 4 × 4 cells of a 3 × 3 grid, inside [1, 3] of their cell.
        let mut polys: Vec<(Material, Vec<(i32, i32)>)> = Vec::new();
        for cell in 0..9 {
            if rng.gen_bool(0.4) {
                continue;
            }
            let (cx, cy) = ((cell % 3) * 4, (cell / 3) * 4);
            let boxed = rng.gen_bool(0.5);
            let mut p = || (cx + rng.gen_range(1..=3), cy + rng.gen_range(1..=3));
            let (a, b) = (p(), p());
            let mut poly = if boxed {
                bx(a.0.min(b.0), a.1.min(b.1), a.0.max(b.0), a.1.max(b.1)).to_vec()
            } else {
                vec![a, b, p()]
            };
            let area = (poly[1].0 - poly[0].0) * (poly[2].1 - poly[0].1)
                - (poly[1].1 - poly[0].1) * (poly[2].0 - poly[0].0);
            if area == 0 {
                continue;
            }
            if area < 0 {
                poly.reverse();
            }
            let m = match rng.gen_range(0..4) {
                0 => Material::Opaque,
                1 => Material::Mirror,
                2 => Material::Refractive {
                    eta: eta(rng.gen_range(1 << 15..3 << 16)),
                },
                _ => Material::Screen,
            };
            polys.push((m, poly));
        }
        let list: Vec<(Material, &[(i32, i32)])> =
            polys.iter().map(|(m, p)| (*m, &p[..])).collect();
        let s = scene(&list);
        let q = v(rng.gen_range(-1..13), rng.gen_range(-1..13));
        let o = opts(rng.gen_range(0..3));
        let Ok(tree) = ray_tree(s.as_ref(), &q, o) else {
            continue; // viewpoint not free
        };
        let n = tree.len();
        for i in 0..n {
            assert!(n == 1 || tree[i].value != tree[(i + 1) % n].value);
            assert!(n == 1 || tree[i].start_vertex.is_some());
        }
        for _ in 0..20 {
            // Large components: a ray exactly through a vertex (where the trace is
            // ambiguous) is then all but impossible.
            let d = v(
                rng.gen_range(-1 << 40..1 << 40),
                rng.gen_range(-1 << 40..1 << 40),
            );
            if d.is_zero() || tree.iter().any(|i| i.start == d.primitive() && n > 1) {
                continue;
            }
            let k = tree
                .iter()
                .rposition(|i| vcx_tests::cmp_angle(&i.start, &d).is_le())
                .unwrap_or(n - 1);
            let tr = trace_ray(s.as_ref(), &q, &d, o).unwrap();
            assert_eq!(tr.branch, tree[k].value, "direction {d} in interval {k}");
        }
    }
}
