//! `vcx bench figures [--quick] [--out DIR]`: the paper's experiments (Cho & Forsyth 1999,
//! §7, Figs. 9–19), run time against error and the numerical-stability stress test
//! measured on this machine in one run, as tables and SVG plots in `DIR`
//! (default `bench-out/`) and `DIR/BENCHMARKS.generated.md` (every table, the machine, the
//! date and the command line). `--quick` runs every figure at smaller sizes (CI smoke use);
//! the environment variable `VCX_FIGURES_TINY=1` shrinks them further (for the CLI test).
//!
//! Every figure is one [`Figure`] entry of [`FIGURES`]: a name, a title and a function that
//! measures, returning one table and its plots. Other benchmarks add their figures by
//! appending entries. Produced here (issue 6, item 3; item 5 is this command):
//!
//! * Figs. 9–10: complex and history size and build time against n, grid scene;
//! * Fig. 11: frames per second along a trajectory against n, grid scene;
//! * Figs. 12–13: hall of mirrors, time per frame and scene complexity against depth;
//! * Figs. 14–15: the mixed scene against n at depth 5;
//! * Fig. 16: active set (cylinders touched per frame) against n, grid scene;
//! * Figs. 17–19: screens placed kd-tree fashion and inserted first: size, build time and
//!   frame rate against the number of screens;
//! * "error" (item 2): run time against coverage error, the complex against the quadtree
//!   and BVH ray casters on the hall of mirrors and the mixed scene at depth 5 — time per
//!   frame, mean absolute error and wrong columns per samples per column, the speed-up at
//!   equal error and the error at equal time; plots of error against time (log–log). The
//!   measurement is `vcx bench error`'s ([`bench_error::measure`]): the classical ray
//!   casters of Figs. 12–15 appear here, on those two scenes, not against depth or n;
//! * "stability" (item 4): per family of near-degenerate scenes, failed builds and views
//!   and times of the predicates this binary was built with, measured as by
//!   `vcx bench stability` ([`stability::measure_all`]). The naive-`f64` predicates are a
//!   compile-time choice: with `VCX_FIGURES_NAIVE=PATH` naming a `vcx` built with
//!   `--features naive-f64`, that binary is run per family on the same scenes and joined
//!   as by `vcx bench stability --compare` (naive failures, views differing from the exact
//!   ones, time ratios, one more plot); without it those columns are left empty and the
//!   caption says how to fill them.
//!
//! A frame is the exact full 360° view (or ray tree) from a viewpoint of the built-in
//! circuit ([`vcx_demo::demo::trajectory::circuit`], room capped at 1/2 unit); Fig. 11 also
//! times it turned into 800 columns (per-column hits and exact coverage, 90° field of
//! view along the circuit). Times use [`Instant`]; every frame is timed once per pass, its time is
//! the median over the passes, and the frame rate is frames over the summed frame times.
//! Scenes and insertion orders use fixed seeds, so everything but the times is the same on
//! every run.

use core::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use plotters::prelude::*;
use vcx::geom::Point;
use vcx::partition::{build_by_sweep, BuildOptions, Complex, History};
use vcx::render::Camera;
use vcx::{Material, ObjectId, QueryPoint, SceneRef};
use vcx_demo::demo::World;
use vcx_demo::generate::{generate, SceneKind};
use vcx_demo::scene_file::{ObjectSpec, SceneFile};

use vcx_demo::stress::{Family, SCALES};

use super::bench::{bytes, history_bytes, internal};
use super::{bench_error, stability};
use super::{write_stdout, Failure};

/// Arguments of `vcx bench figures`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Smaller sizes (every plot in under 2 minutes), for CI smoke use.
    #[arg(long)]
    pub quick: bool,
    /// Directory for the SVG files and `BENCHMARKS.generated.md` (created if missing).
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
}

/// One figure (or group of figures sharing a table): measured by `run`.
pub(crate) struct Figure {
    /// Short name, used in progress output.
    pub name: &'static str,
    /// Section title in the markdown.
    pub title: &'static str,
    /// Measures and returns the table and the plots.
    pub run: fn(&Sizes, &mut Progress) -> Result<Output, Failure>,
}

/// What a figure produces: one table, with a caption, and its plots.
pub(crate) struct Output {
    /// Says what was measured and how (markdown).
    pub caption: String,
    /// The table.
    pub table: Table,
    /// The plots, written as SVG files.
    pub plots: Vec<Plot>,
}

/// A markdown table.
pub(crate) struct Table {
    /// Column headers; a leading `<` left-aligns the column (the `<` is not printed).
    pub header: Vec<&'static str>,
    /// Rows of cells, already formatted.
    pub rows: Vec<Vec<String>>,
}

/// A line plot of several series.
pub(crate) struct Plot {
    /// File name in the output directory.
    pub file: String,
    /// Caption above the plot.
    pub title: String,
    /// Axis labels.
    pub x_label: &'static str,
    /// Axis labels.
    pub y_label: &'static str,
    /// Logarithmic axes (points with a coordinate ≤ 0 are then left out).
    pub log_x: bool,
    /// Logarithmic axes.
    pub log_y: bool,
    /// The curves.
    pub series: Vec<Series>,
}

/// One curve.
pub(crate) struct Series {
    /// Legend text.
    pub label: String,
    /// Points `(x, y)`.
    pub points: Vec<(f64, f64)>,
}

/// Every figure, in output order. Append entries here to add figures.
pub(crate) const FIGURES: &[Figure] = &[
    Figure {
        name: "fig09-10",
        title: "Figs. 9–10: size and construction time against n (grid scene)",
        run: fig_construction,
    },
    Figure {
        name: "fig11",
        title: "Fig. 11: frame rate along a trajectory against n (grid scene)",
        run: fig_frame_rate,
    },
    Figure {
        name: "fig12-13",
        title: "Figs. 12–13: hall of mirrors, time per frame and scene complexity against ray-tree depth",
        run: fig_hall,
    },
    Figure {
        name: "fig14-15",
        title: "Figs. 14–15: mixed scene (mirrors, screens, refraction) against n, depth 5",
        run: fig_mixed,
    },
    Figure {
        name: "fig16",
        title: "Fig. 16: active set, cylinders touched per frame against n (grid scene)",
        run: fig_active_set,
    },
    Figure {
        name: "fig17-19",
        title: "Figs. 17–19: screens on grid lines in kd-tree fashion, inserted first",
        run: fig_screens,
    },
    Figure {
        name: "error",
        title: "Run time against error: the complex against the ray casters (hall and mixed, depth 5)",
        run: fig_error,
    },
    Figure {
        name: "stability",
        title: "Numerical stability: near-degenerate scenes at every scale",
        run: fig_stability,
    },
];

/// The sizes of one run.
pub(crate) struct Sizes {
    /// `full`, `quick` or `tiny`.
    pub label: &'static str,
    /// Grid scene sizes (Figs. 9–11, 16).
    pub grid_n: Vec<u32>,
    /// Repetitions of a construction up to this n (median); a single run above it.
    pub repeat_up_to: u32,
    /// Repetitions of small constructions.
    pub repeat: usize,
    /// Frames along a trajectory.
    pub frames: usize,
    /// Passes along a trajectory (each frame's time is the median over passes).
    pub passes: usize,
    /// Pillars of the hall of mirrors.
    pub hall_n: u32,
    /// Deepest ray tree of Figs. 12–13.
    pub hall_depth: usize,
    /// Mixed scene sizes (Figs. 14–15).
    pub mixed_n: Vec<u32>,
    /// Ray-tree depth of Figs. 14–15.
    pub mixed_depth: usize,
    /// Frames along the trajectory of Figs. 14–15 (their frames cost the most).
    pub mixed_frames: usize,
    /// Cells per side of the grid of Figs. 17–19 (the paper: 12, 144 triangles).
    pub screen_cells: i32,
    /// Numbers of screens of Figs. 17–19.
    pub screens: Vec<usize>,
    /// Ray-tree depth of run time against error.
    pub error_depth: usize,
    /// Columns per frame of run time against error.
    pub error_width: usize,
    /// Samples per column of the ray casters.
    pub error_samples: Vec<usize>,
    /// Frames of run time against error.
    pub error_frames: usize,
    /// Runs per frame (the best is kept) of run time against error.
    pub error_repeat: u32,
    /// Stress instances per family and scale.
    pub stability_instances: u64,
    /// Objects per stress scene.
    pub stability_objects: usize,
    /// Viewpoints per stress scene.
    pub stability_views: usize,
    /// Runs per stress build and set of views (the best is kept).
    pub stability_repeat: u32,
}

