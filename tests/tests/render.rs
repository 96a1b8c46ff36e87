//! Per-column hits and exact coverage (`vcx::render`) against the exact reference.
//!
//! For views (depth 0) and ray trees (depth 1–5, reference with rounded eyes), on random
//! scenes of the three generators and the example scenes, from random viewpoints, headings
//! and fields of view, at widths 1, 7 and 800:
//! * every column's fractions sum to 1;
//! * the coverage per column equals the one built independently from the reference's
//!   intervals: each reference boundary strictly inside a column's arc (decided with big
//!   rationals against the camera's integer column edges) splits it at its image
//!   coordinate, and the pieces between see the reference's objects;
//! * the interval found at each column centre sees what the reference sees there;
//! * the dominant branch of a column is the reference's object at the column centre
//!   wherever the column holds no boundary.
//!
//! `VCX_LONG=1` multiplies the number of viewpoints.

use std::collections::BTreeMap;
use std::path::Path;

use num_traits::Signed;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use vcx::partition::{build_by_sweep, Complex};
use vcx::render::{centre_intervals, Camera, CoverageTable, Interval};
use vcx::walk::{ray_tree, view};
use vcx::{Material, ObjectId, QueryPoint, Scene, SubScene};
use vcx_demo::generate::{generate, SceneKind};
use vcx_tests::reference::{self, cmp_angle, RayTreeOptions, Vec2};

mod common;
use common::random_point;

fn scale(n: usize) -> usize {
    if std::env::var_os("VCX_LONG").is_some() {
        n * 20
    } else {
        n
    }
}

/// A reference sweep: (start direction, branch) per interval, sorted by angle.
type RefSweep = Vec<(Vec2, Vec<ObjectId>)>;

fn edge_vec(camera: &Camera, c: usize) -> Vec2 {
    let v = camera.edge(c).vector;
    Vec2::from_i64(v.0, v.1)
}

/// Index of the reference interval containing direction `d` (a direction on a boundary
/// belongs to the interval starting there).
fn ref_at(sweep: &RefSweep, d: &Vec2) -> usize {
    let p = sweep.partition_point(|(s, _)| cmp_angle(s, d) != core::cmp::Ordering::Greater);
    if p == 0 {
        sweep.len() - 1
    } else {
        p - 1
    }
}

/// Column `c`'s coverage by branch, from the reference alone.
fn expected_column(camera: &Camera, sweep: &RefSweep, c: usize) -> BTreeMap<Vec<u32>, f64> {
    let (l, r) = (edge_vec(camera, c), edge_vec(camera, c + 1));
    let (xl, xr) = (camera.edge(c).x, camera.edge(c + 1).x);
    let mut out = BTreeMap::new();
    let key = |b: &Vec<ObjectId>| b.iter().map(|o| o.0).collect::<Vec<u32>>();
    if sweep.len() == 1 {
        out.insert(key(&sweep[0].1), 1.0);
        return out;
    }
    // Boundaries strictly inside the arc (r, l) (< π wide), counter-clockwise from r.
    let mut inside: Vec<usize> = (0..sweep.len())
        .filter(|&i| {
            let s = &sweep[i].0;
            r.cross(s).is_positive() && s.cross(&l).is_positive()
        })
        .collect();
    inside.sort_by(|&a, &b| {
        let c = sweep[a].0.cross(&sweep[b].0);
        if c.is_positive() {
            core::cmp::Ordering::Less
        } else {
            core::cmp::Ordering::Greater
        }
    });
    let mut cur = ref_at(sweep, &r);
    let mut x = xr;
    for i in inside {
        let s = sweep[i].0.to_f64();
        let xb = camera.image_x(s).clamp(xl, x);
        *out.entry(key(&sweep[cur].1)).or_insert(0.0) += (x - xb) / (xr - xl);
        x = xb;
        cur = i;
    }
    *out.entry(key(&sweep[cur].1)).or_insert(0.0) += (x - xl) / (xr - xl);
    out.retain(|_, f| *f > 0.0);
    out
}

