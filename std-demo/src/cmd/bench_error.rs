//! `vcx bench error SCENE [--depth D] [--width W] [--samples 1,2,4,…,256] [--frames F]
//! [--fov DEG] [--json] [--svg FILE]`: run time against error, the complex against the
//! classical ray casters (issue 6, item 2).
//!
//! Along a short trajectory of `F` free viewpoints (a seeded walk in straight steps of 1 %
//! of the scene's size, the heading turning 360°/F per frame), every frame of `W` columns is
//! rendered three ways, all in the same run, complexes and acceleration structures built
//! beforehand:
//! * **complex**: the ray tree to depth D over the frame's field of view, walked in lock
//!   step without allocating as a device does ([`vcx::walk::frame_tree_into`], over the
//!   complex of the whole scene, into a reused scratch and buffer of
//!   [`vcx::render::FrameInterval`]s), and its exact per-column coverage
//!   ([`CoverageTable::exact_into`], one table reused from frame to frame as the casters
//!   reuse theirs) — the truth, error 0 by construction (checked against the exact
//!   reference in `tests/tests/render.rs`);
//! * **quadtree** and **bvh** (`vcx-baselines`): `s` stratified rays per column for each
//!   `s` of `--samples`, traced through the same optics.
//!
//! Per method and `s`: the time per frame — the best of `--repeat` runs of each frame (which
//! filters out the noise of a shared machine; a caster's frame is timed in chunks of about
//! 1000 rays, best of `--repeat` each, summed, so that long frames are not penalized by
//! preemption; the complex's frame, some 10 µs, in batches of as many calls as last about
//! as long as such a chunk, [`CHUNK_SECONDS`], so that one late call or a coarse clock
//! does not weigh on it more), median over the frames —, the mean absolute coverage error per column
//! (half the L1 distance between the estimated and the exact coverage of a column: the
//! share of the column given to a wrong branch, averaged over columns and frames) and the
//! share of columns whose dominant branch is wrong. Then per caster the
//! **speed-up at equal error** (the fewest samples whose mean error is ≤ 1 % — and ≤ 0.1 %,
//! ≤ 0.01 % —, its time over the complex's) and the **error at equal time** (the error of
//! the most samples that are not slower than the complex). Output: a table, or one JSON
//! object with `--json`; `--svg FILE` also plots the curves (log–log, the complex as a
//! vertical line at its time: its error is 0).
//!
//! The measurement itself is [`measure`] (typed results, [`versus`] for the comparisons),
//! shared with the "error" section of `vcx bench figures`.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::{json, Value};
use vcx::partition::{build_by_sweep, point_in_scene};
use vcx::render::{Camera, CoverageTable};
use vcx::walk::{TreeScratch, WalkError};
use vcx::{QueryPoint, SceneRef};
use vcx_baselines::{render, render_columns, BvhCaster, Caster, Prepared, Quadtree};

use super::bench::walk_frame;
use super::{write_stdout, Failure};

/// Arguments of `vcx bench error`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file.
    pub scene: PathBuf,
    /// Ray-tree depth.
    #[arg(long, default_value_t = 5)]
    pub depth: usize,
    /// Columns per frame.
    #[arg(long, default_value_t = 800)]
    pub width: usize,
    /// Samples per column for the ray casters, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1,2,4,8,16,32,64,128,256"
    )]
    pub samples: Vec<usize>,
    /// Frames along the trajectory.
    #[arg(long, default_value_t = 8)]
    pub frames: usize,
    /// Horizontal field of view in degrees.
    #[arg(long, default_value_t = 90.0)]
    pub fov: f64,
    /// Seed of the trajectory.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Repetitions per frame and method; the best is kept (then the median over frames).
    #[arg(long, default_value_t = 3)]
    pub repeat: u32,
    /// One JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Also plot the curves (time per frame against error, log–log) into this SVG file.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
}

impl Args {
    /// The measurement's parameters.
    fn params(&self) -> Params {
        Params {
            depth: self.depth,
            width: self.width,
            samples: self.samples.clone(),
            frames: self.frames,
            fov: self.fov,
            seed: self.seed,
            repeat: self.repeat,
        }
    }
}

