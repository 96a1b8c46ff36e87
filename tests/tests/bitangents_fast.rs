//! Free-bitangent enumeration: the kinetic sweep used by `build_by_sweep`
//! (`vcx::line_space::free_bitangents`) against the brute force (every vertex pair of every
//! object pair, each tested against every object), on random grid, mixed and hall scenes
//! and on collinear box lattices (shared supporting lines everywhere).

use std::time::Instant;

use vcx::line_space::{bitangents, free_bitangents, is_free, Bitangent};
use vcx::partition::build_by_sweep;
use vcx::{Material, ObjectId, Point, Scene, SceneRef};
use vcx_demo::generate::{generate, SceneKind};

fn pt(x: i32, y: i32) -> Point {
    Point::from_raw(x << 16, y << 16).unwrap()
}

fn scene(polys: &[Vec<Point>]) -> Scene {
    Scene::new(polys.iter().map(|p| (Material::Opaque, &p[..]))).unwrap()
}

fn boxes(cells: &[(i32, i32)], size: i32, gap: i32) -> Scene {
    let polys: Vec<Vec<Point>> = cells
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
        .collect();
    scene(&polys)
}

/// The definition, sorted by θ (as `build_by_sweep` sorted it before).
fn brute_force(s: SceneRef<'_>) -> Vec<Bitangent> {
    let n = s.len() as u32;
    let mut out: Vec<Bitangent> = (0..n)
        .flat_map(|a| (a + 1..n).map(move |b| (ObjectId(a), ObjectId(b))))
        .flat_map(|(a, b)| bitangents(s, a, b).filter(|t| is_free(&s, t)))
        .collect();
    out.sort_by(|a, b| a.angle(&s).cmp_angle(&b.angle(&s)));
    out
}

fn check(name: &str, s: &Scene) -> usize {
    let s = s.as_ref();
    let want = brute_force(s);
    let got = free_bitangents(&s);
    assert_eq!(got.len(), want.len(), "{name}: count");
    assert_eq!(got, want, "{name}: set or order");
    let c = build_by_sweep(&s).unwrap();
    let from_complex: Vec<Bitangent> = c.vertices().iter().map(|v| v.bitangent).collect();
    assert_eq!(from_complex, want, "{name}: complex vertices");
    want.len()
}

#[test]
fn generated_scenes_match_the_brute_force() {
    let mut total = 0;
    for (kind, sizes, seeds) in [
        (
            SceneKind::Grid,
            &[1u32, 2, 3, 4, 9, 16, 30, 64, 100][..],
            0..6u64,
        ),
        (SceneKind::Mixed, &[4, 10, 20, 40][..], 0..6),
        (SceneKind::Hall, &[0, 1, 3, 6, 12][..], 0..6),
        (SceneKind::Grid, &[256][..], 0..2),
        (SceneKind::Mixed, &[150][..], 0..2),
    ] {
        for &n in sizes {
            for seed in seeds.clone() {
                let f = generate(kind, n, seed).unwrap();
                total += check(&format!("{kind:?} {n} seed {seed}"), &f.scene);
            }
        }
    }
    assert!(total > 10_000, "too few bitangents checked: {total}");
}

#[test]
fn collinear_lattices_match_the_brute_force() {
    for (cols, rows) in [
        (1, 1),
        (2, 1),
        (1, 3),
        (2, 2),
        (3, 3),
        (4, 4),
        (6, 2),
        (5, 5),
    ] {
        for (size, gap) in [(1, 1), (2, 1), (3, 1), (2, 2), (1, 3)] {
            let cells: Vec<(i32, i32)> = (0..cols)
                .flat_map(|i| (0..rows).map(move |j| (i, j)))
                .collect();
            check(
                &format!("lattice {cols}x{rows} size {size} gap {gap}"),
                &boxes(&cells, size, gap),
            );
        }
    }
    // Checkerboard and sparse lattices: long shared lines with holes.
    let checker: Vec<(i32, i32)> = (0..6)
        .flat_map(|i| (0..6).map(move |j| (i, j)))
        .filter(|(i, j)| (i + j) % 2 == 0)
        .collect();
    check("checkerboard 6x6", &boxes(&checker, 2, 1));
    let sparse: Vec<(i32, i32)> = (0..7)
        .flat_map(|i| (0..7).map(move |j| (i, j)))
        .filter(|(i, j)| (i * 3 + j * 5) % 7 < 3)
        .collect();
    check("sparse 7x7", &boxes(&sparse, 1, 1));
}