fn got_column(t: &CoverageTable, c: usize) -> BTreeMap<Vec<u32>, f64> {
    let mut m = BTreeMap::new();
    for (b, f) in t.column(c) {
        *m.entry(b.iter().map(|o| o.0).collect::<Vec<u32>>())
            .or_insert(0.0) += *f;
    }
    m
}

/// Compares the core's coverage and centre hits with the reference's sweep.
fn compare<I: Interval>(name: &str, camera: &Camera, intervals: &[I], sweep: &RefSweep, tol: f64) {
    let w = camera.width();
    let table = CoverageTable::exact(camera, intervals);
    assert_eq!(table.columns(), w, "{name}");
    let mut centre = vec![0; w];
    centre_intervals(camera, intervals, &mut centre);
    for c in 0..w {
        let got = got_column(&table, c);
        let sum: f64 = got.values().sum();
        assert!((sum - 1.0).abs() < 1e-9, "{name} column {c}: sum {sum}");
        let want = expected_column(camera, sweep, c);
        for k in got.keys().chain(want.keys()) {
            let (g, e) = (
                got.get(k).copied().unwrap_or(0.0),
                want.get(k).copied().unwrap_or(0.0),
            );
            assert!(
                (g - e).abs() <= tol,
                "{name} column {c} of {w}: branch {k:?}: core {g}, reference {e}\n core {got:?}\n reference {want:?}"
            );
        }
        // The centre, unless it lies (nearly) on a boundary known in f64 only.
        let cv = camera.centre(c).vector;
        let cv = Vec2::from_i64(cv.0, cv.1);
        let cx = camera.image_x(cv.to_f64());
        let near = sweep.iter().any(|(s, _)| {
            s == &cv || (tol > 0.0 && (camera.image_x(s.to_f64()) - cx).abs() < 1e-9)
        });
        if near {
            continue;
        }
        let want_branch = &sweep[ref_at(sweep, &cv)].1;
        let got_branch = intervals[centre[c]].branch();
        assert_eq!(got_branch, &want_branch[..], "{name} column {c}: centre");
        if want.len() == 1 {
            let dominant: Vec<ObjectId> = table.dominant(c).unwrap().iter().copied().collect();
            assert_eq!(&dominant, want_branch, "{name} column {c}: dominant");
        }
    }
}

fn random_camera(rng: &mut ChaCha8Rng, q: QueryPoint, width: usize) -> Camera {
    let heading = rng.gen_range(0.0..core::f64::consts::TAU);
    let fov = rng.gen_range(5.0f64..175.0).to_radians();
    Camera::new(q, heading, fov, width).unwrap()
}

/// Views (depth 0) over the scene without its screens.
fn views(name: &str, scene: &Scene, points: usize, seed: u64) -> usize {
    let full = scene.as_ref();
    let ids = full
        .objects()
        .iter()
        .enumerate()
        .filter(|(_, o)| o.material != Material::Screen)
        .map(|(i, _)| ObjectId(i as u32));
    let sub = SubScene::new(full, ids);
    let s = sub.as_ref();
    let complex = build_by_sweep(&s).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut done = 0;
    for _ in 0..points {
        let q = random_point(&mut rng, &s);
        let Ok(v) = view(&complex, &s, q) else {
            continue;
        };
        let sweep: RefSweep = reference::view(s, &Vec2::from_query(q))
            .unwrap()
            .into_iter()
            .map(|i| (i.start, i.value.into_iter().collect()))
            .collect();
        for width in [1, 7, 800] {
            let camera = random_camera(&mut rng, q, width);
            compare(
                &format!("{name} view q {q:?} {camera:?}"),
                &camera,
                &v,
                &sweep,
                1e-9,
            );
            done += 1;
        }
    }
    done
}