impl Sizes {
    fn new(quick: bool, tiny: bool) -> Sizes {
        if tiny {
            Sizes {
                label: "tiny",
                grid_n: vec![4, 16],
                repeat_up_to: 16,
                repeat: 1,
                frames: 3,
                passes: 1,
                hall_n: 2,
                hall_depth: 2,
                mixed_n: vec![8, 16],
                mixed_depth: 2,
                mixed_frames: 3,
                screen_cells: 4,
                screens: vec![0, 1, 3],
                error_depth: 5,
                error_width: 40,
                error_samples: vec![1, 4],
                error_frames: 2,
                error_repeat: 1,
                stability_instances: 1,
                stability_objects: 6,
                stability_views: 3,
                stability_repeat: 1,
            }
        } else if quick {
            Sizes {
                label: "quick",
                grid_n: vec![16, 64, 256],
                repeat_up_to: 256,
                repeat: 3,
                frames: 24,
                passes: 3,
                hall_n: 12,
                hall_depth: 6,
                mixed_n: vec![16, 64, 128],
                mixed_depth: 5,
                mixed_frames: 24,
                screen_cells: 8,
                screens: vec![0, 1, 3, 7, 15, 31, 63],
                error_depth: 5,
                error_width: 400,
                error_samples: vec![1, 2, 4, 8, 16, 32, 64, 128, 256],
                error_frames: 4,
                error_repeat: 2,
                // `vcx bench stability --quick`.
                stability_instances: 2,
                stability_objects: 12,
                stability_views: 8,
                stability_repeat: 1,
            }
        } else {
            Sizes {
                label: "full",
                grid_n: vec![16, 64, 256, 1024, 4096],
                repeat_up_to: 1024,
                repeat: 3,
                frames: 100,
                passes: 3,
                hall_n: 12,
                hall_depth: 8,
                mixed_n: vec![16, 64, 128, 256],
                mixed_depth: 5,
                mixed_frames: 40,
                screen_cells: 12,
                screens: vec![0, 1, 3, 7, 15, 31, 63, 143],
                // The defaults of `vcx bench error` and `vcx bench stability`.
                error_depth: 5,
                error_width: 800,
                error_samples: vec![1, 2, 4, 8, 16, 32, 64, 128, 256],
                error_frames: 8,
                error_repeat: 3,
                stability_instances: 10,
                stability_objects: 40,
                stability_views: 24,
                stability_repeat: 5,
            }
        }
    }

    fn repeats(&self, n: u32) -> usize {
        if n <= self.repeat_up_to {
            self.repeat
        } else {
            1
        }
    }
}

/// Seed of every scene generator and insertion order.
const SEED: u64 = 1;

/// Columns of a frame (the paper's 800 × 800 frames).
const FRAME_WIDTH: usize = 800;

/// A plain-text progress bar on stderr: `\r[#####     ] 12/40 grid n=1024`.
pub(crate) struct Progress {
    prefix: String,
    total: usize,
    done: usize,
}

impl Progress {
    fn new() -> Progress {
        Progress {
            prefix: String::new(),
            total: 0,
            done: 0,
        }
    }

    /// Starts a figure of `total` steps.
    pub fn start(&mut self, total: usize) {
        self.total = total.max(1);
        self.done = 0;
        self.draw("");
    }

    /// One step done; `label` says what comes next.
    pub fn step(&mut self, label: &str) {
        self.done = (self.done + 1).min(self.total);
        self.draw(label);
    }

    fn draw(&self, label: &str) {
        const WIDTH: usize = 20;
        let filled = WIDTH * self.done / self.total.max(1);
        let bar: String = (0..WIDTH)
            .map(|i| if i < filled { '#' } else { ' ' })
            .collect();
        let mut err = std::io::stderr().lock();
        // Pad so a shorter label overwrites a longer one.
        let _ = write!(
            err,
            "\r{} [{bar}] {}/{} {label:<40}",
            self.prefix, self.done, self.total
        );
        let _ = err.flush();
    }

    fn finish(&self) {
        let _ = writeln!(std::io::stderr());
    }
}

/// Runs every figure and writes the output directory.
pub fn run(a: &Args) -> Result<(), Failure> {
    let tiny = std::env::var("VCX_FIGURES_TINY").is_ok_and(|v| v == "1");
    let sizes = Sizes::new(a.quick, tiny);
    std::fs::create_dir_all(&a.out)
        .map_err(|e| Failure::bad_input(format!("cannot create {}: {e}", a.out.display())))?;
    let started = Instant::now();
    let date = utc_now();
    // The 1, 5 and 15 minute load averages (other work on the machine skews the times).
    let load_before = read_trimmed("/proc/loadavg")
        .map(|l| l.split_whitespace().take(3).collect::<Vec<_>>().join(" "));
    let mut body = String::new();
    let mut progress = Progress::new();
    let mut plots = 0;
    for (k, fig) in FIGURES.iter().enumerate() {
        progress.prefix = format!("[{}/{}] {}", k + 1, FIGURES.len(), fig.name);
        progress.start(1);
        let t = Instant::now();
        let out = (fig.run)(&sizes, &mut progress)?;
        let secs = t.elapsed().as_secs_f64();
        progress.finish();
        let _ = writeln!(body, "### {}\n", fig.title);
        let _ = writeln!(body, "{}\n", out.caption.trim());
        body.push_str(&markdown_table(&out.table));
        let _ = writeln!(body, "\n(measured in {secs:.1} s)\n");
        for plot in &out.plots {
            let svg = render_svg(plot).map_err(|e| internal(format!("{}: {e}", plot.file)))?;
            write_file(&a.out.join(&plot.file), &svg)?;
            plots += 1;
            let _ = writeln!(body, "![{}]({})\n", plot.title, plot.file);
        }
    }
    let total = started.elapsed().as_secs_f64();
    let mut md = String::new();
    let _ = writeln!(md, "# Figures (vcx bench figures)\n");
    let _ = writeln!(
        md,
        "Generated by `{}` on {date} ({} sizes) in {total:.1} s.\n",
        command_line(),
        sizes.label
    );
    let _ = writeln!(md, "Machine: {}.\n", machine());
    if let Some(l) = load_before {
        let _ = writeln!(md, "Load average at the start (1, 5, 15 min): {l}.\n");
    }
    md.push_str(&body);
    let path = a.out.join("BENCHMARKS.generated.md");
    write_file(&path, &md)?;
    write_stdout(&format!(
        "wrote {} and {plots} plots in {total:.1} s\n",
        path.display()
    ))
}

fn write_file(path: &Path, text: &str) -> Result<(), Failure> {
    std::fs::write(path, text)
        .map_err(|e| Failure::bad_input(format!("cannot write {}: {e}", path.display())))
}

// ---------------------------------------------------------------------------------------
// Measurements shared by the figures.

/// Median of `v` (NaN for none).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// One construction: seconds (median over `repeat` runs) and the results of the last run.
struct Built {
    seconds: f64,
    complex: Complex,
    history: Option<vcx::partition::HistoryStats>,
}

fn build_ric(scene: &SceneRef<'_>, first: &[ObjectId], repeat: usize) -> Result<Built, Failure> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        let h = History::build(
            scene,
            &BuildOptions {
                seed: SEED,
                first: first.to_vec(),
                ..Default::default()
            },
        )
        .map_err(internal)?;
        times.push(t.elapsed().as_secs_f64());
        last = Some(h);
    }
    let h = last.ok_or_else(|| internal("no run"))?;
    Ok(Built {
        seconds: median(&mut times),
        complex: h.complex(scene).map_err(internal)?,
        history: Some(h.stats()),
    })
}

