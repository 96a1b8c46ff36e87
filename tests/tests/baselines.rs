//! The ray casters of `vcx-baselines` (quadtree tracer, BVH on parry2d) against the exact
//! per-column coverage of the complex (itself checked against the reference in
//! `tests/render.rs`):
//! * both casters give the same branch for every ray (same narrow phase and optics, two
//!   acceleration structures);
//! * with `s` stratified samples (stratum centres) a column holding `b` exact boundaries
//!   is wrong by at most `b/(2s)` (a boundary at `u` in the column is counted at the
//!   nearest multiple of `1/s`), so the mean error shrinks with `s`; a column without
//!   boundary is exact;
//! * with one sample at the column centre the dominant branch is the exact one in every
//!   column without a boundary.
//!
//! A small share of columns (≤ 1 %) may break the bound: `f64` rays within rounding of a
//! boundary just outside a column, or the core's virtual eyes rounded to 2⁻³².

use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use vcx::partition::build_by_sweep;
use vcx::render::{coverage, Camera, CoverageTable, Interval};
use vcx::walk::ray_tree;
use vcx::Scene;
use vcx_baselines::{render, BvhCaster, Prepared, Quadtree};
use vcx_demo::generate::{generate, SceneKind};

mod common;
use common::random_point;

fn example(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../std-demo/scenes")
        .join(name);
    vcx_demo::scene_file::load(&path).unwrap().scene
}

/// Boundaries per column of the exact coverage.
fn boundaries<I: Interval>(camera: &Camera, intervals: &[I]) -> Vec<usize> {
    let mut b = vec![0usize; camera.width()];
    let mut pieces = vec![0usize; camera.width()];
    coverage(camera, intervals, |p| pieces[p.column] += 1);
    for (c, n) in pieces.iter().enumerate() {
        b[c] = n.saturating_sub(1);
    }
    b
}

#[derive(Default)]
struct Tally {
    frames: usize,
    columns: usize,
    violations: usize,
    centre_checked: usize,
    centre_wrong: usize,
}

fn check_scene(
    name: &str,
    scene: &Scene,
    depths: &[usize],
    points: usize,
    seed: u64,
    t: &mut Tally,
) {
    let s = scene.as_ref();
    let complex = build_by_sweep(&s).unwrap();
    let prepared = Prepared::new(&s);
    let quadtree = Quadtree::new(&prepared);
    let bvh = BvhCaster::new(&prepared);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut est_q, mut est_b) = (CoverageTable::new(), CoverageTable::new());
    for _ in 0..points {
        let q = random_point(&mut rng, &s);
        for &depth in depths {
            let Ok(tree) = ray_tree(&complex, &s, q, depth) else {
                continue;
            };
            let heading = rng.gen_range(0.0..core::f64::consts::TAU);
            let fov = rng.gen_range(20.0f64..120.0).to_radians();
            let camera = Camera::new(q, heading, fov, 96).unwrap();
            let exact = CoverageTable::exact(&camera, &tree);
            let b = boundaries(&camera, &tree);
            let mut errors = Vec::new();
            for samples in [1, 4, 16, 64] {
                render(&prepared, &quadtree, &camera, samples, depth, &mut est_q);
                render(&prepared, &bvh, &camera, samples, depth, &mut est_b);
                assert_eq!(est_q, est_b, "{name} depth {depth} q {q:?}: casters differ");
                assert_eq!(est_q.columns(), camera.width());
                for (c, &bc) in b.iter().enumerate() {
                    let sum: f64 = est_q.column(c).iter().map(|e| e.1).sum();
                    assert!((sum - 1.0).abs() < 1e-9);
                    let one = |t: &CoverageTable| {
                        let mut x = CoverageTable::new();
                        for (br, f) in t.column(c) {
                            x.push(br, *f);
                        }
                        x.end_column();
                        x
                    };
                    let (err, _) = one(&est_q).error_against(&one(&exact));
                    t.columns += 1;
                    if err > bc as f64 / (2.0 * samples as f64) + 1e-9 {
                        t.violations += 1;
                    }
                    if samples == 1 && bc == 0 {
                        t.centre_checked += 1;
                        if est_q.dominant(c) != exact.dominant(c) {
                            t.centre_wrong += 1;
                        }
                    }
                }
                errors.push(est_q.error_against(&exact).0);
            }
            // The mean error shrinks with the samples (the bound b/(2s), on average).
            let mean_b = b.iter().sum::<usize>() as f64 / b.len() as f64;
            for (k, s) in [1.0, 4.0, 16.0, 64.0].into_iter().enumerate() {
                assert!(
                    errors[k] <= mean_b / (2.0 * s) + 0.01,
                    "{name} depth {depth} q {q:?}: error {errors:?}, boundaries per column {mean_b}"
                );
            }
            t.frames += 1;
        }
    }
}