/// Ray trees over the whole scene against the reference with rounded eyes.
fn trees(
    name: &str,
    scene: &Scene,
    complex: &Complex,
    depths: &[usize],
    points: usize,
    seed: u64,
) -> usize {
    let s = scene.as_ref();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut done = 0;
    for _ in 0..points {
        let q = random_point(&mut rng, &s);
        for &depth in depths {
            let want = reference::ray_tree(
                s,
                &Vec2::from_query(q),
                RayTreeOptions {
                    depth,
                    round_eyes: true,
                },
            );
            let (Ok(want), Ok(got)) = (want, ray_tree(complex, &s, q, depth)) else {
                continue;
            };
            let sweep: RefSweep = want.into_iter().map(|i| (i.start, i.value)).collect();
            for width in [1, 7, 800] {
                let camera = random_camera(&mut rng, q, width);
                let n = format!("{name} depth {depth} q {q:?} {camera:?}");
                compare(&n, &camera, &got, &sweep, 1e-6);
                done += 1;
            }
        }
    }
    done
}

fn example(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../std-demo/scenes")
        .join(name);
    vcx_demo::scene_file::load(&path).unwrap().scene
}

#[test]
fn views_match_the_reference_on_random_scenes() {
    let mut done = 0;
    for (k, kind) in [SceneKind::Grid, SceneKind::Hall, SceneKind::Mixed]
        .into_iter()
        .enumerate()
    {
        for seed in 0..3u64 {
            let scene = generate(kind, 12, seed).unwrap().scene;
            done += views(
                &format!("{kind:?} {seed}"),
                &scene,
                scale(3),
                100 * k as u64 + seed,
            );
        }
    }
    assert!(done > 40, "only {done} frames compared");
}

#[test]
fn views_match_the_reference_on_the_example_scenes() {
    let mut done = 0;
    for (i, name) in ["grid.json", "hall.json", "mixed.json"]
        .into_iter()
        .enumerate()
    {
        done += views(name, &example(name), scale(3), 7 + i as u64);
    }
    assert!(done > 15, "only {done} frames compared");
}

#[test]
fn ray_trees_match_the_reference() {
    let mut done = 0;
    // The reference is slow deep down (minutes per viewpoint at depth 5 on the mixed
    // scene): one viewpoint of the hall of mirrors at depth 3 (5 with `VCX_LONG`), shallower
    // trees elsewhere.
    let long = std::env::var_os("VCX_LONG").is_some();
    let (hall, mixed) = if long { (5, 3) } else { (3, 2) };
    for (i, (name, deep)) in [("hall.json", hall), ("mixed.json", mixed)]
        .into_iter()
        .enumerate()
    {
        let scene = example(name);
        let complex = build_by_sweep(&scene.as_ref()).unwrap();
        done += trees(name, &scene, &complex, &[deep], scale(1), 11 + i as u64);
        done += trees(name, &scene, &complex, &[1], scale(2), 21 + i as u64);
    }
    for seed in 0..2u64 {
        let scene = generate(SceneKind::Mixed, 10, seed).unwrap().scene;
        let complex = build_by_sweep(&scene.as_ref()).unwrap();
        done += trees(
            &format!("mixed {seed}"),
            &scene,
            &complex,
            &[2],
            scale(2),
            50 + seed,
        );
    }
    assert!(done > 10, "only {done} frames compared");
}

#[test]
fn camera_edges_are_ordered_and_cover_the_field_of_view() {
    let q = QueryPoint::from_f64(0.5, 0.25).unwrap();
    for (heading, fov, w) in [
        (0.0, 1.0, 1),
        (2.0, 3.1, 7),
        (4.0, 0.01, 800),
        (6.2, 1.5, 800),
    ] {
        let cam = Camera::new(q, heading, fov, w).unwrap();
        for c in 0..w {
            let (a, b) = (cam.edge(c), cam.edge(c + 1));
            assert!(a.x < b.x);
            let cross = i128::from(a.vector.0) * i128::from(b.vector.1)
                - i128::from(a.vector.1) * i128::from(b.vector.0);
            assert!(cross < 0, "edges turn clockwise from left to right");
        }
        let half = (fov / 2.0).tan();
        assert!((cam.edge(0).x + half).abs() < 1e-9 * half.max(1.0));
        assert!((cam.edge(w).x - half).abs() < 1e-9 * half.max(1.0));
    }
    assert!(Camera::new(q, 0.0, 0.0, 10).is_err());
    assert!(Camera::new(q, 0.0, 3.2, 10).is_err());
    assert!(Camera::new(q, 0.0, 1.0, 0).is_err());
    assert!(Camera::new(q, f64::NAN, 1.0, 10).is_err());
}

