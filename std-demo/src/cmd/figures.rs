//! `vcx bench figures [--quick] [--out DIR]`: every benchmark of the repository measured
//! on this machine in one run — `DIR/BENCHMARKS.md` (the whole document: header with the
//! date, machine, compiler, command line and load average, a table of the issues' targets,
//! then one section per measurement) and its plots in `DIR/figures/*.svg`. Run with
//! `--out .` at the repository root it regenerates the committed `BENCHMARKS.md` and
//! `figures/`. `--quick` runs every section at smaller sizes (under 2 minutes); the
//! environment variable `VCX_FIGURES_TINY=1` shrinks them further (for the CLI test).
//!
//! Every section is one [`Figure`] entry of [`FIGURES`]: a name, a title and a function that
//! measures, returning a caption, one table, notes computed from the measured data, plots
//! and the issues' targets it decides. Each measures in-process with the same functions as
//! the separate commands (named in its caption), so the two cannot drift apart:
//!
//! * construction (Figs. 9–10): `vcx bench build` ([`bench::time_build`]);
//! * views, ray trees and frames: `vcx bench views [--depth D] [--fov 90 --width 800]`
//!   ([`bench::measure_views`]), from a scene built by the sweep and from the bytes of
//!   `vcx build -o` loaded as a `.vcx` file (`sections.rs`);
//! * device format sizes: the bytes of `vcx build -o` ([`build::encode_vcx`]) described
//!   as by `vcx inspect --json` ([`inspect::describe`]);
//! * run time against error (issue 6, item 2): `vcx bench error` ([`bench_error::measure`])
//!   on the hall of mirrors and the mixed scene at depth 5 — the quadtree and BVH ray
//!   casters of Figs. 12–15 appear here, on those two scenes, not against depth or n;
//! * numerical stability (item 4): `vcx bench stability` ([`stability::measure_all`]). The
//!   naive-`f64` predicates are a compile-time choice: with `VCX_FIGURES_NAIVE=PATH` naming
//!   a `vcx` built with `--features naive-f64`, that binary is run per family on the same
//!   scenes and joined as by `vcx bench stability --compare`; without it those columns are
//!   left empty and the caption says how to fill them;
//! * the paper's other experiments (§7): Fig. 11 (frame rate along a trajectory), Figs.
//!   12–13 (hall of mirrors against depth), 14–15 (mixed scene against n), 16 (active set),
//!   17–19 (screens placed kd-tree fashion, inserted first).
//!
//! Files: this one (driver, header, the paper's figures), `figures/sections.rs` (views, ray
//! trees, frames, sizes), `figures/issue6.rs` (error, stability), `figures/output.rs`
//! (markdown, SVG, machine).
//!
//! A frame of Figs. 11–19 is the exact full 360° view (or ray tree) from a viewpoint of the
//! built-in circuit ([`vcx_demo::demo::trajectory::circuit`], room capped at 1/2 unit);
//! Fig. 11 also times it turned into 800 columns. Times use [`Instant`]; scenes and
//! insertion orders use fixed seeds, so everything but the times is the same on every run.

mod issue6;
mod output;
mod sections;

use issue6::{fig_error, fig_stability, ERROR_SCENES, NAIVE_ENV};
use output::{
    command_line, git_revision, machine, markdown_table, read_trimmed, render_svg, series,
    thousands, utc_now,
};

use core::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use vcx::geom::Point;
use vcx::partition::{BuildOptions, Complex};
use vcx::render::Camera;
use vcx::{Material, ObjectId, QueryPoint, SceneRef};
use vcx_demo::demo::World;
use vcx_demo::generate::{generate, SceneKind};
use vcx_demo::scene_file::{ObjectSpec, SceneFile};

use super::bench::{self, bytes, history_bytes, internal, time_build};
use super::{bench_error, build, inspect, stability};
use super::{write_stdout, Failure};

/// Arguments of `vcx bench figures`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Smaller sizes (every plot in under 2 minutes), for CI smoke use.
    #[arg(long)]
    pub quick: bool,
    /// Directory for `BENCHMARKS.md` and the plots in `figures/` (created if missing;
    /// `--out .` at the repository root regenerates the committed files).
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
}

