//! `vcx bench`: measurements, not tests. Every number printed comes from the run that
//! prints it; `BENCHMARKS.md` records them with the command and the machine.
//!
//! * `vcx bench build [--n 16,64,256] [--method ric|sweep|both] [--seed S] [--repeat R]
//!   [--growth]`:
//!   the paper's grid scene (Fig. 20; `vcx gen grid N --seed S`) for each n: construction
//!   seconds (best of R runs), cylinders, vertices, free bitangents, history nodes, links
//!   and depth, and the bytes of the arenas (cylinders, vertices, history links). For
//!   `ric` the same history built without search path compaction (§4.4,
//!   `BuildOptions::compaction`) side by side: `uncompacted_seconds`,
//!   `uncompacted_history_nodes`, `_links`, `_depth`, `_bytes` (`null` for the sweep).
//!   With `--growth` (`ric` only) the construction is replayed untimed in the same order,
//!   reading the size k_i of the complex of the first i objects after each insertion:
//!   `prefix_live_sum` (Σ k_i/i, the backwards-analysis bound on the history's size up to
//!   the constant), `peak_live_per_object` (max k_i/i), `peak_at` (that i) and
//!   `nodes_over_prefix_live_sum`. One JSON object per line.
//! * `vcx bench views SCENE [--points FILE | --random K] [--seed S] [--repeat R]`: the
//!   full 360° view from each point (screens left out, complex built once by the sweep),
//!   or with `--depth D` the ray tree (screens kept): median microseconds per view (each
//!   point timed as the best of R repetitions), views per second, mean events of the
//!   primary walk (cylinders entered) and intervals per view. One JSON object. With
//!   `--fov DEG [--heading DEG] [--width W]` each measurement is a frame of W columns: the
//!   ray tree over the field of view walked in lock step without allocating
//!   (`walk::frame_tree_into` into a reused scratch and buffer of `render::FrameInterval`s,
//!   as a device does) plus per-column hits (`render::centre_hits`: each column's centre interval
//!   and the distance along its branch, one `render::Hits` for the frame) and
//!   exact per-column coverage (`render::coverage`); adds `us_per_frame`.
//!
//! The measurements ([`time_build`], [`measure_views`]) are also those of the sections of
//! `vcx bench figures` (BENCHMARKS.md).

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;
use vcx::partition::{build_by_sweep, BuildOptions, Complex, Cylinder, History};
use vcx::render::{angle_order, centre_hits, coverage, Camera, FrameInterval, Interval};
use vcx::walk::{frame_tree_into, TreeScratch, WalkError};
use vcx::{Material, ObjectId, QueryPoint, SceneRef, SubScene};

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
    /// Every benchmark in one run: BENCHMARKS.md and its SVG plots (the paper's Figs.
    /// 9–19, views, ray trees, frames, sizes, error, stability).
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
    /// After the timed runs, replay the randomized construction untimed and report the
    /// sizes of the complexes of its prefixes (`ric` only).
    #[arg(long)]
    pub growth: bool,
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
    /// Draw the random viewpoints in this box (`X0,Y0,X1,Y1`) instead of the scene's
    /// bounding box; by default the region of a `.vcx` file pruned to one (`vcx build
    /// --region`), so a full and a pruned file are timed from the same points.
    #[arg(long, value_name = "X0,Y0,X1,Y1", allow_hyphen_values = true)]
    pub region: Option<String>,
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

/// One construction measured `repeat` times: every run's seconds (of the construction
/// alone, not of `History::complex`) and the results of the last run.
pub(crate) struct Timed {
    /// Seconds of each run.
    pub times: Vec<f64>,
    /// The complex (of the last run).
    pub complex: Complex,
    /// The history's statistics (randomized construction only).
    pub history: Option<vcx::partition::HistoryStats>,
    /// The insertion order (randomized construction only; empty for the sweep).
    pub order: Vec<ObjectId>,
}

impl Timed {
    /// The best run.
    pub fn best(&self) -> f64 {
        self.times.iter().copied().fold(f64::INFINITY, f64::min)
    }
}