/// What [`measure`] measures: the options of [`Args`] without the scene and the output.
#[derive(Clone, Debug)]
pub(crate) struct Params {
    /// Ray-tree depth (0 to 16).
    pub depth: usize,
    /// Columns per frame.
    pub width: usize,
    /// Samples per column for the ray casters (1 to 65536 each).
    pub samples: Vec<usize>,
    /// Frames along the trajectory.
    pub frames: usize,
    /// Horizontal field of view in degrees.
    pub fov: f64,
    /// Seed of the trajectory.
    pub seed: u64,
    /// Repetitions per frame and method; the best is kept.
    pub repeat: u32,
}

impl Params {
    fn check(&self) -> Result<(), Failure> {
        if self.samples.is_empty() || self.samples.iter().any(|&s| s == 0 || s > 1 << 16) {
            return Err(Failure::bad_input(
                "--samples: whole numbers from 1 to 65536",
            ));
        }
        if self.depth > 16 {
            return Err(Failure::bad_input("--depth: 0 to 16"));
        }
        Ok(())
    }
}

fn internal(e: impl core::fmt::Display) -> Failure {
    Failure {
        message: format!("internal: {e}"),
        code: super::build::EXIT_INTERNAL,
    }
}

/// About the time of a caster's chunk of 1000 rays: the complex's frames are timed in
/// batches this long.
const CHUNK_SECONDS: f64 = 100e-6;

/// Times `f` as a caster's chunk is timed: `repeat` batches of as many calls as last about
/// [`CHUNK_SECONDS`] (at most 1000; sized by a first call, not timed), the best batch per
/// call pushed (seconds); returns the first call's result.
fn timed_batched<T>(times: &mut Vec<f64>, repeat: u32, mut f: impl FnMut() -> T) -> T {
    let t = Instant::now();
    let out = core::hint::black_box(f());
    let once = t.elapsed().as_secs_f64();
    let batch = (CHUNK_SECONDS / once.max(1e-9)).ceil().clamp(1.0, 1000.0) as u32;
    timed(times, repeat, || {
        for _ in 0..batch {
            core::hint::black_box(f());
        }
    });
    if let Some(t) = times.last_mut() {
        *t /= f64::from(batch);
    }
    out
}

/// Runs `f` `repeat` times; pushes the best time (seconds) and returns the last result.
fn timed<T>(times: &mut Vec<f64>, repeat: u32, mut f: impl FnMut() -> T) -> T {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        out = Some(core::hint::black_box(f()));
        best = best.min(t.elapsed().as_secs_f64());
    }
    times.push(best);
    match out {
        Some(o) => o,
        None => f(),
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// A seeded xorshift in `[0, 1)`.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` viewpoints with headings (radians) along a walk through free space.
fn trajectory(scene: &SceneRef<'_>, n: usize, seed: u64) -> Vec<(QueryPoint, f64)> {
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for p in scene.vertices() {
        let (x, y) = p.to_f64();
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    let size = (hi.0 - lo.0).max(hi.1 - lo.1).max(1.0);
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let free = |x: f64, y: f64| {
        QueryPoint::from_f64(x, y)
            .ok()
            .filter(|&q| point_in_scene(scene, q).is_none())
    };
    let random_free = |rng: &mut Rng| {
        for _ in 0..10_000 {
            let (x, y) = (
                lo.0 + rng.next() * (hi.0 - lo.0),
                lo.1 + rng.next() * (hi.1 - lo.1),
            );
            if free(x, y).is_some() {
                return Some((x, y));
            }
        }
        None
    };
    let Some(mut p) = random_free(&mut rng) else {
        return Vec::new();
    };
    let a = rng.next() * core::f64::consts::TAU;
    let step = (a.cos() * size * 0.01, a.sin() * size * 0.01);
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let heading = a + core::f64::consts::TAU * k as f64 / n.max(1) as f64;
        if let Some(q) = free(p.0, p.1) {
            out.push((q, heading));
        }
        let next = (p.0 + step.0, p.1 + step.1);
        p = if free(next.0, next.1).is_some() {
            next
        } else {
            random_free(&mut rng).unwrap_or(p)
        };
    }
    out
}

/// One point of a caster's curve.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Point {
    /// Rays per column.
    pub samples: usize,
    /// Seconds per frame (median over the frames of each frame's best run).
    pub seconds: f64,
    /// Mean absolute coverage error per column, in `[0, 1]`.
    pub error: f64,
    /// Share of columns whose dominant branch is wrong, in `[0, 1]`.
    pub wrong: f64,
}