/// One section of BENCHMARKS.md (a figure or group of figures sharing a table): measured
/// by `run`.
pub(crate) struct Figure {
    /// Short name, used in progress output.
    pub name: &'static str,
    /// Section title in the markdown.
    pub title: &'static str,
    /// Measures and returns the table and the plots.
    pub run: fn(&Sizes, &mut Progress) -> Result<Output, Failure>,
}

/// What a figure produces: one table, with a caption, notes and its plots.
#[derive(Default)]
pub(crate) struct Output {
    /// Says what was measured and how, and the commands that measure it alone (markdown).
    pub caption: String,
    /// The table.
    pub table: Table,
    /// Markdown after the table: what the numbers say, computed from them.
    pub notes: String,
    /// The plots, written as SVG files.
    pub plots: Vec<Plot>,
    /// The issues' targets this section decides.
    pub targets: Vec<Target>,
}

/// One target of an issue against what this run measured.
pub(crate) struct Target {
    /// What is measured (markdown).
    pub what: String,
    /// The target, e.g. `≤ 20 ms`.
    pub target: String,
    /// The measured value (markdown).
    pub measured: String,
    /// Met, not met, or not measured at this run's sizes.
    pub met: Option<bool>,
}

impl Target {
    /// `met` as the cell of the targets table.
    fn verdict(&self) -> &'static str {
        match self.met {
            Some(true) => "met",
            Some(false) => "**not met**",
            None => "not measured",
        }
    }
}

/// A markdown table.
#[derive(Default)]
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