fn build_sweep(scene: &SceneRef<'_>, repeat: usize) -> Result<Built, Failure> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        let c = build_by_sweep(scene).map_err(internal)?;
        times.push(t.elapsed().as_secs_f64());
        last = Some(c);
    }
    Ok(Built {
        seconds: median(&mut times),
        complex: last.ok_or_else(|| internal("no run"))?,
        history: None,
    })
}

/// Free viewpoints along the built-in circuit ([`vcx_demo::demo::trajectory::circuit`]: an ellipse around
/// the middle of the scene, each point pushed along its radius to a free point with some
/// room), with two changes so that every frame finds a viewpoint: the room is capped at
/// half a unit (the circuit asks for 1 % of the scene's extent, more than the gaps between
/// the cells of a large grid), and the point must be outside every object of the scene,
/// screens included (ray trees need that).
fn poses(world: &World, frames: usize) -> Vec<QueryPoint> {
    let (x0, y0, x1, y1) = world.bbox;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let (rx, ry) = (0.3 * (x1 - x0).max(1.0), 0.3 * (y1 - y0).max(1.0));
    let room = (0.01 * world.extent()).min(0.5);
    let free = |x: f64, y: f64| -> Option<QueryPoint> {
        let q = QueryPoint::from_f64(x, y).ok()?;
        (world.clearance(x, y) >= room && world.blocked_in_scene(q).is_none()).then_some(q)
    };
    let mut out = Vec::with_capacity(frames);
    for k in 0..frames {
        let phi = core::f64::consts::TAU * k as f64 / frames.max(1) as f64;
        // Scales 1, 1.02, 0.98, 1.04, 0.96, … as the circuit.
        let found = (0..40).find_map(|j| {
            let step = f64::from((j + 1) / 2) * 0.02;
            let s = if j % 2 == 1 { 1.0 + step } else { 1.0 - step };
            free(cx + s * rx * phi.cos(), cy + s * ry * phi.sin())
        });
        out.extend(found);
    }
    out
}

/// Frames along a trajectory.
struct Frames {
    /// Frames measured (viewpoints whose walk succeeded).
    frames: usize,
    /// Viewpoints left out because the walk failed (a rounded virtual eye, …).
    failed: usize,
    /// Mean seconds per frame: each frame's median over the passes, averaged.
    seconds: f64,
    /// Mean intervals per frame (view or ray-tree leaves: the scene complexity).
    intervals: f64,
    /// Mean steps of the primary walk per frame (cylinders entered).
    events: f64,
    /// Mean distinct cylinders the primary walk entered per frame (the active set).
    active: f64,
}

/// Which walk makes a frame.
#[derive(Clone, Copy)]
enum Walk {
    /// `vcx::walk::view` (complex without screens).
    View,
    /// The view turned into a frame of this many columns with a 90° field of view, looking
    /// along the circuit around this centre: per-column hits and exact coverage
    /// (`vcx bench views --fov 90 --width W` measures the same).
    Columns(usize, (f64, f64)),
    /// `vcx::walk::ray_tree` to this depth (complex with every object).
    Tree(usize),
}

fn frames(
    complex: &Complex,
    scene: &SceneRef<'_>,
    points: &[QueryPoint],
    walk: Walk,
    passes: usize,
) -> Result<Frames, Failure> {
    let run = |q: QueryPoint| -> Result<usize, vcx::walk::WalkError> {
        Ok(match walk {
            Walk::View => vcx::walk::view(complex, scene, q)?.len(),
            Walk::Columns(width, (cx, cy)) => {
                let v = vcx::walk::view(complex, scene, q)?;
                // The circuit runs counter-clockwise around the centre: look along it.
                let (x, y) = q.to_f64();
                let heading = (y - cy).atan2(x - cx) + core::f64::consts::FRAC_PI_2;
                let fov = core::f64::consts::FRAC_PI_2;
                // The camera's arguments are valid constants and a finite heading.
                if let Ok(camera) = Camera::new(q, heading, fov, width) {
                    let mut columns = vec![0usize; width];
                    super::bench::frame(scene, Some(&camera), &v, &mut columns);
                }
                v.len()
            }
            Walk::Tree(d) => vcx::walk::ray_tree(complex, scene, q, d)?.len(),
        })
    };
    // Drop the viewpoints whose walk fails, once, before timing.
    let mut good = Vec::new();
    let mut intervals = 0usize;
    for &q in points {
        if let Ok(k) = run(q) {
            intervals += k;
            good.push(q);
        }
    }
    let mut times = vec![Vec::with_capacity(passes); good.len()];
    for _ in 0..passes.max(1) {
        for (q, t) in good.iter().zip(times.iter_mut()) {
            let start = Instant::now();
            let k = core::hint::black_box(run(*q));
            let secs = start.elapsed().as_secs_f64();
            k.map_err(internal)?;
            t.push(secs);
        }
    }
    let (mut events, mut active) = (0usize, 0usize);
    for &q in &good {
        let mut seen = Vec::new();
        complex
            .walk_trace(scene, q, |s| seen.push(s.cylinder))
            .map_err(internal)?;
        events += seen.len();
        seen.sort_unstable_by_key(|c| c.index());
        seen.dedup();
        active += seen.len();
    }
    let k = good.len().max(1) as f64;
    let total: f64 = times.iter_mut().map(|t| median(t)).sum();
    Ok(Frames {
        frames: good.len(),
        failed: points.len() - good.len(),
        seconds: if good.is_empty() { f64::NAN } else { total / k },
        intervals: intervals as f64 / k,
        events: events as f64 / k,
        active: active as f64 / k,
    })
}

fn world(kind: SceneKind, n: u32) -> Result<World, Failure> {
    let file = generate(kind, n, SEED).map_err(|e| Failure::bad_input(e.to_string()))?;
    World::new(file, format!("{} {n}", kind.name()), false).map_err(internal)
}

// ---------------------------------------------------------------------------------------
// The figures.

fn fig_construction(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(2 * s.grid_n.len());
    let mut rows = Vec::new();
    let (mut cyl, mut nodes, mut cbytes, mut hbytes) = (vec![], vec![], vec![], vec![]);
    let (mut t_ric, mut t_sweep) = (vec![], vec![]);
    for &n in &s.grid_n {
        let file = generate(SceneKind::Grid, n, SEED).map_err(|e| internal(e.to_string()))?;
        let scene = file.scene.as_ref();
        p.step(&format!("grid n={n} ric"));
        let ric = build_ric(&scene, &[], s.repeats(n))?;
        p.step(&format!("grid n={n} sweep"));
        let sweep = build_sweep(&scene, s.repeats(n))?;
        let x = f64::from(n);
        for (method, b) in [("ric", &ric), ("sweep", &sweep)] {
            let c = &b.complex;
            let h = b.history;
            rows.push(vec![
                n.to_string(),
                method.to_string(),
                s.repeats(n).to_string(),
                format!("{:.4}", b.seconds),
                thousands(c.cylinders().len()),
                thousands(c.vertices().len()),
                thousands(bytes(c)),
                h.map_or("—".into(), |h| thousands(h.nodes)),
                h.map_or("—".into(), |h| thousands(h.links)),
                h.map_or("—".into(), |h| h.depth.to_string()),
                h.map_or("—".into(), |h| thousands(history_bytes(&h))),
            ]);
        }
        cyl.push((x, ric.complex.cylinders().len() as f64));
        cbytes.push((x, bytes(&ric.complex) as f64));
        if let Some(h) = ric.history {
            nodes.push((x, h.nodes as f64));
            hbytes.push((x, history_bytes(&h) as f64));
        }
        t_ric.push((x, ric.seconds));
        t_sweep.push((x, sweep.seconds));
    }
    Ok(Output {
        caption: format!(
            "Scene `vcx gen grid N --seed {SEED}`, insertion-order seed {SEED}. `ric`: randomized \
             incremental construction with history (§4); `sweep`: rotational sweep of the same \
             canonical partition, no history. Seconds: median of `runs` constructions. Bytes: \
             cylinders + vertices of the complex; history: each node's cylinder record plus 4 \
             bytes per link. Our history links every destroyed cylinder directly to its \
             replacements, which is the paper's search path compaction (§4.4): there is no \
             uncompacted variant to compare with."
        ),
        table: Table {
            header: vec![
                "n",
                "<method",
                "runs",
                "seconds",
                "cylinders",
                "complex vertices",
                "complex bytes",
                "history nodes",
                "links",
                "depth",
                "history bytes",
            ],
            rows,
        },
        plots: vec![
            Plot {
                file: "fig09_size.svg".into(),
                title: "Fig. 9: size of the complex and of its history (grid scene)".into(),
                x_label: "objects n",
                y_label: "count / bytes",
                log_x: true,
                log_y: true,
                series: vec![
                    series("complex cylinders", cyl),
                    series("complex bytes", cbytes),
                    series("history nodes", nodes),
                    series("history bytes", hbytes),
                ],
            },
            Plot {
                file: "fig10_build_time.svg".into(),
                title: "Fig. 10: construction time (grid scene)".into(),
                x_label: "objects n",
                y_label: "seconds",
                log_x: true,
                log_y: true,
                series: vec![
                    series("randomized incremental (history)", t_ric),
                    series("rotational sweep", t_sweep),
                ],
            },
        ],
    })
}