fn curve<C: Caster>(
    prepared: &Prepared,
    caster: &C,
    cameras: &[Camera],
    exact: &[CoverageTable],
    a: &Params,
) -> Vec<Point> {
    let (mut table, mut scratch) = (CoverageTable::new(), CoverageTable::new());
    a.samples
        .iter()
        .map(|&s| {
            let (mut times, mut err, mut wrong) = (Vec::new(), 0.0, 0.0);
            for (cam, truth) in cameras.iter().zip(exact) {
                // Timed in chunks of about 1000 rays, each the best of `repeat` runs, so
                // that preemption on a loaded machine does not weigh on long frames more
                // than on short ones (the complex's frames in batches as long).
                let chunk = (1024 / s).max(1);
                let mut total = 0.0;
                for c0 in (0..cam.width()).step_by(chunk) {
                    let mut t = Vec::new();
                    timed(&mut t, a.repeat, || {
                        scratch.clear();
                        render_columns(
                            prepared,
                            caster,
                            cam,
                            s,
                            a.depth,
                            c0..c0 + chunk,
                            &mut scratch,
                        )
                    });
                    total += t.first().copied().unwrap_or(0.0);
                }
                times.push(total);
                render(prepared, caster, cam, s, a.depth, &mut table);
                let (e, w) = table.error_against(truth);
                err += e;
                wrong += w;
            }
            let n = cameras.len().max(1) as f64;
            Point {
                samples: s,
                seconds: median(&mut times),
                error: err / n,
                wrong: wrong / n,
            }
        })
        .collect()
}

/// The error limits of the speed-up at equal error: name (in the JSON keys) and limit.
pub(crate) const LIMITS: [(&str, f64); 3] =
    [("1pct", 0.01), ("0.1pct", 0.001), ("0.01pct", 0.0001)];

/// One caster against the complex.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Versus {
    /// Per limit of [`LIMITS`]: the fewest samples whose error is within it, if any.
    pub at: [Option<Point>; 3],
    /// The caster's time over the complex's, at each limit; without any point within it,
    /// the ratio for the most samples measured (a lower bound), flagged `true`.
    pub speedup: [Option<(f64, bool)>; 3],
    /// The most samples that are not slower than the complex.
    pub equal_time: Option<Point>,
}

/// Speed-up at equal error (≤ 1 %, and the stricter 0.1 % and 0.01 %) and error at equal
/// time, for one caster.
pub(crate) fn versus(points: &[Point], complex_seconds: f64) -> Versus {
    let best = points.last();
    let at = LIMITS.map(|(_, limit)| points.iter().find(|p| p.error <= limit).copied());
    let speedup = at.map(|p| match p {
        Some(p) => Some((p.seconds / complex_seconds, false)),
        None => best.map(|b| (b.seconds / complex_seconds, true)),
    });
    let equal_time = points
        .iter()
        .filter(|p| p.seconds <= complex_seconds)
        .max_by_key(|p| p.samples)
        .copied();
    Versus {
        at,
        speedup,
        equal_time,
    }
}

