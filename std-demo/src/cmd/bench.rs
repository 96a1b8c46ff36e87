//! `vcx bench`: measurements, not tests. Every number printed comes from the run that
//! prints it; `BENCHMARKS.md` records them with the command and the machine.
//!
//! * `vcx bench build [--n 16,64,256] [--method ric|sweep|both] [--seed S] [--repeat R]`:
//!   the paper's grid scene (Fig. 20; `vcx gen grid N --seed S`) for each n: construction
//!   seconds (best of R runs), cylinders, vertices, free bitangents, history nodes, links
//!   and depth, and the bytes of the arenas (cylinders, vertices, history links). One JSON
//!   object per line.
//! * `vcx bench views SCENE [--points FILE | --random K] [--seed S] [--repeat R]`: the
//!   full 360° view from each point (screens left out, complex built once by the sweep),
//!   or with `--depth D` the ray tree (screens kept): median microseconds per view (each
//!   point timed as the best of R repetitions), views per second, mean events of the
//!   primary walk (cylinders entered) and intervals per view. One JSON object. With
//!   `--fov DEG [--heading DEG] [--width W]` each measurement is a frame of W columns: the
//!   same sweep plus per-column hits (`render::centre_intervals`, `render::hit_along`) and
//!   exact per-column coverage (`render::coverage`); adds `us_per_frame`.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;
use vcx::partition::{build_by_sweep, BuildOptions, Complex, Cylinder, History};
use vcx::render::{centre_intervals, coverage, hit_along, Camera, Interval};
use vcx::{Material, ObjectId, QueryPoint, SubScene};

use super::{write_stdout, Failure};
use vcx_demo::generate::{generate, SceneKind};

/// The benchmarks.
#[derive(Debug, clap::Subcommand)]
pub enum Bench {
    /// Construction time and sizes against n for the grid scene.
    Build(BuildArgs),
    /// Time per full view from points of a scene.
    Views(ViewsArgs),
    /// Run time against error: the complex against the quadtree and BVH ray casters.
    Error(super::bench_error::Args),
    /// Numerical-stability stress test: exact against naive f64 predicates.
    Stability(super::stability::Args),
    /// The paper's experiments (Figs. 9–19): every table and SVG plot in one run.
    Figures(super::figures::Args),
}

/// Arguments of `vcx bench build`.
#[derive(Debug, clap::Args)]
pub struct BuildArgs {
    /// Scene sizes, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "16,64,256")]
    pub n: Vec<u32>,
    /// Construction method.
    #[arg(long, value_enum, default_value_t = MethodChoice::Both)]
    pub method: MethodChoice,
    /// Seed of the scene generator and of the insertion order.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Runs per size; the best time is reported.
    #[arg(long, default_value_t = 1)]
    pub repeat: u32,
}

/// Which construction to measure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodChoice {
    /// Randomized incremental construction with history.
    Ric,
    /// Rotational sweep, no history.
    Sweep,
    /// Both, in the same run.
    Both,
}

/// Arguments of `vcx bench views`.
#[derive(Debug, clap::Args)]
pub struct ViewsArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Viewpoints, one `x,y` per line.
    #[arg(long)]
    pub points: Option<PathBuf>,
    /// Instead of a file: this many random free points in the scene's bounding box.
    #[arg(long, default_value_t = 200)]
    pub random: usize,
    /// Seed for the random points.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Repetitions per point; the best is kept.
    #[arg(long, default_value_t = 5)]
    pub repeat: u32,
    /// Ray-tree depth (0: the direct view).
    #[arg(long, default_value_t = 0)]
    pub depth: usize,
    /// With `--fov`: time a frame instead of a full view — the sweep plus per-column hits
    /// (the interval through each column's centre and its distance) and the exact
    /// per-column coverage — looking along `--heading` (degrees).
    #[arg(long, default_value_t = 0.0)]
    pub heading: f64,
    /// Horizontal field of view of a frame, in degrees (below 180).
    #[arg(long)]
    pub fov: Option<f64>,
    /// Columns of a frame.
    #[arg(long, default_value_t = 800)]
    pub width: usize,
}