fn fig_frame_rate(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(s.grid_n.len());
    let mut rows = Vec::new();
    let (mut fps, mut fps_columns) = (vec![], vec![]);
    for &n in &s.grid_n {
        p.step(&format!("grid n={n}"));
        let w = world(SceneKind::Grid, n)?;
        let points = poses(&w, s.frames);
        let sub = w.sub();
        let f = frames(&w.complex, &sub.as_ref(), &points, Walk::View, s.passes)?;
        let (x0, y0, x1, y1) = w.bbox;
        let columns = Walk::Columns(FRAME_WIDTH, ((x0 + x1) / 2.0, (y0 + y1) / 2.0));
        let c = frames(&w.complex, &sub.as_ref(), &points, columns, s.passes)?;
        let x = f64::from(n);
        fps.push((x, 1.0 / f.seconds));
        fps_columns.push((x, 1.0 / c.seconds));
        rows.push(vec![
            n.to_string(),
            thousands(w.complex.cylinders().len()),
            f.frames.to_string(),
            format!("{:.1}", f.seconds * 1e6),
            format!("{:.0}", 1.0 / f.seconds),
            format!("{:.1}", c.seconds * 1e6),
            format!("{:.0}", 1.0 / c.seconds),
            format!("{:.1}", f.intervals),
        ]);
    }
    Ok(Output {
        caption: format!(
            "Scene `vcx gen grid N --seed {SEED}`, complex by the sweep. A view is the exact \
             full 360° view (`vcx::walk::view`) from a viewpoint of the built-in circuit (an \
             ellipse around the middle of the scene); a frame is that view turned into \
             {FRAME_WIDTH} columns looking along the circuit with a 90° field of view: \
             per-column hits and exact coverage (`vcx::render`, as `vcx bench views --fov 90 \
             --width {FRAME_WIDTH}`). The walk is the full circle either way (the field-of-view \
             restriction, `walk::view_range`, walks everything). {} passes; each frame's time \
             is its median over the passes; frames/s = frames ÷ summed times.",
            s.passes
        ),
        table: Table {
            header: vec![
                "n",
                "cylinders",
                "frames",
                "µs per view",
                "views/s",
                "µs per frame",
                "frames/s",
                "intervals per frame",
            ],
            rows,
        },
        plots: vec![Plot {
            file: "fig11_frame_rate.svg".into(),
            title: "Fig. 11: frames per second along a trajectory (grid scene)".into(),
            x_label: "objects n",
            y_label: "frames per second",
            log_x: true,
            log_y: true,
            series: vec![
                series("full 360° view", fps),
                series(&format!("{FRAME_WIDTH}-column frame"), fps_columns),
            ],
        }],
    })
}

fn fig_hall(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(s.hall_depth + 2);
    p.step(&format!("hall n={} build", s.hall_n));
    let w = world(SceneKind::Hall, s.hall_n)?;
    let full = w.full_complex().map_err(internal)?;
    let scene = w.scene();
    let points = poses(&w, s.frames);
    let mut rows = Vec::new();
    let (mut time, mut intervals, mut events) = (vec![], vec![], vec![]);
    for depth in 0..=s.hall_depth {
        p.step(&format!("hall depth={depth}"));
        let f = frames(full, &scene, &points, Walk::Tree(depth), s.passes)?;
        let x = depth as f64;
        time.push((x, f.seconds * 1e6));
        intervals.push((x, f.intervals));
        events.push((x, f.events));
        rows.push(vec![
            depth.to_string(),
            f.frames.to_string(),
            f.failed.to_string(),
            format!("{:.1}", f.seconds * 1e6),
            format!("{:.0}", 1.0 / f.seconds),
            format!("{:.1}", f.intervals),
            format!("{:.1}", f.events),
        ]);
    }
    Ok(Output {
        caption: format!(
            "Scene `vcx gen hall {} --seed {SEED}` (four mirror walls, {} pillars), complex \
             over every object by the sweep ({} cylinders). A frame is the full 360° ray tree \
             (`vcx::walk::ray_tree`) to the given depth from a viewpoint of the built-in \
             circuit; {} passes, each frame's median, averaged. Scene complexity: intervals \
             of the ray tree per frame (directions where the branch changes); events: \
             cylinders entered by the primary walk. Failed: viewpoints left out because a \
             walk of their tree failed (a rounded virtual eye). The quadtree ray tracer is \
             measured by `vcx bench error`.",
            s.hall_n,
            s.hall_n,
            thousands(full.cylinders().len()),
            s.passes
        ),
        table: Table {
            header: vec![
                "depth",
                "frames",
                "failed",
                "µs per frame",
                "frames/s",
                "intervals per frame",
                "events per frame",
            ],
            rows,
        },
        plots: vec![
            Plot {
                file: "fig12_hall_time.svg".into(),
                title: "Fig. 12: hall of mirrors, time per frame against ray-tree depth".into(),
                x_label: "ray-tree depth",
                y_label: "µs per frame",
                log_x: false,
                log_y: false,
                series: vec![series("visibility complex", time)],
            },
            Plot {
                file: "fig13_hall_complexity.svg".into(),
                title: "Fig. 13: hall of mirrors, scene complexity against ray-tree depth".into(),
                x_label: "ray-tree depth",
                y_label: "per frame",
                log_x: false,
                log_y: false,
                series: vec![
                    series("intervals (scene complexity)", intervals),
                    series("primary walk events", events),
                ],
            },
        ],
    })
}