fn compare(points: &[Point], complex_seconds: f64) -> Value {
    let v = versus(points, complex_seconds);
    let mut out = serde_json::Map::new();
    for (((name, _), p), s) in LIMITS.iter().zip(v.at).zip(v.speedup) {
        out.insert(format!("samples_for_{name}"), json!(p.map(|p| p.samples)));
        // The complex's speed-up: the caster's time at that error over the complex's.
        out.insert(
            format!("speedup_at_{name}"),
            json!(s.filter(|s| !s.1).map(|s| s.0)),
        );
        // Without any point at that error: the ratio for the most samples measured, a
        // lower bound of the speed-up.
        out.insert(
            format!("speedup_lower_bound_{name}"),
            json!(s.filter(|s| s.1).map(|s| s.0)),
        );
    }
    let equal_time = v.equal_time;
    out.insert(
        "samples_at_equal_time".into(),
        json!(equal_time.map(|p| p.samples)),
    );
    out.insert(
        "error_at_equal_time".into(),
        json!(equal_time.map(|p| p.error)),
    );
    out.insert(
        "wrong_dominant_at_equal_time".into(),
        json!(equal_time.map(|p| p.wrong)),
    );
    Value::Object(out)
}

fn points_json(points: &[Point]) -> Value {
    Value::Array(
        points
            .iter()
            .map(|p| {
                json!({
                    "samples": p.samples,
                    "us_per_frame": p.seconds * 1e6,
                    "mean_abs_error": p.error,
                    "wrong_dominant": p.wrong,
                })
            })
            .collect(),
    )
}

/// What [`measure`] returns: the complex's time and each caster's curve.
pub(crate) struct Measured {
    /// Objects in the scene.
    pub objects: usize,
    /// Frames measured (viewpoints whose ray tree succeeded).
    pub frames: usize,
    /// Mean intervals of the ray tree per frame.
    pub intervals: f64,
    /// Nodes of the quadtree.
    pub quadtree_nodes: usize,
    /// The complex's seconds per frame: ray tree and exact coverage.
    pub complex_seconds: f64,
    /// The ray tree alone.
    pub tree_seconds: f64,
    /// The exact coverage alone.
    pub cover_seconds: f64,
    /// The quadtree's curve, one point per samples count.
    pub quadtree: Vec<Point>,
    /// The BVH's curve.
    pub bvh: Vec<Point>,
}

/// Measures the complex and both casters on `scene` (the module documentation).
pub(crate) fn measure(scene: &SceneRef<'_>, a: &Params) -> Result<Measured, Failure> {
    a.check()?;
    let scene = *scene;
    let complex = build_by_sweep(&scene)
        .map_err(internal)?
        .with_arc_vertices(&scene);
    let prepared = Prepared::new(&scene);
    let quadtree = Quadtree::new(&prepared);
    let bvh = BvhCaster::new(&prepared);
    let path = trajectory(&scene, a.frames.max(1), a.seed);
    let mut cameras = Vec::new();
    for &(q, heading) in &path {
        cameras.push(
            Camera::new(q, heading, a.fov.to_radians(), a.width)
                .map_err(|e| Failure::bad_input(format!("--fov/--width: {e}")))?,
        );
    }
    // The complex: ray tree + exact coverage per frame; the walk's scratch, its intervals
    // and the table are reused from frame to frame, as the casters reuse theirs.
    let (mut times, mut exact, mut intervals) = (Vec::new(), Vec::new(), 0usize);
    let (mut tree_times, mut cover_times) = (Vec::new(), Vec::new());
    let mut used = Vec::new();
    let (mut scratch, mut kept) = (Box::new(TreeScratch::<64>::new()), Vec::new());
    let mut table = CoverageTable::new();
    for cam in &cameras {
        let r = timed_batched(&mut times, a.repeat, || {
            walk_frame(&complex, &scene, cam, a.depth, &mut scratch, &mut kept)?;
            table.exact_into(cam, &kept);
            Ok::<_, WalkError>(kept.len())
        });
        // A viewpoint the walk rejects (degenerate rounded optics) is left out.
        if let Ok(n) = r {
            exact.push(table.clone());
            // The two stages apart: the walk (the ray tree over the field of view), then
            // the frame's coverage.
            timed_batched(&mut tree_times, a.repeat, || {
                walk_frame(&complex, &scene, cam, a.depth, &mut scratch, &mut kept)
            })
            .map_err(internal)?;
            timed_batched(&mut cover_times, a.repeat, || table.exact_into(cam, &kept));
            intervals += n;
            used.push(*cam);
        }
    }
    if used.is_empty() {
        return Err(Failure::bad_input(
            "no viewpoint along the trajectory could be rendered",
        ));
    }
    Ok(Measured {
        objects: scene.len(),
        frames: used.len(),
        intervals: intervals as f64 / used.len() as f64,
        quadtree_nodes: quadtree.nodes(),
        complex_seconds: median(&mut times),
        tree_seconds: median(&mut tree_times),
        cover_seconds: median(&mut cover_times),
        quadtree: curve(&prepared, &quadtree, &used, &exact, a),
        bvh: curve(&prepared, &bvh, &used, &exact, a),
    })
}