/// Every section, in output order. Append entries here to add sections.
pub(crate) const FIGURES: &[Figure] = &[
    Figure {
        name: "construction",
        title: "Construction: the paper's grid scene (Figs. 9–10)",
        run: fig_construction,
    },
    Figure {
        name: "views",
        title: "Views: full 360° view from random free points",
        run: sections::views,
    },
    Figure {
        name: "ray-trees",
        title: "Ray trees: hall of mirrors and mixed scene (full circle)",
        run: sections::ray_trees,
    },
    Figure {
        name: "frames",
        title: "Frames: a field of view of 800 columns",
        run: sections::frames,
    },
    Figure {
        name: "sizes",
        title: "Device format sizes",
        run: sections::sizes,
    },
    Figure {
        name: "regions",
        title: "Device format sizes with a region of viewpoints (vcx build --region)",
        run: sections::regions,
    },
    Figure {
        name: "region-trees",
        title: "Regions where ray trees leave the box (vcx build --region, mirrors, refraction, screens)",
        run: sections::region_trees,
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
    /// Grid sizes of the views section.
    pub views_n: Vec<u32>,
    /// Random free viewpoints of `vcx bench views` (`--random`) in the views section.
    pub views_random: usize,
    /// Runs per viewpoint (`--repeat`, the best is kept) in the views section.
    pub views_repeat: u32,
    /// Deepest ray tree of the ray-trees section.
    pub tree_depth: usize,
    /// `--random` of the ray-trees and frames sections.
    pub tree_random: usize,
    /// `--repeat` of the ray-trees and frames sections.
    pub tree_repeat: u32,
    /// Grid size of the frames section.
    pub frames_grid_n: u32,
    /// Grid sizes of the device format sizes.
    pub sizes_n: Vec<u32>,
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
                views_n: vec![4, 16],
                views_random: 8,
                views_repeat: 1,
                tree_depth: 2,
                tree_random: 4,
                tree_repeat: 1,
                frames_grid_n: 16,
                sizes_n: vec![4, 16],
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
                // n = 1024 decides the view target (a few seconds more).
                views_n: vec![64, 256, 1024],
                views_random: 50,
                views_repeat: 3,
                tree_depth: 5,
                tree_random: 30,
                tree_repeat: 2,
                frames_grid_n: 1024,
                sizes_n: vec![64, 256, 1024],
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
                // The commands of the hand-kept BENCHMARKS.md this replaces.
                views_n: vec![64, 256, 1024],
                views_random: 200,
                views_repeat: 5,
                tree_depth: 8,
                tree_random: 100,
                tree_repeat: 3,
                frames_grid_n: 1024,
                sizes_n: vec![64, 256, 1024, 4096],
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

/// The plots' directory inside the output directory (links are relative to it).
const PLOT_DIR: &str = "figures";

/// Load average (1 min) above which the header warns that times are inflated.
const BUSY: f64 = 1.0;

/// Runs every section and writes `BENCHMARKS.md` and the plots.
pub fn run(a: &Args) -> Result<(), Failure> {
    let tiny = std::env::var("VCX_FIGURES_TINY").is_ok_and(|v| v == "1");
    let sizes = Sizes::new(a.quick, tiny);
    let plot_dir = a.out.join(PLOT_DIR);
    std::fs::create_dir_all(&plot_dir)
        .map_err(|e| Failure::bad_input(format!("cannot create {}: {e}", plot_dir.display())))?;
    let started = Instant::now();
    let date = utc_now();
    let load_before = load_average();
    // Before the run writes its plots (tracked files when `--out .`).
    let source = git_revision();
    let mut body = String::new();
    let mut targets = Vec::new();
    let mut progress = Progress::new();
    let mut plots = 0;
    for (k, fig) in FIGURES.iter().enumerate() {
        progress.prefix = format!("[{}/{}] {}", k + 1, FIGURES.len(), fig.name);
        progress.start(1);
        let t = Instant::now();
        let out = (fig.run)(&sizes, &mut progress)?;
        let secs = t.elapsed().as_secs_f64();
        progress.finish();
        let _ = writeln!(body, "## {}\n", fig.title);
        let _ = writeln!(body, "{}\n", out.caption.trim());
        body.push_str(&markdown_table(&out.table));
        body.push('\n');
        if !out.notes.trim().is_empty() {
            let _ = writeln!(body, "{}\n", out.notes.trim());
        }
        for plot in &out.plots {
            let svg = render_svg(plot).map_err(|e| internal(format!("{}: {e}", plot.file)))?;
            write_file(&plot_dir.join(&plot.file), &svg)?;
            plots += 1;
            let _ = writeln!(body, "![{}]({PLOT_DIR}/{})\n", plot.title, plot.file);
        }
        let _ = writeln!(body, "(Section measured in {secs:.2} s.)\n");
        targets.extend(out.targets);
    }
    let total = started.elapsed().as_secs_f64();
    let load_after = load_average();
    let md = header(&sizes, &date, source, total, load_before, load_after)
        + &targets_table(&targets)
        + &body;
    let path = a.out.join("BENCHMARKS.md");
    write_file(&path, &md)?;
    write_stdout(&format!(
        "wrote {} and {plots} plots in {}/ in {total:.1} s\n",
        path.display(),
        plot_dir.display()
    ))
}

/// The 1, 5 and 15 minute load averages (other work on the machine skews the times).
fn load_average() -> Option<[f64; 3]> {
    let l = read_trimmed("/proc/loadavg")?;
    let mut it = l.split_whitespace().map(|v| v.parse::<f64>().ok());
    Some([it.next()??, it.next()??, it.next()??])
}

/// The document's title and header: how it was made, where and under what load.
fn header(
    sizes: &Sizes,
    date: &str,
    source: Option<String>,
    total: f64,
    before: Option<[f64; 3]>,
    after: Option<[f64; 3]>,
) -> String {
    let mut md = String::from("# Benchmarks\n\n");
    let _ = writeln!(
        md,
        "Generated by `{}` ({} sizes) on {date}, in {} of wall time. Every number below was \
         measured by that run: do not edit this file by hand, re-run the command (at the \
         repository root with `--out .`, on an idle machine). `vcx` is `cargo run --release -p \
         vcx-demo --`; each section names the separate subcommand that measures its table \
         alone, with the same code. Scenes and insertion orders use fixed seeds, so sizes, \
         counts and intervals are the same on every run; only the times vary. Tests never \
         assert on time.\n",
        command_line(),
        sizes.label,
        duration(total),
    );
    md.push_str(
        "The committed file is made at the repository root by (the naive-`f64` binary fills \
         the naive columns of \"Numerical stability\"; `--quick` runs smaller sizes in under \
         2 minutes):\n\n```sh\ncargo build --release -p vcx-demo --features naive-f64 \
         --target-dir /tmp/target-naive\nVCX_FIGURES_NAIVE=/tmp/target-naive/release/vcx \
         cargo run --release -p vcx-demo -- bench figures --out .\n```\n\n",
    );
    let m = machine();
    let _ = writeln!(md, "| | |\n|---|---|");
    let _ = writeln!(md, "| date | {date} |");
    let _ = writeln!(md, "| CPU | {} |", m.cpu);
    let _ = writeln!(md, "| logical cores | {} |", m.cores);
    let _ = writeln!(md, "| memory | {} |", m.memory);
    let _ = writeln!(md, "| compiler | {} |", m.rustc);
    let _ = writeln!(md, "| build profile | {} |", m.profile);
    if let Some(rev) = source {
        let _ = writeln!(md, "| source | {rev} |");
    }
    let _ = writeln!(md, "| command | `{}` |", command_line());
    let fmt = |l: Option<[f64; 3]>| {
        l.map_or("unknown".to_string(), |[a, b, c]| {
            format!("{a:.2}, {b:.2}, {c:.2}")
        })
    };
    let _ = writeln!(
        md,
        "| load average (1, 5, 15 min) | at the start {}; at the end {} |",
        fmt(before),
        fmt(after)
    );
    let _ = writeln!(md, "| wall time | {} |\n", duration(total));
    let busy = [before, after]
        .iter()
        .flatten()
        .map(|l| l[0])
        .fold(f64::NAN, f64::max);
    if busy > BUSY {
        let _ = writeln!(
            md,
            "**Warning: the machine was busy** (1-minute load average up to {busy:.2}, above \
             {BUSY:.1}): other work competed for the cores, so the times below are slower \
             than on an idle machine, and ratios between rows measured at different moments \
             are noisy. Sizes, counts and intervals are not affected.\n"
        );
    }
    md
}

/// The issues' targets, collected from the sections.
fn targets_table(targets: &[Target]) -> String {
    let mut md = String::from("## Targets\n\n");
    md.push_str(
        "The targets of the issues (construction, walking, device format, issue 6) against \
         this run; each row is computed from the section named in it.\n\n",
    );
    md.push_str(&markdown_table(&Table {
        header: vec!["<what", "<target", "<measured", "<verdict"],
        rows: targets
            .iter()
            .map(|t| {
                vec![
                    t.what.clone(),
                    t.target.clone(),
                    t.measured.clone(),
                    t.verdict().to_string(),
                ]
            })
            .collect(),
    }));
    md.push('\n');
    md
}

/// `75.3 s`, `5 min 07 s`.
fn duration(secs: f64) -> String {
    if secs < 60.0 {
        format!("{secs:.1} s")
    } else {
        let s = secs.round() as u64;
        format!("{} min {:02} s", s / 60, s % 60)
    }
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

/// `vcx bench build`'s measurement, timed as the median of `repeat` runs (`compaction`:
/// of the randomized construction's history, §4.4).
fn build_median(
    scene: &SceneRef<'_>,
    ric: bool,
    first: &[ObjectId],
    repeat: usize,
    compaction: bool,
) -> Result<(f64, bench::Timed), Failure> {
    let options = BuildOptions {
        seed: SEED,
        first: first.to_vec(),
        compaction,
        ..Default::default()
    };
    let mut t = time_build(scene, ric, &options, repeat as u32)?;
    Ok((median(&mut t.times), t))
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
    p.start(3 * s.grid_n.len());
    let mut rows = Vec::new();
    let (mut cyl, mut nodes, mut cbytes, mut hbytes) = (vec![], vec![], vec![], vec![]);
    let (mut t_ric, mut t_sweep) = (vec![], vec![]);
    // Per n: the history with and without search path compaction.
    let mut saved = Vec::new();
    // Per n: seconds of both methods, live cylinders and the history's statistics.
    let mut measured = Vec::new();
    for &n in &s.grid_n {
        let file = generate(SceneKind::Grid, n, SEED).map_err(|e| internal(e.to_string()))?;
        let scene = file.scene.as_ref();
        p.step(&format!("grid n={n} ric"));
        let ric = build_median(&scene, true, &[], s.repeats(n), true)?;
        p.step(&format!("grid n={n} ric, no compaction"));
        let (u_s, u) = build_median(&scene, true, &[], s.repeats(n), false)?;
        if u.complex.cylinders() != ric.1.complex.cylinders() {
            return Err(internal("the uncompacted history's live partition differs"));
        }
        p.step(&format!("grid n={n} sweep"));
        let sweep = build_median(&scene, false, &[], s.repeats(n), true)?;
        let x = f64::from(n);
        for (method, (seconds, b)) in [("ric", &ric), ("sweep", &sweep)] {
            let c = &b.complex;
            let h = b.history;
            // Side by side, for the randomized construction: its history without compaction.
            let uh = u.history.filter(|_| h.is_some());
            rows.push(vec![
                n.to_string(),
                method.to_string(),
                s.repeats(n).to_string(),
                format!("{seconds:.4}"),
                thousands(c.cylinders().len()),
                thousands(c.vertices().len()),
                thousands(c.free_bitangents()),
                thousands(bytes(c)),
                h.map_or("—".into(), |h| thousands(h.nodes)),
                h.map_or("—".into(), |h| thousands(h.links)),
                h.map_or("—".into(), |h| h.depth.to_string()),
                h.map_or("—".into(), |h| thousands(history_bytes(&h))),
                uh.map_or("—".into(), |_| format!("{u_s:.4}")),
                uh.map_or("—".into(), |h| thousands(h.nodes)),
                uh.map_or("—".into(), |h| thousands(h.links)),
                uh.map_or("—".into(), |h| h.depth.to_string()),
                uh.map_or("—".into(), |h| thousands(history_bytes(&h))),
            ]);
        }
        if let (Some(c), Some(h)) = (ric.1.history, u.history) {
            saved.push((n, c, h));
        }
        let (ric_s, ric) = ric;
        cyl.push((x, ric.complex.cylinders().len() as f64));
        cbytes.push((x, bytes(&ric.complex) as f64));
        if let Some(h) = ric.history {
            nodes.push((x, h.nodes as f64));
            hbytes.push((x, history_bytes(&h) as f64));
        }
        t_ric.push((x, ric_s));
        t_sweep.push((x, sweep.0));
        measured.push((
            n,
            ric_s,
            sweep.0,
            ric.complex.cylinders().len(),
            ric.history,
        ));
    }
    // The construction issue's targets: n = 256 in 20 ms, n = 4096 in 1 s.
    let mut notes = Vec::new();
    let mut targets = Vec::new();
    for (n, limit) in [(256u32, 0.02), (4096, 1.0)] {
        let at = measured.iter().find(|m| m.0 == n);
        let what = format!("randomized construction, grid n = {n} (Construction)");
        let target = format!("≤ {}", seconds_text(limit));
        let Some(&(_, ric_s, sweep_s, ..)) = at else {
            targets.push(Target {
                what,
                target,
                measured: format!("n = {n} not in this run's sizes"),
                met: None,
            });
            continue;
        };
        let verdict = |t: f64| {
            if t <= limit {
                "met".to_string()
            } else {
                format!("{}× over", ratio_text(t / limit))
            }
        };
        notes.push(format!(
            "n = {n} in {}: the randomized construction takes {} ({}), the sweep {} ({})",
            target,
            seconds_text(ric_s),
            verdict(ric_s),
            seconds_text(sweep_s),
            verdict(sweep_s)
        ));
        targets.push(Target {
            what,
            target,
            measured: format!("{} (sweep: {})", seconds_text(ric_s), seconds_text(sweep_s)),
            met: Some(ric_s <= limit),
        });
    }
    let per_live: Vec<String> = measured
        .iter()
        .filter_map(|m| {
            let h = m.4?;
            Some(format!(
                "{:.1} (n = {})",
                h.nodes as f64 / m.3.max(1) as f64,
                m.0
            ))
        })
        .collect();
    let links: Vec<String> = measured
        .iter()
        .filter_map(|m| {
            m.4.map(|h| format!("{:.1}", h.links as f64 / h.nodes.max(1) as f64))
        })
        .collect();
    let depths: Vec<String> = measured
        .iter()
        .filter_map(|m| m.4.map(|h| h.depth.to_string()))
        .collect();
    let mut text = String::new();
    // Fig. 9 against n: cylinders per object at the smallest and the largest n.
    if let (Some(a), Some(b)) = (measured.first(), measured.last()) {
        let _ = write!(
            text,
            "The complex grows a little faster than n: {:.0} cylinders per object at n = {}, \
             {:.0} at n = {}. ",
            a.3 as f64 / f64::from(a.0.max(1)),
            a.0,
            b.3 as f64 / f64::from(b.0.max(1)),
            b.0
        );
    }
    if !notes.is_empty() {
        let _ = write!(
            text,
            "Against the targets of the construction issue: {}. ",
            notes.join("; ")
        );
    }
    let _ = write!(
        text,
        "History nodes per live cylinder: {}; links per node: {}; the history's depth grows \
         slowly ({} for n = {}). The paper needed about 3 minutes for n = 256 on a 200 MHz \
         Pentium.",
        per_live.join(", "),
        links.join(", "),
        depths.join(", "),
        s.grid_n
            .iter()
            .map(|n| n.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    // What search path compaction saves (§4.4).
    let saving: Vec<String> = saved
        .iter()
        .map(|(n, c, u)| {
            let less = |a: usize, b: usize| 100.0 * (1.0 - a as f64 / b.max(1) as f64);
            format!(
                "{:.0} % of the nodes, {:.0} % of the links, depth {} instead of {} (n = {n})",
                less(c.nodes, u.nodes),
                less(c.links, u.links),
                c.depth,
                u.depth
            )
        })
        .collect();
    if !saving.is_empty() {
        let _ = write!(
            text,
            " Search path compaction saves {} (§4.4 reports \"a small percentage\" for the \
             paper's own, finer uncompacted history).",
            saving.join("; ")
        );
    }
    Ok(Output {
        caption: format!(
            "Scene `vcx gen grid N --seed {SEED}`, insertion-order seed {SEED}. `ric`: randomized \
             incremental construction with history (§4); `sweep`: rotational sweep of the same \
             canonical partition, no history. Seconds: median of `runs` constructions (of the \
             construction alone). Bytes: cylinders + vertices of the complex in memory; history: \
             each node's cylinder record plus 4 bytes per link. By default the history links \
             every destroyed cylinder directly to its replacements: the paper's search path \
             compaction (§4.4). The columns \"no compaction\" are the same construction with \
             `BuildOptions::compaction` off (`vcx build --no-compaction`): each link from a \
             destroyed cylinder with several children to a new one with several parents goes \
             through a piece node (split, then merge) — coarser than the paper's edge-by-edge \
             process, so fewer nodes than the paper's uncompacted history; its seconds include \
             that pass. Alone: `vcx bench build --n {} --method both --seed {SEED} --repeat R` \
             (one JSON object per line, the uncompacted history in the `uncompacted_` keys; it \
             reports the best of R runs, this table the median).",
            s.grid_n
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(",")
        ),
        table: Table {
            header: vec![
                "n",
                "<method",
                "runs",
                "seconds",
                "cylinders",
                "complex vertices",
                "free bitangents",
                "complex bytes",
                "history nodes",
                "links",
                "depth",
                "history bytes",
                "seconds (no compaction)",
                "nodes (no compaction)",
                "links (no compaction)",
                "depth (no compaction)",
                "history bytes (no compaction)",
            ],
            rows,
        },
        notes: text,
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
        targets,
    })
}

/// First x, last x and last y over first y of a curve, if it has two points.
fn growth(points: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    match (points.first(), points.last()) {
        (Some(a), Some(b)) if points.len() > 1 => Some((a.0, b.0, b.1 / a.1)),
        _ => None,
    }
}

/// Figs. 17–19 against no screens: the smallest complex, history and build time, and the
/// frame rate with the most screens.
fn screens_notes(
    cyl: &[(f64, f64)],
    nodes: &[(f64, f64)],
    time: &[(f64, f64)],
    fps: &[(f64, f64)],
) -> String {
    // The point of least y, and how much less than the first point's y that is.
    let best = |v: &[(f64, f64)]| {
        let first = v.first()?;
        let min = v.iter().min_by(|a, b| a.1.total_cmp(&b.1))?;
        Some(format!(
            "{}× (at {:.0} screens)",
            ratio_text(first.1 / min.1),
            min.0
        ))
    };
    let (Some(c), Some(h), Some(t), Some(f)) = (best(cyl), best(nodes), best(time), growth(fps))
    else {
        return String::new();
    };
    format!(
        "Against no screens, screens placed first cut the complex by up to {c} and the history \
         by up to {h}, and make the construction up to {t} faster (Figs. 17–18); with {:.0} \
         screens the frame rate is {}× that without (Fig. 19: the frame walks through the \
         screens' cylinders).",
        f.1,
        ratio_text(f.2)
    )
}

/// `0.0219` → `21.9 ms`, `20.6` → `20.6 s`.
fn seconds_text(secs: f64) -> String {
    if secs < 1.0 {
        format!("{:.1} ms", secs * 1e3)
    } else {
        format!("{secs:.2} s")
    }
}

/// A ratio such as `14`, `1.7`, `0.62`.
fn ratio_text(x: f64) -> String {
    if x >= 10.0 {
        format!("{x:.0}")
    } else if x >= 1.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    }
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
             restriction, `walk::view_range`, would walk to its edge and over it). {} \
             passes; each frame's time is its median over the passes; frames/s = frames ÷ \
             summed times.",
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
        ..Default::default()
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
    let notes = match (growth(&time), growth(&intervals)) {
        (Some(t), Some(k)) => format!(
            "From depth {:.0} to {:.0} the time per frame grows {}× for {}× the intervals \
             (the paper's scene complexity): the time per interval {} with depth; the \
             primary walk's events do not change with depth.",
            t.0,
            t.1,
            ratio_text(t.2),
            ratio_text(k.2),
            if t.2 > k.2 { "grows" } else { "does not grow" }
        ),
        _ => String::new(),
    };
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
        notes,
        ..Default::default()
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
    let notes = match (growth(&fps), growth(&intervals)) {
        (Some(f), Some(k)) => format!(
            "From n = {:.0} to {:.0} the time per frame grows {}× for {}× the intervals \
             per frame.",
            f.0,
            f.1,
            ratio_text(1.0 / f.2),
            ratio_text(k.2)
        ),
        _ => String::new(),
    };
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
        notes,
        ..Default::default()
    })
}

fn fig_active_set(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(s.grid_n.len());
    let mut rows = Vec::new();
    let (mut steps, mut distinct, mut share) = (vec![], vec![], vec![]);
    let mut sizes = Vec::new();
    for &n in &s.grid_n {
        p.step(&format!("grid n={n}"));
        let w = world(SceneKind::Grid, n)?;
        let points = poses(&w, s.frames);
        let sub = w.sub();
        // One pass: only the walk statistics are used, not the times.
        let f = frames(&w.complex, &sub.as_ref(), &points, Walk::View, 1)?;
        let cylinders = w.complex.cylinders().len();
        sizes.push((f64::from(n), cylinders as f64));
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
    let notes = match (distinct.first(), distinct.last(), growth(&sizes)) {
        (Some(a), Some(b), Some(g)) => format!(
            "The active set stays small: {:.0} to {:.0} cylinders per frame (n = {:.0} … \
             {:.0}) while the complex grows {}×.",
            a.1,
            b.1,
            g.0,
            g.1,
            ratio_text(g.2)
        ),
        _ => String::new(),
    };
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
        notes,
        ..Default::default()
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
        let (seconds, b) = build_median(&scene, true, &first, s.repeat, true)?;
        let points = poses(&w, s.frames);
        let f = frames(&b.complex, &scene, &points, Walk::Tree(0), s.passes)?;
        let x = placed as f64;
        cyl.push((x, b.complex.cylinders().len() as f64));
        if let Some(h) = b.history {
            nodes.push((x, h.nodes as f64));
        }
        time.push((x, seconds));
        fps.push((x, 1.0 / f.seconds));
        let h = b.history;
        rows.push(vec![
            placed.to_string(),
            thousands(b.complex.cylinders().len()),
            thousands(b.complex.vertices().len()),
            thousands(bytes(&b.complex)),
            h.map_or("—".into(), |h| thousands(h.nodes)),
            h.map_or("—".into(), |h| thousands(history_bytes(&h))),
            format!("{seconds:.4}"),
            f.frames.to_string(),
            format!("{:.1}", f.seconds * 1e6),
            format!("{:.0}", 1.0 / f.seconds),
            format!("{:.1}", f.intervals),
        ]);
    }
    let notes = screens_notes(&cyl, &nodes, &time, &fps);
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
        notes,
        ..Default::default()
    })
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