fn fig_mixed(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(s.mixed_n.len());
    let mut rows = Vec::new();
    let (mut fps, mut intervals) = (vec![], vec![]);
    for &n in &s.mixed_n {
        p.step(&format!("mixed n={n}"));
        let w = world(SceneKind::Mixed, n)?;
        let full = w.full_complex().map_err(internal)?;
        let scene = w.scene();
        let points = poses(&w, s.mixed_frames);
        let f = frames(full, &scene, &points, Walk::Tree(s.mixed_depth), s.passes)?;
        let x = f64::from(n);
        fps.push((x, 1.0 / f.seconds));
        intervals.push((x, f.intervals));
        rows.push(vec![
            n.to_string(),
            w.screens().to_string(),
            thousands(full.cylinders().len()),
            f.frames.to_string(),
            f.failed.to_string(),
            format!("{:.1}", f.seconds * 1e6),
            format!("{:.0}", 1.0 / f.seconds),
            format!("{:.1}", f.intervals),
            format!("{:.1}", f.events),
        ]);
    }
    Ok(Output {
        caption: format!(
            "Scene `vcx gen mixed N --seed {SEED}` (opaque blocks, mirror slabs, refractive \
             discs, n/10 screens), complex over every object by the sweep. A frame is the full \
             360° ray tree to depth {} from a viewpoint of the built-in circuit; {} passes, \
             each frame's median, averaged. Columns as in Figs. 12–13.",
            s.mixed_depth, s.passes
        ),
        table: Table {
            header: vec![
                "n",
                "screens",
                "cylinders",
                "frames",
                "failed",
                "µs per frame",
                "frames/s",
                "intervals per frame",
                "events per frame",
            ],
            rows,
        },
        plots: vec![
            Plot {
                file: "fig14_mixed_frame_rate.svg".into(),
                title: format!(
                    "Fig. 14: mixed scene, frames per second at depth {}",
                    s.mixed_depth
                ),
                x_label: "objects n",
                y_label: "frames per second",
                log_x: true,
                log_y: true,
                series: vec![series("visibility complex", fps)],
            },
            Plot {
                file: "fig15_mixed_complexity.svg".into(),
                title: "Fig. 15: mixed scene, scene complexity (intervals per frame)".into(),
                x_label: "objects n",
                y_label: "intervals per frame",
                log_x: true,
                log_y: false,
                series: vec![series("visibility complex", intervals)],
            },
        ],
    })
}

fn fig_active_set(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(s.grid_n.len());
    let mut rows = Vec::new();
    let (mut steps, mut distinct, mut share) = (vec![], vec![], vec![]);
    for &n in &s.grid_n {
        p.step(&format!("grid n={n}"));
        let w = world(SceneKind::Grid, n)?;
        let points = poses(&w, s.frames);
        let sub = w.sub();
        // One pass: only the walk statistics are used, not the times.
        let f = frames(&w.complex, &sub.as_ref(), &points, Walk::View, 1)?;
        let cylinders = w.complex.cylinders().len();
        let x = f64::from(n);
        steps.push((x, f.events));
        distinct.push((x, f.active));
        share.push((x, 100.0 * f.active / cylinders.max(1) as f64));
        rows.push(vec![
            n.to_string(),
            thousands(cylinders),
            f.frames.to_string(),
            format!("{:.1}", f.events),
            format!("{:.1}", f.active),
            format!("{:.3}", 100.0 * f.active / cylinders.max(1) as f64),
        ]);
    }
    Ok(Output {
        caption: format!(
            "Scene `vcx gen grid N --seed {SEED}`, complex by the sweep, viewpoints of the \
             built-in circuit. Steps: calls of `Complex::walk_trace`'s step per frame (the \
             cylinders entered by the full 360° walk, the start cylinder included); distinct: \
             the active set, the distinct cylinders among them. The history is not walked \
             (the view starts by locating θ = 0 among the cylinders)."
        ),
        table: Table {
            header: vec![
                "n",
                "cylinders",
                "frames",
                "walk steps per frame",
                "active set (distinct cylinders)",
                "% of the complex",
            ],
            rows,
        },
        plots: vec![Plot {
            file: "fig16_active_set.svg".into(),
            title: "Fig. 16: cylinders touched per frame (grid scene)".into(),
            x_label: "objects n",
            y_label: "cylinders per frame",
            log_x: true,
            log_y: false,
            series: vec![
                series("walk steps", steps),
                series("distinct cylinders (active set)", distinct),
            ],
        }],
    })
}

/// Side of a grid cell of `vcx gen grid`, in scene units.
const CELL: i32 = 10;
/// Raw grid units (2⁻¹⁶) per 1/64 scene unit, the step of generated coordinates.
const STEP_RAW: i32 = 1 << 10;

/// Screens on the lines of a `cells × cells` grid of cells of side [`CELL`] from the
/// origin (the layout of `vcx gen grid`), placed as the splits of a kd-tree in
/// breadth-first order: the first cuts the whole grid across its longer side through the
/// middle grid line, the next two cut each half, and so on while a region is wider than
/// one cell; `count` splits at most. Each screen is a box 1/4 unit thick on its grid line,
/// stopping 1/2 unit short of its region's ends, so screens never touch each other, and
/// cell contents (1 unit inside their cells) stay clear.
pub(crate) fn kd_screens(cells: i32, count: usize) -> Vec<Vec<Point>> {
    let mut regions = std::collections::VecDeque::from([(0, 0, cells, cells)]);
    let mut out = Vec::new();
    let p = |x: i32, y: i32| Point::from_raw(x * STEP_RAW, y * STEP_RAW);
    let (half, end, cell) = (8, 32, CELL * 64); // in 1/64 units
                                                // Every split makes one more region and a region is popped once: at most cells² − 1
                                                // splits and cells² single cells.
    let bound = 2 * (cells.max(0) as usize).pow(2);
    for _ in 0..bound {
        if out.len() >= count {
            break;
        }
        let Some((x0, y0, x1, y1)) = regions.pop_front() else {
            break;
        };
        let (w, h) = (x1 - x0, y1 - y0);
        if w < 2 && h < 2 {
            continue;
        }
        let boxed = if w >= h {
            let m = (x0 + x1) / 2;
            regions.push_back((x0, y0, m, y1));
            regions.push_back((m, y0, x1, y1));
            let l = m * cell;
            [
                p(l - half, y0 * cell + end),
                p(l + half, y0 * cell + end),
                p(l + half, y1 * cell - end),
                p(l - half, y1 * cell - end),
            ]
        } else {
            let m = (y0 + y1) / 2;
            regions.push_back((x0, y0, x1, m));
            regions.push_back((x0, m, x1, y1));
            let l = m * cell;
            [
                p(x0 * cell + end, l - half),
                p(x1 * cell - end, l - half),
                p(x1 * cell - end, l + half),
                p(x0 * cell + end, l + half),
            ]
        };
        if let [Some(a), Some(b), Some(c), Some(d)] = boxed {
            out.push(vec![a, b, c, d]);
        }
    }
    out
}

/// The grid scene of `cells²` triangles with `screens` kd-tree screens, screens first.
fn screen_scene(cells: i32, screens: usize) -> Result<SceneFile, Failure> {
    let n = (cells * cells) as u32;
    let grid = generate(SceneKind::Grid, n, SEED).map_err(|e| internal(e.to_string()))?;
    let scene = grid.scene.as_ref();
    let mut objects: Vec<ObjectSpec> = kd_screens(cells, screens)
        .into_iter()
        .map(|vertices| ObjectSpec {
            material: Material::Screen,
            vertices,
            extra: Default::default(),
        })
        .collect();
    objects.extend(scene.objects().iter().map(|o| ObjectSpec {
        material: o.material,
        vertices: scene.polygon(o).to_vec(),
        extra: Default::default(),
    }));
    SceneFile::new(objects, Default::default()).map_err(internal)
}