fn assert_tally(t: &Tally, min_frames: usize) {
    eprintln!(
        "{} frames, {} of {} columns beyond b/(2s), {} of {} boundary-free centres wrong",
        t.frames, t.violations, t.columns, t.centre_wrong, t.centre_checked
    );
    assert!(t.frames >= min_frames, "only {} frames", t.frames);
    assert!(
        t.violations * 100 <= t.columns,
        "{} of {} columns beyond the b/(2s) bound",
        t.violations,
        t.columns
    );
    assert!(
        t.centre_wrong * 100 <= t.centre_checked,
        "{} of {} boundary-free columns with a wrong dominant branch at 1 sample",
        t.centre_wrong,
        t.centre_checked
    );
}

#[test]
fn casters_converge_to_the_exact_coverage_on_random_scenes() {
    let mut t = Tally::default();
    for (k, kind) in [SceneKind::Grid, SceneKind::Hall, SceneKind::Mixed]
        .into_iter()
        .enumerate()
    {
        for seed in 0..2u64 {
            let scene = generate(kind, 16, seed).unwrap().scene;
            check_scene(
                &format!("{kind:?} {seed}"),
                &scene,
                &[0, 3],
                3,
                10 * k as u64 + seed,
                &mut t,
            );
        }
    }
    assert_tally(&t, 20);
}

#[test]
fn casters_converge_to_the_exact_coverage_on_the_example_scenes() {
    let mut t = Tally::default();
    for (i, name) in ["grid.json", "hall.json", "mixed.json"]
        .into_iter()
        .enumerate()
    {
        check_scene(name, &example(name), &[0, 5], 4, 100 + i as u64, &mut t);
    }
    assert_tally(&t, 15);
}

#[test]
fn quadtree_leaves_hold_at_most_one_object_and_find_every_hit() {
    // Every ray of a 360° fan finds the same nearest object by the quadtree, the BVH and
    // a scan of all objects.
    let scene = example("mixed.json");
    let s = scene.as_ref();
    let p = Prepared::new(&s);
    let (qt, bvh) = (Quadtree::new(&p), BvhCaster::new(&p));
    assert_eq!(qt.max_leaf_objects(), 1);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    use vcx_baselines::Caster;
    let mut hits = 0;
    for _ in 0..2000 {
        let o = random_point(&mut rng, &s).to_f64();
        let a: f64 = rng.gen_range(0.0..core::f64::consts::TAU);
        let d = (a.cos(), a.sin());
        let scan = (0..p.objects.len() as u32)
            .filter(|&i| p.kind(i) != vcx_baselines::Kind::Screen)
            .filter_map(|i| p.enter(i, o, d))
            .min_by(|x, y| x.t.total_cmp(&y.t));
        // Points inside an object see nothing from the inside; skip them.
        let inside = (0..p.objects.len() as u32).any(|i| {
            let obj = &p.objects[i as usize];
            p.kind(i) != vcx_baselines::Kind::Screen
                && (0..obj.len).all(|k| {
                    let e = &p.edges[(obj.first + k) as usize];
                    e.n.0 * o.0 + e.n.1 * o.1 < e.c
                })
        });
        if inside {
            continue;
        }
        assert_eq!(
            qt.nearest(&p, o, d, None),
            scan,
            "quadtree from {o:?} along {d:?}"
        );
        assert_eq!(
            bvh.nearest(&p, o, d, None),
            scan,
            "bvh from {o:?} along {d:?}"
        );
        hits += usize::from(scan.is_some());
    }
    assert!(hits > 1000);
}