/// Builds the complex of `scene` `repeat` times (at least once) by the randomized
/// incremental construction with `options` (`ric`) or by the sweep: `vcx bench build`'s
/// measurement, also used by `vcx bench figures`.
pub(crate) fn time_build(
    scene: &vcx::SceneRef<'_>,
    ric: bool,
    options: &BuildOptions,
    repeat: u32,
) -> Result<Timed, Failure> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        let built = if ric {
            let h = History::build(scene, options).map_err(internal)?;
            times.push(t.elapsed().as_secs_f64());
            let c = h.complex(scene).map_err(internal)?;
            (c, Some(h.stats()), h.order().to_vec())
        } else {
            let c = build_by_sweep(scene).map_err(internal)?;
            times.push(t.elapsed().as_secs_f64());
            (c, None, Vec::new())
        };
        last = Some(built);
    }
    let (complex, history, order) = last.ok_or_else(|| internal("no run"))?;
    Ok(Timed {
        times,
        complex,
        history,
        order,
    })
}

/// The sizes k_i of the complexes of the prefixes of a randomized construction's
/// insertion order (`vcx bench build --growth`). By backwards analysis the expected
/// structural change of the i-th insertion is at most D·k_i/i (D: the objects defining a
/// cylinder), so Σ k_i/i bounds the history's size up to a constant; random prefixes of a
/// large grid are sparser and see more, so k_i/i peaks before the end.
struct Growth {
    /// Σ_i k_i / i.
    sum: f64,
    /// max_i k_i / i.
    peak: f64,
    /// The (1-based) i of the peak.
    peak_at: usize,
    /// The replayed history's statistics.
    stats: vcx::partition::HistoryStats,
}

/// Replays the insertions of `order` into a fresh history (untimed), reading
/// `live_cylinders()` after each.
fn growth(scene: &SceneRef<'_>, order: &[ObjectId]) -> Result<Growth, Failure> {
    let mut h = History::new();
    let mut g = Growth {
        sum: 0.0,
        peak: 0.0,
        peak_at: 0,
        stats: h.stats(),
    };
    for (i, &id) in (1..).zip(order) {
        h.insert(scene, id).map_err(internal)?;
        let per = h.live_cylinders() as f64 / i as f64;
        g.sum += per;
        if per > g.peak {
            (g.peak, g.peak_at) = (per, i);
        }
    }
    g.stats = h.stats();
    Ok(g)
}

fn build(a: &BuildArgs) -> Result<(), Failure> {
    if a.growth && a.method == MethodChoice::Sweep {
        return Err(Failure::bad_input(
            "--growth measures the randomized construction: use --method ric or both",
        ));
    }
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
            let ric = m == MethodChoice::Ric;
            let options = BuildOptions {
                seed: a.seed,
                ..Default::default()
            };
            let t = time_build(&scene, ric, &options, a.repeat)?;
            let (c, h) = (&t.complex, t.history);
            let uncompacted = if ric {
                let options = BuildOptions {
                    compaction: false,
                    ..options
                };
                let u = time_build(&scene, true, &options, a.repeat)?;
                if u.complex.cylinders() != c.cylinders() {
                    return Err(internal("the uncompacted history's live partition differs"));
                }
                Some((u.best(), u.history))
            } else {
                None
            };
            let uh = uncompacted.and_then(|u| u.1);
            let mut line = json!({
                "scene": "grid",
                "n": n,
                "method": if m == MethodChoice::Ric { "ric" } else { "sweep" },
                "seconds": t.best(),
                "cylinders": c.cylinders().len(),
                "complex_vertices": c.vertices().len(),
                "free_bitangents": c.free_bitangents(),
                "complex_bytes": bytes(c),
                "history_nodes": h.map(|h| h.nodes),
                "history_links": h.map(|h| h.links),
                "history_depth": h.map(|h| h.depth),
                "history_bytes": h.map(|h| history_bytes(&h)),
                "uncompacted_seconds": uncompacted.map(|u| u.0),
                "uncompacted_history_nodes": uh.map(|h| h.nodes),
                "uncompacted_history_links": uh.map(|h| h.links),
                "uncompacted_history_depth": uh.map(|h| h.depth),
                "uncompacted_history_bytes": uh.map(|h| history_bytes(&h)),
            });
            if let (true, Some(h)) = (a.growth, h) {
                let g = growth(&scene, &t.order)?;
                // Same order, same history: a difference would be a bug (nondeterminism).
                if (g.stats.nodes, g.stats.links) != (h.nodes, h.links) {
                    return Err(internal("the replayed history differs from the built one"));
                }
                line["prefix_live_sum"] = json!(g.sum);
                line["peak_live_per_object"] = json!(g.peak);
                line["peak_at"] = json!(g.peak_at);
                line["nodes_over_prefix_live_sum"] = json!(h.nodes as f64 / g.sum);
            }
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
    let points = match &a.points {
        Some(path) => Points::Given(
            super::view::read_points(path)?
                .into_iter()
                .map(|p| p.q)
                .collect(),
        ),
        None => {
            let stored = input.stored.as_ref().and_then(|s| s.complex.region());
            let region = match &a.region {
                Some(text) => Some(super::build::parse_region("--region", text)?),
                None => stored,
            };
            match region {
                Some(r) => Points::Given(random_points_in(
                    &input.file.scene.as_ref(),
                    &r,
                    a.random,
                    a.seed,
                )),
                None => Points::Random(a.random, a.seed),
            }
        }
    };
    let frame = a.fov.map(|fov| FrameSpec {
        heading: a.heading,
        fov,
        width: a.width,
    });
    let m = measure_views(&input, &points, a.depth, a.repeat, frame)?;
    let mut line = json!({
        "scene": a.scene.display().to_string(),
        "objects": m.objects,
        "depth": a.depth,
        "cylinders": m.cylinders,
        "views": m.views,
        "us_per_view": m.seconds * 1e6,
        "views_per_second": 1.0 / m.seconds,
        "events_per_view": m.events,
        "intervals_per_view": m.intervals,
    });
    if let Some(fov) = a.fov {
        // Each "view" is a frame: sweep, per-column hits and exact coverage.
        line["frame"] = json!({ "heading": a.heading, "fov": fov, "width": a.width });
        line["us_per_frame"] = json!(m.seconds * 1e6);
        line["frames_per_second"] = json!(1.0 / m.seconds);
    }
    write_stdout(&format!("{line}\n"))
}