fn fig_screens(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(s.screens.len());
    let n = s.screen_cells * s.screen_cells;
    let mut rows = Vec::new();
    let (mut cyl, mut nodes, mut time, mut fps) = (vec![], vec![], vec![], vec![]);
    for &k in &s.screens {
        p.step(&format!("{k} screens"));
        let file = screen_scene(s.screen_cells, k)?;
        let placed = file
            .scene
            .as_ref()
            .objects()
            .iter()
            .filter(|o| o.material == Material::Screen)
            .count();
        let first: Vec<ObjectId> = (0..placed as u32).map(ObjectId).collect();
        let w =
            World::new(file, format!("grid {n} + {placed} screens"), false).map_err(internal)?;
        let scene = w.scene();
        let b = build_ric(&scene, &first, s.repeat)?;
        let points = poses(&w, s.frames);
        let f = frames(&b.complex, &scene, &points, Walk::Tree(0), s.passes)?;
        let x = placed as f64;
        cyl.push((x, b.complex.cylinders().len() as f64));
        if let Some(h) = b.history {
            nodes.push((x, h.nodes as f64));
        }
        time.push((x, b.seconds));
        fps.push((x, 1.0 / f.seconds));
        let h = b.history;
        rows.push(vec![
            placed.to_string(),
            thousands(b.complex.cylinders().len()),
            thousands(b.complex.vertices().len()),
            thousands(bytes(&b.complex)),
            h.map_or("—".into(), |h| thousands(h.nodes)),
            h.map_or("—".into(), |h| thousands(history_bytes(&h))),
            format!("{:.4}", b.seconds),
            f.frames.to_string(),
            format!("{:.1}", f.seconds * 1e6),
            format!("{:.0}", 1.0 / f.seconds),
            format!("{:.1}", f.intervals),
        ]);
    }
    Ok(Output {
        caption: format!(
            "Scene `vcx gen grid {n} --seed {SEED}` ({c} × {c} triangles) plus screens (thin \
             boxes 1/4 unit thick) on grid lines as the splits of a kd-tree in breadth-first \
             order (`kd_screens` in `std-demo/src/cmd/figures.rs`). Construction: randomized \
             incremental with the screens inserted first (`BuildOptions::first`), the \
             triangles after in random order (seed {SEED}); seconds: median of {r} runs. \
             Frame: the full 360° depth-0 ray tree (walking through the screens) from a \
             viewpoint of the built-in circuit; {pa} passes, each frame's median, averaged.",
            c = s.screen_cells,
            r = s.repeat,
            pa = s.passes
        ),
        table: Table {
            header: vec![
                "screens",
                "cylinders",
                "complex vertices",
                "complex bytes",
                "history nodes",
                "history bytes",
                "build seconds",
                "frames",
                "µs per frame",
                "frames/s",
                "intervals per frame",
            ],
            rows,
        },
        plots: vec![
            Plot {
                file: "fig17_screens_size.svg".into(),
                title: "Fig. 17: size against the number of screens".into(),
                x_label: "screens",
                y_label: "count",
                log_x: false,
                log_y: false,
                series: vec![
                    series("complex cylinders", cyl),
                    series("history nodes", nodes),
                ],
            },
            Plot {
                file: "fig18_screens_build_time.svg".into(),
                title: "Fig. 18: construction time against the number of screens".into(),
                x_label: "screens",
                y_label: "seconds",
                log_x: false,
                log_y: false,
                series: vec![series("randomized incremental, screens first", time)],
            },
            Plot {
                file: "fig19_screens_frame_rate.svg".into(),
                title: "Fig. 19: frame rate against the number of screens".into(),
                x_label: "screens",
                y_label: "frames per second",
                log_x: false,
                log_y: false,
                series: vec![series("depth-0 ray tree", fps)],
            },
        ],
    })
}

// ---------------------------------------------------------------------------------------
// Run time against error (issue 6, item 2) and numerical stability (item 4): the
// measurements of `vcx bench error` and `vcx bench stability`, shown as figures.

/// The scenes of `vcx bench error` in BENCHMARKS.md: `std-demo/scenes/hall.json` and
/// `mixed.json` are `vcx gen` of these.
const ERROR_SCENES: [(SceneKind, u32); 2] = [(SceneKind::Hall, 12), (SceneKind::Mixed, 30)];

/// A share in `[0, 1]` as a percentage.
fn percent(v: f64) -> String {
    format!("{:.3} %", 100.0 * v)
}

/// A ratio with three significant digits or so: `0.0123×`, `1.14×`, `69×`.
fn ratio(x: f64) -> String {
    if x >= 10.0 {
        format!("{x:.0}×")
    } else if x >= 1.0 {
        format!("{x:.2}×")
    } else {
        format!("{x:.3}×")
    }
}

/// One caster against the complex, for the caption: speed-up at each error limit and the
/// error at equal time.
fn versus_text(name: &str, v: &bench_error::Versus) -> String {
    let mut parts = Vec::new();
    for (((_, limit), at), speedup) in bench_error::LIMITS.iter().zip(v.at).zip(v.speedup) {
        let what = match (at, speedup) {
            (Some(p), Some((x, _))) => format!("{} (s = {})", ratio(x), p.samples),
            // Time grows with the samples: the most samples measured give a lower bound.
            (None, Some((x, _))) => format!("≥ {} (no s reached it)", ratio(x)),
            _ => "—".to_string(),
        };
        parts.push(format!("≤ {} %: {what}", 100.0 * limit));
    }
    let equal = v
        .equal_time
        .map_or("no s is as fast as the complex".to_string(), |p| {
            format!(
                "s = {}: {} error, {} of columns wrong",
                p.samples,
                percent(p.error),
                percent(p.wrong)
            )
        });
    format!(
        "{name}: speed-up of the complex at equal error {}; error at the complex's time: {equal}",
        parts.join(", ")
    )
}

fn fig_error(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(ERROR_SCENES.len());
    let params = bench_error::Params {
        depth: s.error_depth,
        width: s.error_width,
        samples: s.error_samples.clone(),
        frames: s.error_frames,
        fov: 90.0,
        seed: SEED,
        repeat: s.error_repeat,
    };
    let mut rows = Vec::new();
    let mut notes = Vec::new();
    let mut plots = Vec::new();
    for (kind, n) in ERROR_SCENES {
        let name = kind.name();
        p.step(&format!("{name} {n}"));
        let file = generate(kind, n, SEED).map_err(|e| internal(e.to_string()))?;
        let m = bench_error::measure(&file.scene.as_ref(), &params)?;
        let c = m.complex_seconds;
        rows.push(vec![
            name.to_string(),
            "complex".to_string(),
            "exact".to_string(),
            m.frames.to_string(),
            format!("{:.1}", c * 1e6),
            percent(0.0),
            percent(0.0),
            "1.00".to_string(),
        ]);
        for (method, curve) in [("quadtree", &m.quadtree), ("bvh", &m.bvh)] {
            for q in curve {
                rows.push(vec![
                    name.to_string(),
                    method.to_string(),
                    q.samples.to_string(),
                    m.frames.to_string(),
                    format!("{:.1}", q.seconds * 1e6),
                    percent(q.error),
                    percent(q.wrong),
                    format!("{:.2}", q.seconds / c),
                ]);
            }
        }
        notes.push(format!(
            "* **{name}** (`vcx gen {name} {n} --seed {SEED}`, = `std-demo/scenes/{name}.json`: \
             {} objects, {:.1} intervals per 360° tree, quadtree of {} nodes): complex {:.1} µs \
             per frame (ray tree {:.1}, coverage {:.1}).\n  {}.\n  {}.",
            m.objects,
            m.intervals,
            m.quadtree_nodes,
            c * 1e6,
            m.tree_seconds * 1e6,
            m.cover_seconds * 1e6,
            versus_text("quadtree", &bench_error::versus(&m.quadtree, c)),
            versus_text("bvh", &bench_error::versus(&m.bvh, c)),
        ));
        // Error in % against µs per frame; the complex (error 0, off a log axis) as a
        // vertical line across the casters' errors, the 1 % target as a horizontal one.
        let pts = |curve: &[bench_error::Point]| -> Vec<(f64, f64)> {
            curve
                .iter()
                .map(|q| (q.seconds * 1e6, 100.0 * q.error))
                .collect()
        };
        let (qt, bv) = (pts(&m.quadtree), pts(&m.bvh));
        let positive = || qt.iter().chain(&bv).filter(|q| q.1 > 0.0);
        let lo = positive().map(|q| q.1).fold(1.0, f64::min);
        let hi = positive().map(|q| q.1).fold(1.0, f64::max);
        let t0 = qt.iter().chain(&bv).map(|q| q.0).fold(c * 1e6, f64::min);
        let t1 = qt.iter().chain(&bv).map(|q| q.0).fold(c * 1e6, f64::max);
        plots.push(Plot {
            file: format!("error_{name}.svg"),
            title: format!(
                "{name}: coverage error against time per frame, depth {}",
                s.error_depth
            ),
            x_label: "µs per frame",
            y_label: "mean abs. coverage error per column (%)",
            log_x: true,
            log_y: true,
            series: vec![
                series("quadtree", qt.clone()),
                series("bvh (parry2d)", bv.clone()),
                series("complex (error 0)", vec![(c * 1e6, lo), (c * 1e6, hi)]),
                series("1 % error", vec![(t0, 1.0), (t1, 1.0)]),
            ],
        });
    }
    Ok(Output {
        caption: format!(
            "The measurement of `vcx bench error SCENE --depth {d} --width {w} --samples {sa} \
             --frames {f} --repeat {r}` (`std-demo/src/cmd/bench_error.rs`; section \"Run time \
             against error\"): along {f} free viewpoints of a seeded walk, each 90° frame of \
             {w} columns is rendered by the complex (the 360° ray tree to depth {d} plus the \
             exact per-column coverage: the truth, error 0) and by the quadtree and BVH ray \
             casters with s stratified rays per column. µs per frame: the best of {r} runs of \
             each frame, median over the frames. Error: half the L1 distance between the \
             estimated and the exact coverage of a column, averaged over columns and frames; \
             wrong: share of columns whose dominant branch differs. Time / complex: the \
             caster's time over the complex's, i.e. the complex's speed-up at that error.\n\n{}",
            notes.join("\n"),
            d = s.error_depth,
            w = s.error_width,
            sa = s
                .error_samples
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(","),
            f = s.error_frames,
            r = s.error_repeat,
        ),
        table: Table {
            header: vec![
                "<scene",
                "<method",
                "samples",
                "frames",
                "µs per frame",
                "mean abs error",
                "wrong dominant",
                "time / complex",
            ],
            rows,
        },
        plots,
    })
}