#[test]
fn hits_follow_the_branch() {
    // Along the column centres of a hall view, the first distance equals the distance to
    // the reference's first hit point, and the unfolded length is at least that.
    let scene = example("hall.json");
    let s = scene.as_ref();
    let complex = build_by_sweep(&s).unwrap();
    let q = QueryPoint::from_f64(20.3, 20.1).unwrap();
    let tree = ray_tree(&complex, &s, q, 3).unwrap();
    let camera = Camera::new(q, 0.7, 1.6, 64).unwrap();
    let mut centre = vec![0; 64];
    centre_intervals(&camera, &tree, &mut centre);
    let mut checked = 0;
    for (c, &i) in centre.iter().enumerate() {
        let dir = camera.centre(c).vector;
        let tr = reference::trace_ray(
            s,
            &Vec2::from_query(q),
            &Vec2::from_i64(dir.0, dir.1),
            RayTreeOptions {
                depth: 3,
                round_eyes: true,
            },
        )
        .unwrap();
        let Some(hit) =
            vcx::render::hit_along(&s, q, camera.centre(c).direction(), &tree[i].branch)
        else {
            continue;
        };
        let p = tr.stages[0].hit.as_ref().unwrap().point.to_f64();
        let (qx, qy) = q.to_f64();
        let d = (p.0 - qx).hypot(p.1 - qy);
        assert!(
            (hit.first - d).abs() < 1e-6 * d.max(1.0),
            "column {c}: {} vs {d}",
            hit.first
        );
        assert!(hit.length >= hit.first - 1e-9);
        assert!((0.0..=1.0).contains(&hit.facing));
        checked += 1;
    }
    assert!(checked > 50);
}

/// Relative difference of two distances.
fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1.0)
}

/// Checks the hit `got` along the integer direction `v` from `q` on `branch`: a fresh
/// `Hits` and `hit_along` agree with it, and so does the reference's traced ray when it
/// follows the same branch. Returns (traced, through a refractive object).
fn check_hit(
    n: &str,
    s: &vcx::SceneRef<'_>,
    q: QueryPoint,
    depth: usize,
    v: (i64, i64),
    branch: &[ObjectId],
    got: Option<vcx::render::Hit>,
) -> (bool, bool) {
    let dir = (v.0 as f64, v.1 as f64);
    let fresh = vcx::render::Hits::new().along(s, q, dir, branch);
    let plain = vcx::render::hit_along(s, q, dir, branch);
    let g = match (got, fresh, plain) {
        (Some(g), Some(f), Some(p)) => {
            assert!(rel(g.first, f.first) < 1e-9, "{n}: {g:?} vs fresh {f:?}");
            assert!(rel(g.length, f.length) < 1e-9, "{n}: {g:?} vs fresh {f:?}");
            assert!(
                (g.facing - f.facing).abs() < 1e-9,
                "{n}: {g:?} vs fresh {f:?}"
            );
            assert!(rel(g.first, p.first) < 1e-9, "{n}: {g:?} vs {p:?}");
            assert!(rel(g.length, p.length) < 1e-9, "{n}: {g:?} vs {p:?}");
            assert!((g.facing - p.facing).abs() < 1e-6, "{n}: {g:?} vs {p:?}");
            g
        }
        (None, None, None) => return (false, false),
        other => panic!("{n}: {other:?}"),
    };
    let tr = reference::trace_ray(
        *s,
        &Vec2::from_query(q),
        &Vec2::from_i64(v.0, v.1),
        RayTreeOptions {
            depth,
            round_eyes: true,
        },
    )
    .unwrap();
    if tr.degenerate || tr.branch != branch {
        return (false, false);
    }
    // `Hit::length` ends where the ray enters the last object of the branch.
    let stages: Vec<_> = tr
        .stages
        .iter()
        .filter(|st| st.hit.is_some() && !(st.inside && st.level + 1 == branch.len()))
        .collect();
    let dist = |st: &reference::Stage| {
        let (p, o) = (st.hit.as_ref().unwrap().point.to_f64(), st.origin.to_f64());
        (p.0 - o.0).hypot(p.1 - o.1)
    };
    let length: f64 = stages.iter().map(|st| dist(st)).sum();
    let first = dist(stages[0]);
    assert!(
        rel(g.first, first) < 1e-6,
        "{n}: first {} vs {first}",
        g.first
    );
    assert!(
        rel(g.length, length) < 1e-4,
        "{n}: length {} vs {length}",
        g.length
    );
    (true, stages.iter().any(|st| st.inside))
}

