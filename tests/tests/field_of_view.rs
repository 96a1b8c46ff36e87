//! A field of view (`walk::view_range`) is exactly the restriction of the full-circle view:
//! checked against the exact reference's full view restricted here in big rationals, with
//! range ends at random directions, at the directions of scene vertices (boundaries, and
//! directions exactly along them that are not boundaries), at θ = 0 and the full circle
//! (`from == to`).

use num_traits::{Signed, Zero};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use vcx::geom::predicates::Direction;
use vcx::partition::build_by_sweep;
use vcx::walk::view_range;
use vcx::{Material, ObjectId, QueryPoint, SceneRef, SubScene};
use vcx_demo::generate::{generate, SceneKind};
use vcx_tests::generators::{same_direction, written_vertex};
use vcx_tests::reference::{self, Vec2};

fn long() -> bool {
    std::env::var_os("VCX_LONG").is_some()
}

fn vec2(d: Direction) -> Vec2 {
    Vec2::from_i64(d.x, d.y)
}

/// Counter-clockwise order on `[0, 2π)` from +x.
fn angle_cmp(a: &Vec2, b: &Vec2) -> core::cmp::Ordering {
    let upper = |v: &Vec2| v.y.is_positive() || (v.y.is_zero() && v.x.is_positive());
    match (upper(a), upper(b)) {
        (true, false) => core::cmp::Ordering::Less,
        (false, true) => core::cmp::Ordering::Greater,
        _ => {
            let c = a.cross(b);
            if c.is_positive() {
                core::cmp::Ordering::Less
            } else if c.is_zero() {
                core::cmp::Ordering::Equal
            } else {
                core::cmp::Ordering::Greater
            }
        }
    }
}

/// The reference's full view restricted to `(from, to)`: (start, object, vertex).
type Row = (Vec2, Option<ObjectId>, Option<(u32, usize)>);

fn restrict(full: &[reference::Interval<Option<ObjectId>>], from: &Vec2, to: &Vec2) -> Vec<Row> {
    use core::cmp::Ordering::*;
    let lap = |a: &Vec2| u8::from(angle_cmp(a, from) == Less);
    let lap_to = if angle_cmp(to, from) == Greater { 0 } else { 1 };
    let n = full.len();
    // Boundaries: every start when there is more than one interval.
    let k = if n == 1 {
        0
    } else {
        full.iter()
            .rposition(|i| angle_cmp(&i.start, from) != Greater)
            .unwrap_or(n - 1)
    };
    let first = &full[k];
    let on_from = n > 1 && angle_cmp(&first.start, from) == Equal;
    let mut rows = vec![(
        from.clone(),
        first.value,
        if on_from {
            first.start_vertex.map(|v| (v.object.0, v.vertex))
        } else {
            None
        },
    )];
    // Around to the containing interval's own start (the full circle), unless on `from`.
    for j in 1..=n {
        let i = &full[(k + j) % n];
        let l = lap(&i.start);
        if n == 1
            || (j == n && on_from)
            || !(l < lap_to || (l == lap_to && angle_cmp(&i.start, to) == Less))
        {
            break;
        }
        rows.push((
            i.start.clone(),
            i.value,
            i.start_vertex.map(|v| (v.object.0, v.vertex)),
        ));
    }
    rows
}

/// Compares `view_range` from `q` over `(from, to)` with the reference's full view
/// restricted there.
#[allow(clippy::too_many_arguments)]
fn check(
    c: &vcx::partition::Complex,
    s: &SceneRef<'_>,
    sub: &SubScene<'_>,
    q: QueryPoint,
    full: &[reference::Interval<Option<ObjectId>>],
    from: Direction,
    to: Direction,
    what: &str,
) {
    let sr = sub.as_ref();
    let want = restrict(full, &vec2(from), &vec2(to));
    let got = view_range(c, &sr, q, from, to).unwrap();
    let show =
        || format!("{what} q {q:?} from {from:?} to {to:?}\n core {got:#?}\n want {want:#?}");
    assert_eq!(got.len(), want.len(), "{}", show());
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g.object.and_then(|o| sub.original(o)), w.1, "{}", show());
        assert!(same_direction(g.start.vector(), &w.0), "{}", show());
        assert_eq!(
            g.start_vertex.and_then(|k| written_vertex(s, k)),
            w.2,
            "{}",
            show()
        );
    }
}

/// The objects of `s` that are not screens (a primary view looks through screens).
fn not_screens(s: &SceneRef<'_>) -> Vec<ObjectId> {
    s.objects()
        .iter()
        .enumerate()
        .filter(|(_, o)| o.material != Material::Screen)
        .map(|(i, _)| ObjectId(i as u32))
        .collect()
}