/// The environment variable naming a `vcx` built with `--features naive-f64`, run as a
/// subprocess for the naive columns of the stability section.
const NAIVE_ENV: &str = "VCX_FIGURES_NAIVE";

/// The naive run of one family: `vcx bench stability --json` of the binary `bin`.
fn naive_records(
    bin: &Path,
    family: Family,
    cfg: &stability::Config,
) -> Result<Vec<stability::Record>, Failure> {
    let scales: Vec<String> = SCALES.iter().map(|e| e.to_string()).collect();
    let out = std::process::Command::new(bin)
        .args(["bench", "stability", "--json", "--families", family.name()])
        .arg(format!("--scales={}", scales.join(",")))
        .args(["--instances", &cfg.instances.to_string()])
        .args(["--objects", &cfg.objects.to_string()])
        .args(["--views", &cfg.views.to_string()])
        .args(["--repeat", &cfg.repeat.to_string()])
        .args(["--seed", &cfg.seed.to_string()])
        .output()
        .map_err(|e| Failure::bad_input(format!("{NAIVE_ENV}={}: {e}", bin.display())))?;
    if !out.status.success() {
        return Err(Failure::bad_input(format!(
            "{NAIVE_ENV}={}: {}",
            bin.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    let records = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(serde_json::from_str::<stability::Record>)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| Failure::bad_input(format!("{NAIVE_ENV}={}: {e}", bin.display())))?;
    if let Some(r) = records.iter().find(|r| r.variant != "naive-f64") {
        return Err(Failure::bad_input(format!(
            "{NAIVE_ENV}={}: a {} binary, expected naive-f64",
            bin.display(),
            r.variant
        )));
    }
    Ok(records)
}

fn fig_stability(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    let cfg = stability::Config {
        instances: s.stability_instances,
        objects: s.stability_objects,
        views: s.stability_views,
        repeat: s.stability_repeat,
        seed: SEED,
    };
    let variant = stability::variant();
    // The naive columns need a second binary; only an exact one can judge it.
    let naive = std::env::var_os(NAIVE_ENV)
        .filter(|v| !v.is_empty() && variant == "exact")
        .map(PathBuf::from);
    p.start(Family::ALL.len() * SCALES.len());
    let mut rows = Vec::new();
    let (mut build, mut walk) = (Vec::new(), Vec::new());
    let mut differ = Vec::new();
    for f in Family::ALL {
        let records = stability::measure_all(
            &[f],
            &SCALES,
            &cfg,
            |f, e| p.step(&format!("{} 2^{e}", f.name())),
            |_| Ok(()),
        )?;
        let joined = match &naive {
            Some(bin) => Some(stability::join(&records, &naive_records(bin, f, &cfg)?)?),
            None => None,
        };
        let t = stability::tally(&records);
        let per = |v: f64, k: usize| v / k.max(1) as f64;
        let (mut b, mut w) = (Vec::new(), Vec::new());
        for &e in &SCALES {
            let at = stability::tally(records.iter().filter(|r| r.scale == e));
            b.push((f64::from(e), 1e3 * per(at.build_s, at.instances)));
            w.push((f64::from(e), 1e3 * per(at.walk_s, at.instances)));
        }
        build.push(series(f.name(), b));
        walk.push(series(f.name(), w));
        let mut row = vec![
            f.name().to_string(),
            SCALES.len().to_string(),
            t.instances.to_string(),
            if t.failing.is_empty() {
                "0".to_string()
            } else {
                format!("{} ({})", t.failing.len(), t.failing.join(", "))
            },
            t.views.to_string(),
            t.views_failing.to_string(),
            format!("{:.3}", 1e3 * per(t.build_s, t.instances)),
            format!("{:.3}", 1e3 * per(t.walk_s, t.instances)),
        ];
        match &joined {
            Some(j) => {
                if let Some((_, r)) = j.by_family.first() {
                    // family, scales, instances, then the naive columns.
                    row.extend(r.cells("", "").into_iter().skip(3));
                }
                differ.push(series(
                    f.name(),
                    j.rows
                        .iter()
                        .map(|((_, e), r)| {
                            let share = r.views_differ as f64 / r.views.max(1) as f64;
                            (f64::from(*e), 100.0 * share)
                        })
                        .collect(),
                ));
            }
            None => row.extend(["—"; 5].map(String::from)),
        }
        rows.push(row);
    }
    let (fails, views_fail) = if variant == "exact" {
        ("exact builds failing", "exact views failing")
    } else {
        ("naive builds failing", "naive views failing")
    };
    let naive_note = match &naive {
        Some(bin) => format!(
            "Naive columns: the same scenes run by `{} bench stability --json` (`{NAIVE_ENV}`), \
             per family right after the exact run, joined as by `vcx bench stability \
             --compare`: naive builds that fail (scene rejected, sweep error, `validate()` \
             failed, panic), naive views that differ from the exact build's view of the same \
             instance, exact failures (must be 0), and the time ratios exact/naive summed where \
             both built.",
            bin.display()
        ),
        None => format!(
            "The naive-`f64` columns are empty (—): the predicates are fixed at compile time \
             (`vcx::geom::NAIVE_F64`), so this binary runs only the {variant} variant. To fill \
             them, build the naive binary and name it in `{NAIVE_ENV}`: `cargo build --release \
             -p vcx-demo --features naive-f64 --target-dir /tmp/target-naive` then \
             `{NAIVE_ENV}=/tmp/target-naive/release/vcx vcx bench figures` (same options); or \
             join two runs of `vcx bench stability --json` with `vcx bench stability --compare \
             EXACT.json NAIVE.json` (BENCHMARKS.md, \"Numerical stability\")."
        ),
    };
    let mut plots = vec![
        Plot {
            file: "stability_build_time.svg".into(),
            title: format!("Stress families: construction time against scale ({variant})"),
            x_label: "scale e (max |coordinate| = 2^e)",
            y_label: "ms per build",
            log_x: false,
            log_y: true,
            series: build,
        },
        Plot {
            file: "stability_walk_time.svg".into(),
            title: format!(
                "Stress families: time of {} views against scale ({variant})",
                s.stability_views
            ),
            x_label: "scale e (max |coordinate| = 2^e)",
            y_label: "ms per instance",
            log_x: false,
            log_y: true,
            series: walk,
        },
    ];
    if naive.is_some() {
        plots.push(Plot {
            file: "stability_naive_views.svg".into(),
            title: "Naive f64: views differing from the exact ones against scale".into(),
            x_label: "scale e (max |coordinate| = 2^e)",
            y_label: "% of views",
            log_x: false,
            log_y: false,
            series: differ,
        });
    }
    Ok(Output {
        caption: format!(
            "The measurement of `vcx bench stability --instances {i} --objects {o} --views {v} \
             --repeat {r} --seed {SEED}` (`std-demo/src/cmd/stability.rs`; section \"Numerical \
             stability\"), {variant} predicates: per family of near-degenerate scenes \
             (`std-demo/src/stress.rs`) and each of the {k} scales 2^e, e = {scales} (the largest \
             coordinate in scene units), {i} instances of {o} objects: build the complex by the \
             sweep, `validate()` it and walk the full view from {v} viewpoints each. Builds \
             failing: scene rejected, sweep error, failed validation or panic; views failing: \
             a walk's error or panic. Times: best of {r} runs, per instance, averaged over the \
             scales. The exact build is checked against the big-rational reference by \
             `tests/tests/stability.rs`. {naive_note}",
            i = s.stability_instances,
            o = s.stability_objects,
            v = s.stability_views,
            r = s.stability_repeat,
            k = SCALES.len(),
            scales = SCALES
                .iter()
                .map(|e| e.to_string())
                .collect::<Vec<_>>()
                .join(", "),
        ),
        table: Table {
            header: vec![
                "<family",
                "scales",
                "instances",
                fails,
                "views",
                views_fail,
                "build ms per instance",
                "walk ms per instance",
                "naive builds failing",
                "naive views differing from exact",
                "exact failures",
                "build time exact/naive",
                "walk time exact/naive",
            ],
            rows,
        },
        plots,
    })
}

// ---------------------------------------------------------------------------------------
// Output: tables, plots, the machine.

fn series(label: &str, points: Vec<(f64, f64)>) -> Series {
    Series {
        label: label.to_string(),
        points,
    }
}

/// `1234567` → `1,234,567`.
fn thousands(v: usize) -> String {
    let digits = v.to_string();
    let mut out = String::new();
    for (i, ch) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(ch);
    }
    out
}

fn markdown_table(t: &Table) -> String {
    let mut s = String::from("|");
    for h in &t.header {
        let _ = write!(s, " {} |", h.trim_start_matches('<'));
    }
    s.push_str("\n|");
    for h in &t.header {
        s.push_str(if h.starts_with('<') { "---|" } else { "---:|" });
    }
    s.push('\n');
    for row in &t.rows {
        s.push('|');
        for cell in row {
            let _ = write!(s, " {cell} |");
        }
        s.push('\n');
    }
    s
}

/// The range of the finite values (positive ones on a log axis), widened a little.
fn axis(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return if log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        (lo / 1.5, hi * 1.5)
    } else {
        let pad = ((hi - lo) * 0.05).max(hi.abs() * 0.05).max(1e-9);
        (
            (lo - pad).min(if lo >= 0.0 { 0.0 } else { lo - pad }),
            hi + pad,
        )
    }
}

/// A tick label: `16`, `2.5`, `0.004`, `2e6`.
fn short(v: f64) -> String {
    let a = v.abs();
    if a >= 1e6 {
        format!("{v:.0e}")
    } else if a >= 100.0 || v == v.round() {
        format!("{v:.0}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// The legend goes where the first curve is not: upper left if it rises, else upper right.
fn legend_position(plot: &Plot) -> SeriesLabelPosition {
    let first = plot
        .series
        .first()
        .map(|s| s.points.as_slice())
        .unwrap_or(&[]);
    match (first.first(), first.last()) {
        (Some(a), Some(b)) if b.1 < a.1 => SeriesLabelPosition::UpperRight,
        _ => SeriesLabelPosition::UpperLeft,
    }
}

fn render_svg(plot: &Plot) -> Result<String, String> {
    let xs = axis(
        plot.series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0)),
        plot.log_x,
    );
    let ys = axis(
        plot.series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1)),
        plot.log_y,
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 460)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (x, y) = (xs.0..xs.1, ys.0..ys.1);
        match (plot.log_x, plot.log_y) {
            (true, true) => draw(&root, plot, x.log_scale(), y.log_scale()),
            (true, false) => draw(&root, plot, x.log_scale(), y),
            (false, true) => draw(&root, plot, x, y.log_scale()),
            (false, false) => draw(&root, plot, x, y),
        }?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

fn draw<X, Y>(
    root: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    plot: &Plot,
    x: X,
    y: Y,
) -> Result<(), String>
where
    X: plotters::coord::ranged1d::AsRangedCoord<Value = f64>,
    Y: plotters::coord::ranged1d::AsRangedCoord<Value = f64>,
    X::CoordDescType: plotters::coord::ranged1d::ValueFormatter<f64>,
    Y::CoordDescType: plotters::coord::ranged1d::ValueFormatter<f64>,
{
    let e = |e: DrawingAreaErrorKind<_>| e.to_string();
    let mut chart = ChartBuilder::on(root)
        .caption(&plot.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x, y)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(plot.x_label)
        .y_desc(plot.y_label)
        .x_label_formatter(&|v| short(*v))
        .y_label_formatter(&|v| short(*v))
        .draw()
        .map_err(e)?;
    for (i, s) in plot.series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|&(x, y)| {
                x.is_finite()
                    && y.is_finite()
                    && (!plot.log_x || x > 0.0)
                    && (!plot.log_y || y > 0.0)
            })
            .collect();
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
            .map_err(e)?
            .label(s.label.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(PointSeries::of_element(
                pts.iter().copied(),
                4,
                color.filled(),
                &|c, s, st| Circle::new(c, s, st),
            ))
            .map_err(e)?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(legend_position(plot))
        .draw()
        .map_err(e)?;
    Ok(())
}

fn read_trimmed(path: &str) -> Option<String> {
    std::fs::read_to_string(path)
        .ok()
        .map(|s| s.trim().to_string())
}

/// CPU model, logical cores, memory and the compiler, from /proc and `rustc --version`.
fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = cpu
        .lines()
        .find(|l| l.starts_with("model name"))
        .and_then(|l| l.split(':').nth(1))
        .map_or("unknown CPU".to_string(), |m| m.trim().to_string());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mem = std::fs::read_to_string("/proc/meminfo")
        .unwrap_or_default()
        .lines()
        .find(|l| l.starts_with("MemTotal:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|kb| kb.parse::<f64>().ok())
        .map_or("unknown memory".to_string(), |kb| {
            format!("{:.1} GiB", kb / 1024.0 / 1024.0)
        });
    let rustc = std::process::Command::new("rustc")
        .arg("--version")
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "rustc not found".to_string());
    let profile = if cfg!(debug_assertions) {
        "debug build"
    } else {
        "release build"
    };
    format!("{model}, {cores} logical cores, {mem} memory; {rustc}; {profile}")
}

fn command_line() -> String {
    let args: Vec<String> = std::env::args().collect();
    let mut s = String::from("vcx");
    for a in args.iter().skip(1) {
        s.push(' ');
        s.push_str(a);
    }
    if std::env::var("VCX_FIGURES_TINY").is_ok_and(|v| v == "1") {
        s = format!("VCX_FIGURES_TINY=1 {s}");
    }
    s
}

/// The current UTC date and time, `YYYY-MM-DD HH:MM UTC` (civil from days, proleptic
/// Gregorian calendar).
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        rem / 3600,
        (rem % 3600) / 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kd_screens_are_valid_and_disjoint_with_the_grid() {
        for cells in [1, 2, 3, 4, 5, 12] {
            let all = kd_screens(cells, usize::MAX);
            // A full kd-tree down to single cells: one split per extra region.
            assert_eq!(all.len(), (cells * cells - 1) as usize, "cells={cells}");
            let file = screen_scene(cells, usize::MAX).expect("valid scene");
            assert_eq!(
                file.scene.as_ref().len(),
                all.len() + (cells * cells) as usize
            );
        }
        assert_eq!(kd_screens(12, 7).len(), 7);
    }

    #[test]
    fn thousands_and_dates() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1000), "1,000");
        assert_eq!(thousands(1_234_567), "1,234,567");
        assert!(utc_now().ends_with(" UTC"));
    }
}