/// `render::centre_hits` (the merged sweep of column centres and boundaries, with hits
/// through one `Hits`) against `centre_intervals`, `hit_along` and the reference's traced
/// rays: ray trees of the hall of mirrors and of the mixed scene (mirrors and refractive
/// objects) from random viewpoints and cameras. A `Hits` fed the columns in a shuffled
/// order, and one fed rays across each interval, give the same hits as a fresh one.
#[test]
fn centre_hits_match_hit_along_and_the_reference() {
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    let (mut columns, mut traced, mut refracted) = (0, 0, 0);
    for (name, depth, points) in [
        ("hall.json", 5, 2),
        ("mixed.json", 3, 6),
        ("grid.json", 0, 2),
    ] {
        let scene = example(name);
        let s = scene.as_ref();
        let complex = build_by_sweep(&s).unwrap();
        for _ in 0..scale(points) {
            let q = random_point(&mut rng, &s);
            let Ok(tree) = ray_tree(&complex, &s, q, depth) else {
                continue;
            };
            let width = [1, 7, 300][rng.gen_range(0..3)];
            let camera = random_camera(&mut rng, q, width);
            let mut centre = vec![0; width];
            centre_intervals(&camera, &tree, &mut centre);
            let mut got = vec![None; width];
            let mut order = Vec::new();
            vcx::render::centre_hits(&s, &camera, &tree, |c, k, hit| {
                assert_eq!(k, centre[c], "{name} q {q:?} column {c}: interval");
                got[c] = hit;
                order.push(c);
            });
            assert_eq!(
                order,
                (0..width).collect::<Vec<_>>(),
                "{name}: column order"
            );
            let mut shuffled: Vec<usize> = (0..width).collect();
            for i in (1..width).rev() {
                shuffled.swap(i, rng.gen_range(0..=i));
            }
            let mut hits = vcx::render::Hits::new();
            for c in shuffled {
                let branch = &tree[centre[c]].branch;
                let v = camera.centre(c).vector;
                let n = format!("{name} q {q:?} {camera:?} column {c} branch {branch:?}");
                let again = hits.along(&s, q, camera.centre(c).direction(), branch);
                check_hit(&n, &s, q, depth, v, branch, again);
                let (t, r) = check_hit(&n, &s, q, depth, v, branch, got[c]);
                columns += 1;
                traced += usize::from(t);
                refracted += usize::from(r);
            }
            // Rays across the middle of each interval narrower than π, in turn.
            let mut hits = vcx::render::Hits::new();
            for (i, iv) in tree.iter().enumerate() {
                let next = tree
                    .get(i + 1)
                    .map_or(tree[0].start + core::f64::consts::TAU, |x| x.start);
                if next - iv.start >= core::f64::consts::PI || next <= iv.start {
                    continue;
                }
                for k in 1..4 {
                    let a = iv.start + (next - iv.start) * (0.25 + 0.5 * f64::from(k) / 4.0);
                    let v = ((a.cos() * 1e12) as i64, (a.sin() * 1e12) as i64);
                    let got = hits.along(&s, q, (v.0 as f64, v.1 as f64), &iv.branch);
                    let n = format!("{name} q {q:?} interval {i} ray {k} branch {:?}", iv.branch);
                    let (t, r) = check_hit(&n, &s, q, depth, v, &iv.branch, got);
                    traced += usize::from(t);
                    refracted += usize::from(r);
                }
            }
        }
    }
    eprintln!("{columns} columns, {traced} traced, {refracted} through a refractive object");
    assert!(
        columns > 200 && traced > 500,
        "{columns} columns, {traced} traced"
    );
    assert!(
        refracted > 20,
        "{refracted} rays through a refractive object"
    );
}