#[test]
fn collinear_triangles_and_near_touching_match_the_brute_force() {
    // Triangles whose edges share supporting lines across the whole row, and vertices on
    // each other's edge extensions.
    let mut tris = Vec::new();
    for i in 0..5 {
        for j in 0..3 {
            let (x, y) = (4 * i, 4 * j);
            tris.push(vec![pt(x, y), pt(x + 2, y), pt(x, y + 2)]);
            tris.push(vec![pt(x + 3, y + 1), pt(x + 3, y + 3), pt(x + 1, y + 3)]);
        }
    }
    check("collinear triangles", &scene(&tris));
    let t = |x: i32, y: i32| Point::from_raw(x, y).unwrap();
    let u = 1 << 16;
    check(
        "near-touching",
        &scene(&[
            vec![t(0, 0), t(4 * u, 0), t(4 * u, 4 * u), t(0, 4 * u)],
            vec![
                t(4 * u + 1, 0),
                t(8 * u, 0),
                t(8 * u, 4 * u),
                t(4 * u + 1, 4 * u),
            ],
            vec![t(0, 4 * u + 1), t(4 * u, 4 * u + 1), t(2 * u, 6 * u)],
        ]),
    );
}

/// Seconds this thread has run on a CPU (Linux `schedstat`), or `None`: on a loaded
/// machine wall time measures the neighbours.
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns as f64 * 1e-9)
}

/// Runs `f`, returning its result, wall seconds and CPU seconds (wall if unknown).
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (w, c) = (Instant::now(), cpu_seconds());
    let out = f();
    let wall = w.elapsed().as_secs_f64();
    let cpu = c.zip(cpu_seconds()).map_or(wall, |(a, b)| b - a);
    (out, wall, cpu)
}

/// Mean CPU seconds and best wall seconds per call of `f`, repeating it for at least
/// `budget` wall seconds (and at least twice): the CPU clock ticks in milliseconds.
fn measure<T>(budget: f64, mut f: impl FnMut() -> T) -> (T, f64, f64) {
    let (mut runs, mut cpu, mut best, mut total) = (0u32, 0.0, f64::INFINITY, 0.0);
    loop {
        let (out, wall, c) = timed(&mut f);
        (runs, cpu, best, total) = (runs + 1, cpu + c, best.min(wall), total + wall);
        if runs >= 2 && total >= budget {
            return (out, cpu / f64::from(runs), best);
        }
    }
}

/// Build times of the grid scene. Run with
/// `cargo test -p vcx-tests --release --test bitangents_fast time -- --ignored --nocapture
/// --test-threads 1` (`VCX_SIZES=64,256` to choose the sizes).
#[test]
#[ignore]
fn build_time_grid() {
    for n in sizes(&[64, 256, 1024, 4096]) {
        let f = generate(SceneKind::Grid, n, 1).unwrap();
        let s = f.scene.as_ref();
        let (c, cpu, wall) = measure(1.0, || build_by_sweep(&s).unwrap());
        let (v, enumerate, _) = measure(0.5, || free_bitangents(&s));
        assert_eq!(v.len(), c.vertices().len());
        println!(
            "grid n = {n:5}: {:7} directed free bitangents, {:8} cylinders; build_by_sweep \
             {cpu:.4} s CPU (best wall {wall:.4} s), of which free_bitangents {enumerate:.4} s",
            v.len(),
            c.cylinders().len()
        );
    }
}

fn sizes(default: &[u32]) -> Vec<u32> {
    std::env::var("VCX_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_else(|| default.to_vec())
}

/// `free_bitangents` alone on the grid scene, for profiling (`VCX_SIZES`, default 4096).
#[test]
#[ignore]
fn enumeration_time_grid() {
    for n in sizes(&[4096]) {
        let f = generate(SceneKind::Grid, n, 1).unwrap();
        let s = f.scene.as_ref();
        let (v, cpu, wall) = measure(2.0, || free_bitangents(&s));
        println!(
            "grid n = {n:5}: {:7} directed free bitangents, free_bitangents {cpu:.4} s CPU \
             (best wall {wall:.4} s)",
            v.len()
        );
    }
}