#[test]
fn field_of_view_is_the_restriction_of_the_full_view() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut compared = 0;
    let per_scene = if long() { 400 } else { 30 };
    for (kind, n, seed) in [
        (SceneKind::Grid, 16, 1),
        (SceneKind::Grid, 64, 2),
        (SceneKind::Mixed, 12, 3),
        (SceneKind::Hall, 6, 4),
    ] {
        let file = generate(kind, n, seed).unwrap();
        let s = file.scene.as_ref();
        let sub = SubScene::new(s, not_screens(&s));
        let sr = sub.as_ref();
        let c = build_by_sweep(&sr).unwrap();
        let verts = s.vertices();
        let (lo, hi) = verts.iter().fold(
            ((i32::MAX, i32::MAX), (i32::MIN, i32::MIN)),
            |(lo, hi), p| {
                (
                    (lo.0.min(p.x()), lo.1.min(p.y())),
                    (hi.0.max(p.x()), hi.1.max(p.y())),
                )
            },
        );
        for k in 0..per_scene {
            let q = if k % 2 == 0 {
                QueryPoint::from_raw(
                    i64::from(rng.gen_range(lo.0..=hi.0)) << 16,
                    i64::from(rng.gen_range(lo.1..=hi.1)) << 16,
                )
            } else {
                // On the line through two vertices: boundaries through several vertices.
                let (a, b) = (
                    verts[rng.gen_range(0..verts.len())],
                    verts[rng.gen_range(0..verts.len())],
                );
                let t = rng.gen_range(-2i64..=3);
                QueryPoint::from_raw(
                    (i64::from(a.x()) + t * (i64::from(b.x()) - i64::from(a.x()))) << 16,
                    (i64::from(a.y()) + t * (i64::from(b.y()) - i64::from(a.y()))) << 16,
                )
            };
            let Some(q) = q else { continue };
            let Ok(full) = reference::view(s, &Vec2::from_query(q)) else {
                continue;
            };
            // Range ends: random, toward a vertex (often a boundary), +x, equal ends.
            let toward = |rng: &mut ChaCha8Rng| {
                let v = verts[rng.gen_range(0..verts.len())].to_query();
                Direction::new(v.x() - q.x(), v.y() - q.y())
            };
            for r in 0..6 {
                let pick = |rng: &mut ChaCha8Rng| match rng.gen_range(0..4) {
                    0 => Direction::new(rng.gen_range(-9..=9), rng.gen_range(-9..=9)),
                    1 | 2 => toward(rng),
                    _ => Direction::new(1, 0),
                };
                let (Some(from), Some(to)) = (pick(&mut rng), pick(&mut rng)) else {
                    continue;
                };
                let to = if r == 0 { from } else { to };
                check(&c, &s, &sub, q, &full, from, to, &format!("{kind:?}"));
                compared += 1;
            }
        }
    }
    assert!(compared > 500, "{compared}");
}

/// Ranges that start or end exactly on the direction of a vertex (a boundary, or a ray
/// along which a vertex lies that is not one) or exactly opposite it, of lengths that
/// walk there from θ = 0 either way round.
#[test]
fn field_of_view_from_vertex_directions() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut compared = 0;
    for (kind, n, seed) in [
        (SceneKind::Grid, 16, 1),
        (SceneKind::Mixed, 12, 3),
        (SceneKind::Hall, 6, 4),
    ] {
        let file = generate(kind, n, seed).unwrap();
        let s = file.scene.as_ref();
        let sub = SubScene::new(s, not_screens(&s));
        let c = build_by_sweep(&sub.as_ref()).unwrap();
        let verts = s.vertices();
        for k in 0..6 {
            // On the line through two vertices every other time.
            let (a, b) = (
                verts[rng.gen_range(0..verts.len())],
                verts[rng.gen_range(0..verts.len())],
            );
            let t = if k % 2 == 0 {
                rng.gen_range(1i64..=9)
            } else {
                rng.gen_range(-2i64..=3) * 16
            };
            let Some(q) = QueryPoint::from_raw(
                (i64::from(a.x()) << 16) + t * (i64::from(b.x()) - i64::from(a.x())) * 4096,
                (i64::from(a.y()) << 16) + t * (i64::from(b.y()) - i64::from(a.y())) * 4096,
            ) else {
                continue;
            };
            let Ok(full) = reference::view(s, &Vec2::from_query(q)) else {
                continue;
            };
            for v in verts {
                let v = v.to_query();
                let Some(d) = Direction::new(v.x() - q.x(), v.y() - q.y()) else {
                    continue;
                };
                let turn = |d: Direction, a: i64, b: i64| {
                    Direction::new(a * d.x - b * d.y, b * d.x + a * d.y)
                };
                for from in [d, Direction::new(-d.x, -d.y).unwrap()] {
                    let ranges = [
                        turn(from, 0, 1),
                        turn(from, 8, 1),
                        turn(from, -1, 1),
                        turn(from, -8, -1),
                    ];
                    for to in ranges.into_iter().flatten() {
                        check(&c, &s, &sub, q, &full, from, to, &format!("{kind:?}"));
                        check(&c, &s, &sub, q, &full, to, from, &format!("{kind:?}"));
                        compared += 2;
                    }
                }
            }
        }
    }
    assert!(compared > 2000, "{compared}");
}