/// Runs `vcx bench error`.
pub fn run(a: &Args) -> Result<(), Failure> {
    let params = a.params();
    params.check()?;
    let file = super::check::load(&a.scene)?;
    let m = measure(&file.scene.as_ref(), &params)?;
    let (complex_seconds, qt, bv) = (m.complex_seconds, &m.quadtree, &m.bvh);
    let out = json!({
        "scene": a.scene.display().to_string(),
        "objects": m.objects,
        "depth": a.depth,
        "width": a.width,
        "fov_deg": a.fov,
        "frames": m.frames,
        "intervals_per_frame": m.intervals,
        "quadtree_nodes": m.quadtree_nodes,
        "complex": {
            "us_per_frame": complex_seconds * 1e6,
            "us_ray_tree": m.tree_seconds * 1e6,
            "us_coverage": m.cover_seconds * 1e6,
            "mean_abs_error": 0.0,
            "wrong_dominant": 0.0,
        },
        "quadtree": points_json(qt),
        "bvh": points_json(bv),
        "quadtree_vs_complex": compare(qt, complex_seconds),
        "bvh_vs_complex": compare(bv, complex_seconds),
    });
    if let Some(path) = &a.svg {
        let svg = plot(&a.scene.display().to_string(), complex_seconds, qt, bv);
        std::fs::write(path, svg)
            .map_err(|e| Failure::bad_input(format!("{}: cannot write: {e}", path.display())))?;
    }
    if a.json {
        return write_stdout(&format!("{out}\n"));
    }
    let mut text = format!(
        "{}: {} objects, depth {}, {} columns, {} frames, {:.1} intervals per frame\n\
         complex: {:.1} µs per frame (ray tree over the field of view {:.1}, coverage {:.1}), error 0\n\
         {:>8} {:>14} {:>10} {:>10} {:>14} {:>10} {:>10}\n",
        a.scene.display(),
        m.objects,
        a.depth,
        a.width,
        m.frames,
        m.intervals,
        complex_seconds * 1e6,
        out["complex"]["us_ray_tree"].as_f64().unwrap_or(f64::NAN),
        out["complex"]["us_coverage"].as_f64().unwrap_or(f64::NAN),
        "samples",
        "quadtree µs",
        "error",
        "wrong",
        "bvh µs",
        "error",
        "wrong"
    );
    for (p, b) in qt.iter().zip(bv) {
        text.push_str(&format!(
            "{:>8} {:>14.1} {:>10.5} {:>10.5} {:>14.1} {:>10.5} {:>10.5}\n",
            p.samples,
            p.seconds * 1e6,
            p.error,
            p.wrong,
            b.seconds * 1e6,
            b.error,
            b.wrong
        ));
    }
    for (name, v) in [
        ("quadtree", &out["quadtree_vs_complex"]),
        ("bvh", &out["bvh_vs_complex"]),
    ] {
        text.push_str(&format!("{name} vs complex: {v}\n"));
    }
    write_stdout(&text)
}