/// The viewpoints of `vcx bench views`.
pub(crate) enum Points {
    /// These points (`--points FILE`).
    Given(Vec<QueryPoint>),
    /// This many random free points of the walked scene, from this seed (`--random K
    /// --seed S`).
    Random(usize, u64),
}

/// A frame of `vcx bench views --fov`: heading and field of view in degrees, columns.
#[derive(Clone, Copy)]
pub(crate) struct FrameSpec {
    /// Heading, degrees.
    pub heading: f64,
    /// Horizontal field of view, degrees.
    pub fov: f64,
    /// Columns.
    pub width: usize,
}

/// What `vcx bench views` measures.
pub(crate) struct ViewsMeasure {
    /// Objects of the walked scene (screens left out at depth 0).
    pub objects: usize,
    /// Cylinders of its complex.
    pub cylinders: usize,
    /// Viewpoints measured (the free ones).
    pub views: usize,
    /// Median over the viewpoints of each one's best time, seconds per view (or frame).
    pub seconds: f64,
    /// Mean events (cylinders entered by the primary walk) per view.
    pub events: f64,
    /// Mean intervals per view (or ray-tree leaves).
    pub intervals: f64,
}

/// `vcx bench views`' measurement: the full 360° view (depth 0, screens left out) or the
/// ray tree to `depth` (screens kept) from each free point, each timed as the best of
/// `repeat` runs, as a frame of `frame`'s columns if given. The complex is the input's
/// stored one where it is the walked scene's (a `.vcx` file), else built by the sweep.
pub(crate) fn measure_views(
    input: &crate::input::Input,
    points: &Points,
    depth: usize,
    repeat: u32,
    frame: Option<FrameSpec>,
) -> Result<ViewsMeasure, Failure> {
    let file = &input.file;
    let full = file.scene.as_ref();
    let keep = full
        .objects()
        .iter()
        .enumerate()
        .filter(|(_, o)| o.material != Material::Screen)
        .map(|(i, _)| ObjectId(i as u32));
    // Depth 0 walks the complex without screens; ray trees need them in the complex.
    let sub = if depth == 0 {
        SubScene::new(full, keep)
    } else {
        SubScene::new(full, (0..full.len() as u32).map(ObjectId))
    };
    let scene = sub.as_ref();
    let complex = input.complex_for(&scene).map_err(internal)?;
    let points: Vec<QueryPoint> = match points {
        Points::Given(p) => p.clone(),
        Points::Random(k, seed) => random_points(&scene, *k, *seed),
    };
    let width = frame.map_or(0, |f| f.width);
    let mut tree = Box::new(TreeScratch::<64>::new());
    let mut times = Vec::with_capacity(points.len());
    let (mut events, mut boundaries, mut used) = (0usize, 0usize, 0usize);
    for &q in &points {
        if vcx::partition::point_in_scene(&full, q).is_some() {
            continue;
        }
        let camera = match frame {
            Some(f) => Some(
                Camera::new(q, f.heading.to_radians(), f.fov.to_radians(), f.width)
                    .map_err(|e| Failure::bad_input(format!("--heading/--fov/--width: {e}")))?,
            ),
            None => None,
        };
        let mut columns = vec![0usize; width];
        let mut kept: Vec<FrameInterval> = Vec::new();
        let mut count = || -> Result<usize, Failure> {
            Ok(if depth == 0 {
                let v = vcx::walk::view(&complex, &scene, q).map_err(internal)?;
                self::frame(&scene, camera.as_ref(), &v, &mut columns);
                v.len()
            } else {
                match &camera {
                    // A frame walks the ray tree over its field of view only, in lock step
                    // without allocating, as a device does: the scratch and the buffer of
                    // intervals are reused from frame to frame.
                    Some(cam) => {
                        walk_frame(&complex, &scene, cam, depth, &mut tree, &mut kept)
                            .map_err(internal)?;
                        self::frame(&scene, camera.as_ref(), &kept, &mut columns);
                        kept.len()
                    }
                    None => vcx::walk::ray_tree(&complex, &scene, q, depth)
                        .map_err(internal)?
                        .len(),
                }
            })
        };
        let mut best = f64::INFINITY;
        let mut intervals = 0;
        for _ in 0..repeat.max(1) {
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
    times.sort_by(f64::total_cmp);
    let Some(&median) = times.get(times.len() / 2) else {
        return Err(Failure::bad_input("no free viewpoint to measure"));
    };
    Ok(ViewsMeasure {
        objects: scene.len(),
        cylinders: complex.cylinders().len(),
        views: used,
        seconds: median,
        events: events as f64 / used as f64,
        intervals: boundaries as f64 / used as f64,
    })
}

/// The ray tree over `cam`'s field of view into `kept`, in start-angle order: walked in
/// lock step without allocating, as a device does, the scratch and `kept` reused.
pub(crate) fn walk_frame(
    complex: &Complex,
    scene: &SceneRef<'_>,
    cam: &Camera,
    depth: usize,
    scratch: &mut TreeScratch<64>,
    kept: &mut Vec<FrameInterval>,
) -> Result<(), WalkError> {
    let (from, to) = cam.range();
    kept.clear();
    let mut fits = true;
    frame_tree_into(complex, scene, cam.eye(), depth, from, to, scratch, |i| {
        match FrameInterval::new(&i) {
            Some(f) => kept.push(f),
            None => fits = false,
        }
    })?;
    if !fits {
        return Err(WalkError::TreeTooDeep);
    }
    angle_order(kept);
    Ok(())
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
    let mut sum = 0.0;
    centre_hits(scene, camera, intervals, |c, k, hit| {
        if let Some(slot) = columns.get_mut(c) {
            *slot = k;
        }
        if let Some(hit) = hit {
            sum += hit.length;
        }
    });
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
    random_points_between(scene, lo, hi, k, seed)
}

/// `k` random free points of the scene in the closed box `region` (`--region`).
pub(crate) fn random_points_in(
    scene: &vcx::SceneRef<'_>,
    region: &vcx::partition::Region,
    k: usize,
    seed: u64,
) -> Vec<QueryPoint> {
    let (lo, hi) = (region.min().to_query(), region.max().to_query());
    // One more than the width: the upper edges are drawn too.
    random_points_between(scene, (lo.x(), lo.y()), (hi.x() + 1, hi.y() + 1), k, seed)
}

/// `k` random free points in `[lo, hi)` (query grid), at most `20 k` draws.
fn random_points_between(
    scene: &vcx::SceneRef<'_>,
    lo: (i64, i64),
    hi: (i64, i64),
    k: usize,
    seed: u64,
) -> Vec<QueryPoint> {
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