/// Runs a benchmark.
pub fn run(bench: &Bench) -> Result<(), Failure> {
    match bench {
        Bench::Build(a) => build(a),
        Bench::Views(a) => views(a),
        Bench::Error(a) => super::bench_error::run(a),
        Bench::Stability(a) => super::stability::run(a),
        Bench::Figures(a) => super::figures::run(a),
    }
}

pub(crate) fn internal(e: impl core::fmt::Display) -> Failure {
    Failure {
        message: format!("internal: {e}"),
        code: super::build::EXIT_INTERNAL,
    }
}

pub(crate) fn bytes(c: &Complex) -> usize {
    core::mem::size_of_val(c.cylinders()) + core::mem::size_of_val(c.vertices())
}

/// History bytes: every node's cylinder record plus 4 bytes per link.
pub(crate) fn history_bytes(h: &vcx::partition::HistoryStats) -> usize {
    h.nodes * core::mem::size_of::<Cylinder>() + h.links * 4
}

fn build(a: &BuildArgs) -> Result<(), Failure> {
    let mut out = String::new();
    for &n in &a.n {
        let file =
            generate(SceneKind::Grid, n, a.seed).map_err(|e| Failure::bad_input(e.to_string()))?;
        let scene = file.scene.as_ref();
        let methods: &[MethodChoice] = match a.method {
            MethodChoice::Both => &[MethodChoice::Ric, MethodChoice::Sweep],
            MethodChoice::Ric => &[MethodChoice::Ric],
            _ => &[MethodChoice::Sweep],
        };
        for &m in methods {
            let mut best = f64::INFINITY;
            let mut last = None;
            for _ in 0..a.repeat.max(1) {
                let t = Instant::now();
                let (complex, history) = match m {
                    MethodChoice::Ric => {
                        let h = History::build(
                            &scene,
                            &BuildOptions {
                                seed: a.seed,
                                ..Default::default()
                            },
                        )
                        .map_err(internal)?;
                        let secs = t.elapsed().as_secs_f64();
                        best = best.min(secs);
                        (h.complex(&scene).map_err(internal)?, Some(h.stats()))
                    }
                    _ => {
                        let c = build_by_sweep(&scene).map_err(internal)?;
                        best = best.min(t.elapsed().as_secs_f64());
                        (c, None)
                    }
                };
                last = Some((complex, history));
            }
            let Some((c, h)) = last else { continue };
            let line = json!({
                "scene": "grid",
                "n": n,
                "method": if m == MethodChoice::Ric { "ric" } else { "sweep" },
                "seconds": best,
                "cylinders": c.cylinders().len(),
                "complex_vertices": c.vertices().len(),
                "free_bitangents": c.free_bitangents(),
                "complex_bytes": bytes(&c),
                "history_nodes": h.map(|h| h.nodes),
                "history_links": h.map(|h| h.links),
                "history_depth": h.map(|h| h.depth),
                "history_bytes": h.map(|h| history_bytes(&h)),
            });
            out.push_str(&line.to_string());
            out.push('\n');
            eprintln!("{line}");
        }
    }
    write_stdout(&out)
}