/// A log–log SVG plot: mean absolute error per column against µs per frame, one polyline
/// per caster (labelled by samples), the complex as a vertical line (error 0).
fn plot(title: &str, complex_seconds: f64, qt: &[Point], bv: &[Point]) -> String {
    let (w, h, m) = (640.0, 420.0, 60.0);
    let all = qt.iter().chain(bv).filter(|p| p.error > 0.0);
    let (mut t0, mut t1, mut e0, mut e1) = (complex_seconds, complex_seconds, f64::MAX, f64::MIN);
    for p in all {
        (t0, t1) = (t0.min(p.seconds), t1.max(p.seconds));
        (e0, e1) = (e0.min(p.error), e1.max(p.error));
    }
    if e0 > e1 {
        (e0, e1) = (1e-4, 1e-1);
    }
    let (lt0, lt1) = (
        (t0 * 1e6).log10().floor(),
        (t1 * 1e6)
            .log10()
            .ceil()
            .max((t0 * 1e6).log10().floor() + 1.0),
    );
    let (le0, le1) = (
        e0.log10().floor(),
        e1.log10().ceil().max(e0.log10().floor() + 1.0),
    );
    let x = |sec: f64| m + ((sec * 1e6).log10() - lt0) / (lt1 - lt0) * (w - 2.0 * m);
    let y = |err: f64| h - m - (err.log10() - le0) / (le1 - le0) * (h - 2.0 * m);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"11\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n\
         <text x=\"{m}\" y=\"20\" font-size=\"13\">{title}: mean abs. coverage error per column vs µs per frame</text>\n"
    );
    for k in lt0 as i32..=lt1 as i32 {
        let xx = x(10f64.powi(k) / 1e6);
        s += &format!("<line x1=\"{xx:.1}\" y1=\"{m}\" x2=\"{xx:.1}\" y2=\"{:.1}\" stroke=\"#ddd\"/><text x=\"{xx:.1}\" y=\"{:.1}\" text-anchor=\"middle\">1e{k} µs</text>\n", h - m, h - m + 16.0);
    }
    for k in le0 as i32..=le1 as i32 {
        let yy = y(10f64.powi(k));
        s += &format!("<line x1=\"{m}\" y1=\"{yy:.1}\" x2=\"{:.1}\" y2=\"{yy:.1}\" stroke=\"#ddd\"/><text x=\"{:.1}\" y=\"{yy:.1}\" text-anchor=\"end\">1e{k}</text>\n", w - m, m - 4.0);
    }
    let cx = x(complex_seconds);
    s += &format!("<line x1=\"{cx:.1}\" y1=\"{m}\" x2=\"{cx:.1}\" y2=\"{:.1}\" stroke=\"black\" stroke-width=\"2\"/><text x=\"{:.1}\" y=\"{:.1}\">complex (error 0)</text>\n", h - m, cx + 4.0, m + 12.0);
    for (name, pts, colour, dy) in [
        ("quadtree", qt, "#c0392b", -6.0),
        ("bvh (parry2d)", bv, "#2e86c1", 14.0),
    ] {
        let line: Vec<String> = pts
            .iter()
            .filter(|p| p.error > 0.0)
            .map(|p| format!("{:.1},{:.1}", x(p.seconds), y(p.error)))
            .collect();
        s += &format!(
            "<polyline fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.5\" points=\"{}\"/>\n",
            line.join(" ")
        );
        for p in pts.iter().filter(|p| p.error > 0.0) {
            s += &format!("<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2.5\" fill=\"{colour}\"><title>{name}, s = {}</title></circle>\n", x(p.seconds), y(p.error), p.samples);
        }
        if let Some(p) = pts.iter().find(|p| p.error > 0.0) {
            s += &format!(
                "<text x=\"{:.1}\" y=\"{:.1}\" fill=\"{colour}\">{name}</text>\n",
                x(p.seconds) + 4.0,
                y(p.error) + dy
            );
        }
    }
    let one = y(0.01);
    s += &format!("<line x1=\"{m}\" y1=\"{one:.1}\" x2=\"{:.1}\" y2=\"{one:.1}\" stroke=\"#888\" stroke-dasharray=\"4 3\"/><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\" fill=\"#888\">1 %</text>\n</svg>\n", w - m, w - m, one - 3.0);
    s
}