fn views(a: &ViewsArgs) -> Result<(), Failure> {
    // JSON or `.vcx`: a stored complex is used where it is the one needed (crate::input).
    let input = crate::input::load(&a.scene)?;
    let file = &input.file;
    let full = file.scene.as_ref();
    let keep = full
        .objects()
        .iter()
        .enumerate()
        .filter(|(_, o)| o.material != Material::Screen)
        .map(|(i, _)| ObjectId(i as u32));
    // Depth 0 walks the complex without screens; ray trees need them in the complex.
    let sub = if a.depth == 0 {
        SubScene::new(full, keep)
    } else {
        SubScene::new(full, (0..full.len() as u32).map(ObjectId))
    };
    let scene = sub.as_ref();
    let complex = input.complex_for(&scene).map_err(internal)?;
    let points: Vec<QueryPoint> = match &a.points {
        Some(path) => super::view::read_points(path)?
            .into_iter()
            .map(|p| p.q)
            .collect(),
        None => random_points(&scene, a.random, a.seed),
    };
    let mut times = Vec::with_capacity(points.len());
    let (mut events, mut boundaries, mut used) = (0usize, 0usize, 0usize);
    for &q in &points {
        if vcx::partition::point_in_scene(&full, q).is_some() {
            continue;
        }
        let camera = match a.fov {
            Some(fov) => Some(
                Camera::new(q, a.heading.to_radians(), fov.to_radians(), a.width)
                    .map_err(|e| Failure::bad_input(format!("--heading/--fov/--width: {e}")))?,
            ),
            None => None,
        };
        let mut columns = vec![0usize; a.width];
        let mut count = || -> Result<usize, Failure> {
            Ok(if a.depth == 0 {
                let v = vcx::walk::view(&complex, &scene, q).map_err(internal)?;
                frame(&scene, camera.as_ref(), &v, &mut columns);
                v.len()
            } else {
                let t = vcx::walk::ray_tree(&complex, &scene, q, a.depth).map_err(internal)?;
                frame(&scene, camera.as_ref(), &t, &mut columns);
                t.len()
            })
        };
        let mut best = f64::INFINITY;
        let mut intervals = 0;
        for _ in 0..a.repeat.max(1) {
            let t = Instant::now();
            intervals = core::hint::black_box(count()?);
            best = best.min(t.elapsed().as_secs_f64());
        }
        boundaries += intervals;
        complex
            .walk_trace(&scene, q, |_| events += 1)
            .map_err(internal)?;
        times.push(best);
        used += 1;
    }
    if times.is_empty() {
        return Err(Failure::bad_input("no free viewpoint to measure"));
    }
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    let mut line = json!({
        "scene": a.scene.display().to_string(),
        "objects": scene.len(),
        "depth": a.depth,
        "cylinders": complex.cylinders().len(),
        "views": used,
        "us_per_view": median * 1e6,
        "views_per_second": 1.0 / median,
        "events_per_view": events as f64 / used as f64,
        "intervals_per_view": boundaries as f64 / used as f64,
    });
    if let Some(fov) = a.fov {
        // Each "view" is a frame: sweep, per-column hits and exact coverage.
        line["frame"] = json!({ "heading": a.heading, "fov": fov, "width": a.width });
        line["us_per_frame"] = json!(median * 1e6);
        line["frames_per_second"] = json!(1.0 / median);
    }
    write_stdout(&format!("{line}\n"))
}

/// The per-column work of a frame after the sweep (nothing without a camera): the interval
/// through each column's centre and the distance along its branch, and the exact coverage
/// of every column (summed, so that nothing is optimised away).
pub(crate) fn frame<I: Interval>(
    scene: &vcx::SceneRef<'_>,
    camera: Option<&Camera>,
    intervals: &[I],
    columns: &mut [usize],
) {
    let Some(camera) = camera else { return };
    centre_intervals(camera, intervals, columns);
    let mut sum = 0.0;
    for (c, &k) in columns.iter().enumerate() {
        let branch = intervals.get(k).map_or(&[][..], |i| i.branch());
        let d = camera.centre(c).direction();
        if let Some(hit) = hit_along(scene, camera.eye(), d, branch) {
            sum += hit.length;
        }
    }
    coverage(camera, intervals, |p| sum += p.fraction);
    core::hint::black_box(sum);
}

/// `k` free points drawn uniformly in the bounding box (a portable xorshift, seeded).
fn random_points(scene: &vcx::SceneRef<'_>, k: usize, seed: u64) -> Vec<QueryPoint> {
    let (mut lo, mut hi) = ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN));
    for p in scene.vertices() {
        let q = p.to_query();
        lo = (lo.0.min(q.x()), lo.1.min(q.y()));
        hi = (hi.0.max(q.x()), hi.1.max(q.y()));
    }
    let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut next = |lo: i64, hi: i64| {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        lo + (s % ((hi - lo).max(1) as u64)) as i64
    };
    let mut out = Vec::new();
    for _ in 0..k * 20 {
        if out.len() >= k || lo.0 > hi.0 {
            break;
        }
        let q = QueryPoint::from_raw(next(lo.0, hi.0), next(lo.1, hi.1));
        if let Some(q) = q.filter(|q| vcx::partition::point_in_scene(scene, *q).is_none()) {
            out.push(q);
        }
    }
    out
}
