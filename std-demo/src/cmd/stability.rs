//! `vcx bench stability [--quick] [--json] [--seed S]`: the numerical-stability stress test
//! (issue 6, item 4). For every family of near-degenerate scenes ([`vcx_demo::stress`])
//! and every scale from the finest grid unit to the top of the coordinate range: build the
//! complex by the sweep, `validate()` it, and walk the full view from each of the family's
//! viewpoints; record builds that fail (scene rejected, error, failed validation, panic —
//! panics are caught and reported, never abort the run), views that fail, a fingerprint
//! of every view, and the times (best of `--repeat` runs).
//!
//! Which predicates decide is fixed at compile time (`vcx::geom::NAIVE_F64`): the default
//! build is exact; `--features naive-f64` rounds every predicate's leading determinant in
//! `f64`. Run both binaries with `--json` on the same arguments (they generate the same
//! scenes: the generators use no predicate) and join them with
//! `vcx bench stability --compare EXACT.json NAIVE.json`: per family and scale, the share of
//! naive builds that fail, the share of naive views that differ from the exact ones, the
//! exact failures (must be 0) and the time ratios exact/naive of construction and walks.
//!
//! The judge of the naive views is the exact build. The exact build itself has no judge
//! here: `tests/tests/stability.rs` checks it against the big-rational reference
//! (`tests/src/reference/view.rs`) on every family and scale at a small size.
//!
//! The measurement is [`measure_all`] (one [`Record`] per instance), shared with the
//! "stability" section of `vcx bench figures`; [`join`] is the comparison's arithmetic.

use core::panic::AssertUnwindSafe;
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::panic::catch_unwind;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

use serde::{Deserialize, Serialize};
use vcx::partition::build_by_sweep;
use vcx::walk::{view, ViewInterval};
use vcx_demo::stress::{self, Family, Fnv, StressScene, SCALES};

use super::{write_stdout, Failure};

/// Arguments of `vcx bench stability`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Smaller scenes, fewer instances, one repetition (for CI smoke use).
    #[arg(long)]
    pub quick: bool,
    /// One JSON object per instance (for `--compare`) instead of the summary table.
    #[arg(long)]
    pub json: bool,
    /// Seed of the scene generators.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Join the JSON output of an exact and of a naive run into the comparison table.
    #[arg(long, num_args = 2, value_names = ["EXACT", "NAIVE"])]
    pub compare: Option<Vec<PathBuf>>,
    /// Instances per family and scale (default 10; quick 2).
    #[arg(long)]
    pub instances: Option<u64>,
    /// Objects per scene (default 40; quick 12).
    #[arg(long)]
    pub objects: Option<usize>,
    /// Viewpoints per scene (default 24; quick 8).
    #[arg(long)]
    pub views: Option<usize>,
    /// Timed runs per build and per set of views; the best is kept (default 5; quick 1).
    #[arg(long)]
    pub repeat: Option<u32>,
    /// Only these families (comma-separated names).
    #[arg(long, value_delimiter = ',')]
    pub families: Vec<String>,
    /// Only these scales (comma-separated exponents, −8 to 14).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub scales: Vec<i32>,
}

/// The result of one instance on one binary: one JSON line of `--json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Record {
    /// `exact` or `naive-f64`.
    pub variant: String,
    /// Family name.
    pub family: String,
    /// Scale exponent.
    pub scale: i32,
    /// Instance number within the family and scale.
    pub instance: u64,
    /// Generator seed.
    pub seed: u64,
    /// Objects in the scene.
    pub objects: usize,
    /// The scene's fingerprint (both runs must agree).
    pub fingerprint: String,
    /// `ok`, `scene` (rejected by validation), `error` (the build returned an error),
    /// `invalid` (built, but `validate()` failed) or `panic`.
    pub build: String,
    /// The message of a failed build.
    pub why: Option<String>,
    /// Best build seconds (`None` if the build did not return a complex).
    pub build_s: Option<f64>,
    /// Cylinders of the complex.
    pub cylinders: Option<usize>,
    /// Per viewpoint: the view's fingerprint and interval count, `error: …` or `panic: …`;
    /// empty if there is no complex to walk.
    pub views: Vec<String>,
    /// Best seconds for all the views (`None` if a walk panicked or nothing was walked).
    pub walk_s: Option<f64>,
}

/// The last panic message, recorded by the hook installed during the run.
static LAST_PANIC: Mutex<String> = Mutex::new(String::new());

/// Runs `f`, turning a panic into `Err(message)`.
fn guarded<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|_| {
        LAST_PANIC
            .lock()
            .map(|m| m.clone())
            .unwrap_or_else(|_| "panic".to_string())
    })
}

/// Runs the stress test, or the comparison.
pub fn run(a: &Args) -> Result<(), Failure> {
    if let Some(files) = &a.compare {
        return match files.as_slice() {
            [exact, naive] => compare(exact, naive),
            _ => Err(Failure::bad_input("--compare takes two files")),
        };
    }
    let families: Vec<Family> = if a.families.is_empty() {
        Family::ALL.to_vec()
    } else {
        a.families
            .iter()
            .map(|n| {
                Family::from_name(n).ok_or_else(|| {
                    Failure::bad_input(format!(
                        "unknown family {n:?} (one of {})",
                        Family::ALL.map(Family::name).join(", ")
                    ))
                })
            })
            .collect::<Result<_, _>>()?
    };
    let scales: Vec<i32> = if a.scales.is_empty() {
        SCALES.to_vec()
    } else {
        a.scales.clone()
    };
    let base = Config::new(a.quick, a.seed);
    let cfg = Config {
        instances: a.instances.unwrap_or(base.instances),
        objects: a.objects.unwrap_or(base.objects),
        views: a.views.unwrap_or(base.views),
        repeat: a.repeat.unwrap_or(base.repeat).max(1),
        seed: a.seed,
    };
    let progress = std::io::stderr().is_terminal();
    let result = measure_all(
        &families,
        &scales,
        &cfg,
        |f, e| {
            if progress {
                eprint!("\r{} scale {e:>3}    ", f.name());
            }
        },
        |r| {
            if a.json {
                let line =
                    serde_json::to_string(r).map_err(|e| Failure::bad_input(e.to_string()))?;
                write_stdout(&format!("{line}\n"))?;
            }
            Ok(())
        },
    );
    if progress {
        eprintln!();
    }
    let records = result?;
    if a.json {
        return Ok(());
    }
    write_stdout(&summary(&records))
}

/// Sizes of a run.
pub(crate) struct Config {
    /// Instances per family and scale.
    pub instances: u64,
    /// Objects per scene.
    pub objects: usize,
    /// Viewpoints per scene.
    pub views: usize,
    /// Timed runs per build and per set of views (the best is kept), at least 1.
    pub repeat: u32,
    /// Seed of the scene generators.
    pub seed: u64,
}

impl Config {
    /// The defaults of `vcx bench stability` (`--quick`: smaller).
    pub(crate) fn new(quick: bool, seed: u64) -> Config {
        let (instances, objects, views, repeat) = if quick {
            (2, 12, 8, 1)
        } else {
            (10, 40, 24, 5)
        };
        Config {
            instances,
            objects,
            views,
            repeat,
            seed,
        }
    }
}

/// Generates and measures every instance of `families` × `scales`, in that order: calls
/// `at` before each family and scale and `each` on each record as it is measured (an error
/// of `each` stops the run). Panics are caught and recorded; the panic hook is restored
/// before returning.
pub(crate) fn measure_all(
    families: &[Family],
    scales: &[i32],
    cfg: &Config,
    mut at: impl FnMut(Family, i32),
    mut each: impl FnMut(&Record) -> Result<(), Failure>,
) -> Result<Vec<Record>, Failure> {
    // Panics are results here: record them quietly instead of the one-line exit.
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(|info| {
        if let Ok(mut m) = LAST_PANIC.lock() {
            *m = super::panic_message(info);
        }
    }));
    let mut records = Vec::new();
    let mut result = Ok(());
    'all: for &f in families {
        for &e in scales {
            at(f, e);
            for i in 0..cfg.instances {
                let s = match stress::generate(f, e, cfg.objects, cfg.views, cfg.seed, i) {
                    Ok(s) => s,
                    Err(err) => {
                        result = Err(Failure::bad_input(err.to_string()));
                        break 'all;
                    }
                };
                let r = measure(&s, i, cfg);
                if let Err(e) = each(&r) {
                    result = Err(e);
                    break 'all;
                }
                records.push(r);
            }
        }
    }
    std::panic::set_hook(previous);
    result.map(|()| records)
}

/// `exact` or `naive-f64`: the predicates this binary was built with.
pub(crate) fn variant() -> &'static str {
    if vcx::geom::NAIVE_F64 {
        "naive-f64"
    } else {
        "exact"
    }
}

/// Builds, validates and walks one instance.
fn measure(s: &StressScene, instance: u64, cfg: &Config) -> Record {
    let mut r = Record {
        variant: variant().to_string(),
        family: s.family.name().to_string(),
        scale: s.scale,
        instance,
        seed: cfg.seed,
        objects: s.polygons.len(),
        fingerprint: format!("{:016x}", s.fingerprint()),
        build: "ok".to_string(),
        why: None,
        build_s: None,
        cylinders: None,
        views: Vec::new(),
        walk_s: None,
    };
    let fail = |r: &mut Record, kind: &str, why: String| {
        r.build = kind.to_string();
        r.why = Some(super::one_line(&why));
    };
    let scene = match guarded(|| s.scene()) {
        Ok(Ok(scene)) => scene,
        Ok(Err(e)) => {
            fail(&mut r, "scene", e.to_string());
            return r;
        }
        Err(p) => {
            fail(&mut r, "panic", format!("scene validation: {p}"));
            return r;
        }
    };
    let sr = scene.as_ref();

    // Construction: best of `repeat`; the first run's complex is kept.
    let mut complex = None;
    let mut best = f64::INFINITY;
    for _ in 0..cfg.repeat {
        let t = Instant::now();
        let built = guarded(|| build_by_sweep(&sr));
        let dt = t.elapsed().as_secs_f64();
        match built {
            Ok(Ok(c)) => {
                best = best.min(dt);
                if complex.is_none() {
                    complex = Some(c);
                }
            }
            Ok(Err(e)) => {
                fail(&mut r, "error", e.to_string());
                return r;
            }
            Err(p) => {
                fail(&mut r, "panic", format!("build: {p}"));
                return r;
            }
        }
    }
    let Some(complex) = complex else {
        return r;
    };
    r.build_s = Some(best);
    r.cylinders = Some(complex.cylinders().len());
    match guarded(|| complex.validate(&sr)) {
        Ok(Ok(())) => {}
        Ok(Err(e)) => fail(&mut r, "invalid", e.to_string()),
        Err(p) => fail(&mut r, "invalid", format!("validate panicked: {p}")),
    }

    // Walks: every viewpoint, `repeat` times; the first pass records the views.
    let mut best = f64::INFINITY;
    let mut panicked = false;
    for pass in 0..cfg.repeat {
        let t = Instant::now();
        for &q in &s.viewpoints {
            let got = guarded(|| view(&complex, &sr, q));
            if pass == 0 {
                r.views.push(match got {
                    Ok(Ok(v)) => view_key(&v),
                    Ok(Err(e)) => format!("error: {}", super::one_line(&e.to_string())),
                    Err(p) => {
                        panicked = true;
                        format!("panic: {p}")
                    }
                });
            }
        }
        best = best.min(t.elapsed().as_secs_f64());
        if panicked {
            break;
        }
    }
    if !panicked && !s.viewpoints.is_empty() {
        r.walk_s = Some(best);
    }
    r
}

fn gcd(a: u128, b: u128) -> u128 {
    let (mut a, mut b) = (a, b);
    // Euclid: the remainder at least halves every two steps, so ≤ 256 steps for u128.
    for _ in 0..512 {
        if b == 0 {
            break;
        }
        (a, b) = (b, a % b);
    }
    a
}

/// A view's fingerprint: objects, boundary directions (primitive vectors) and boundary
/// vertices of every interval, FNV-1a, with the interval count.
fn view_key(v: &[ViewInterval]) -> String {
    let mut h = Fnv::new();
    for i in v {
        let object = i.object.map_or(u32::MAX, |o| o.0);
        h.write(&object.to_le_bytes());
        let (x, y) = i.start.vector();
        let g = gcd(x.unsigned_abs(), y.unsigned_abs()).max(1) as i128;
        h.write(&(x / g).to_le_bytes());
        h.write(&(y / g).to_le_bytes());
        let vertex = i.start_vertex.map_or(u64::MAX, |k| k as u64);
        h.write(&vertex.to_le_bytes());
    }
    format!("{:016x}:{}", h.finish(), v.len())
}

/// Whether a view key of [`Record::views`] is a view (not `error: …` or `panic: …`).
pub(crate) fn is_view(key: &str) -> bool {
    !key.starts_with("error") && !key.starts_with("panic")
}

/// Per family and scale, in the order of the run.
fn groups(records: &[Record]) -> Vec<((String, i32), Vec<&Record>)> {
    let mut order: Vec<(String, i32)> = Vec::new();
    let mut map: BTreeMap<(String, i32), Vec<&Record>> = BTreeMap::new();
    for r in records {
        let k = (r.family.clone(), r.scale);
        if !map.contains_key(&k) {
            order.push(k.clone());
        }
        map.entry(k).or_default().push(r);
    }
    order
        .into_iter()
        .map(|k| {
            let v = map.remove(&k).unwrap_or_default();
            (k, v)
        })
        .collect()
}

/// Totals of one run over some records (no judge: see the module documentation).
#[derive(Default)]
pub(crate) struct Tally {
    /// Instances.
    pub instances: usize,
    /// The [`Record::build`] of every failed build, in order.
    pub failing: Vec<String>,
    /// Views walked.
    pub views: usize,
    /// Views that failed (an error or a panic).
    pub views_failing: usize,
    /// Summed best build seconds.
    pub build_s: f64,
    /// Summed best walk seconds.
    pub walk_s: f64,
}

/// Adds up `records`.
pub(crate) fn tally<'a>(records: impl IntoIterator<Item = &'a Record>) -> Tally {
    let mut t = Tally::default();
    for r in records {
        t.instances += 1;
        if r.build != "ok" {
            t.failing.push(r.build.clone());
        }
        t.views += r.views.len();
        t.views_failing += r.views.iter().filter(|v| !is_view(v)).count();
        t.build_s += r.build_s.unwrap_or(0.0);
        t.walk_s += r.walk_s.unwrap_or(0.0);
    }
    t
}

/// The table of one run (no judge: see the module documentation).
fn summary(records: &[Record]) -> String {
    let mut out = format!(
        "vcx bench stability: {} predicates (the exact build is checked against the \
         big-rational reference by tests/tests/stability.rs; join with --compare to judge \
         the naive build)\n\n\
         | family | scale | instances | builds failing | views | views failing | build ms | walk ms |\n\
         |---|---:|---:|---|---:|---:|---:|---:|\n",
        variant()
    );
    for ((family, scale), rs) in groups(records) {
        let t = tally(rs);
        let (views, bad) = (t.views, t.views_failing);
        let (build_ms, walk_ms) = (t.build_s * 1e3, t.walk_s * 1e3);
        out += &format!(
            "| {family} | 2^{scale} | {} | {} | {views} | {bad} | {build_ms:.2} | {walk_ms:.2} |\n",
            t.instances,
            if t.failing.is_empty() {
                "0".to_string()
            } else {
                format!("{} ({})", t.failing.len(), t.failing.join(", "))
            }
        );
    }
    out
}

fn read_records(path: &PathBuf) -> Result<Vec<Record>, Failure> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Failure::bad_input(format!("cannot read {}: {e}", path.display())))?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(n, l)| {
            serde_json::from_str(l)
                .map_err(|e| Failure::bad_input(format!("{}:{}: {e}", path.display(), n + 1)))
        })
        .collect()
}

/// Totals of one row of the comparison.
#[derive(Default)]
pub(crate) struct Row {
    /// Instances joined.
    pub instances: usize,
    /// Naive builds that failed.
    pub naive_build_fail: usize,
    /// Naive builds that failed, by [`Record::build`].
    pub naive_fail_kinds: BTreeMap<String, usize>,
    /// Exact views compared (where the naive build returned a complex).
    pub views: usize,
    /// Naive views differing from the exact ones.
    pub views_differ: usize,
    /// Exact builds and views that failed (must be 0).
    pub exact_fail: usize,
    /// Summed build seconds (exact, naive) where both built.
    pub build: (f64, f64),
    /// Summed walk seconds (exact, naive) where both walked.
    pub walk: (f64, f64),
}

impl Row {
    fn add(&mut self, e: &Record, n: &Record) {
        self.instances += 1;
        if e.build != "ok" {
            self.exact_fail += 1;
        }
        self.exact_fail += e.views.iter().filter(|v| !is_view(v)).count();
        if n.build != "ok" {
            self.naive_build_fail += 1;
            *self.naive_fail_kinds.entry(n.build.clone()).or_default() += 1;
        }
        // Views of naive builds that returned a complex (valid or not) against the exact ones.
        if !n.views.is_empty() {
            for (ev, nv) in e.views.iter().zip(&n.views) {
                if is_view(ev) {
                    self.views += 1;
                    if ev != nv {
                        self.views_differ += 1;
                    }
                }
            }
        }
        if let (Some(a), Some(b)) = (e.build_s, n.build_s) {
            self.build.0 += a;
            self.build.1 += b;
        }
        if let (Some(a), Some(b)) = (e.walk_s, n.walk_s) {
            self.walk.0 += a;
            self.walk.1 += b;
        }
    }

    fn merge(&mut self, o: &Row) {
        self.instances += o.instances;
        self.naive_build_fail += o.naive_build_fail;
        for (k, v) in &o.naive_fail_kinds {
            *self.naive_fail_kinds.entry(k.clone()).or_default() += v;
        }
        self.views += o.views;
        self.views_differ += o.views_differ;
        self.exact_fail += o.exact_fail;
        self.build.0 += o.build.0;
        self.build.1 += o.build.1;
        self.walk.0 += o.walk.0;
        self.walk.1 += o.walk.1;
    }

    fn line(&self, family: &str, scale: &str) -> String {
        format!("| {} |\n", self.cells(family, scale).join(" | "))
    }

    /// The cells of the comparison table's row.
    pub(crate) fn cells(&self, family: &str, scale: &str) -> Vec<String> {
        let pct = |a: usize, b: usize| {
            if b == 0 {
                "—".to_string()
            } else {
                format!("{:.1} % ({a}/{b})", 100.0 * a as f64 / b as f64)
            }
        };
        let ratio = |(a, b): (f64, f64)| {
            if b > 0.0 {
                format!("{:.2}", a / b)
            } else {
                "—".to_string()
            }
        };
        let kinds = if self.naive_fail_kinds.is_empty() {
            String::new()
        } else {
            let k: Vec<String> = self
                .naive_fail_kinds
                .iter()
                .map(|(k, v)| format!("{v} {k}"))
                .collect();
            format!(": {}", k.join(", "))
        };
        vec![
            family.to_string(),
            scale.to_string(),
            self.instances.to_string(),
            format!("{}{kinds}", pct(self.naive_build_fail, self.instances)),
            pct(self.views_differ, self.views),
            self.exact_fail.to_string(),
            ratio(self.build),
            ratio(self.walk),
        ]
    }
}

/// `--compare EXACT NAIVE`: the table of BENCHMARKS.md.
fn compare(exact: &PathBuf, naive: &PathBuf) -> Result<(), Failure> {
    let (er, nr) = (read_records(exact)?, read_records(naive)?);
    if let Some(r) = er.iter().find(|r| r.variant != "exact") {
        return Err(Failure::bad_input(format!(
            "{}: a {} record, expected exact",
            exact.display(),
            r.variant
        )));
    }
    if let Some(r) = nr.iter().find(|r| r.variant != "naive-f64") {
        return Err(Failure::bad_input(format!(
            "{}: a {} record, expected naive-f64",
            naive.display(),
            r.variant
        )));
    }
    let j = join(&er, &nr)?;
    let mut out = String::from(
        "| family | scale (max \\|coord\\|) | instances | naive builds failing | naive views differing from exact | exact failures | build time exact/naive | walk time exact/naive |\n\
         |---|---:|---:|---|---|---:|---:|---:|\n",
    );
    for ((family, scale), row) in &j.rows {
        out += &row.line(family, &format!("2^{scale}"));
    }
    out += "\nPer family, all scales:\n\n\
            | family | scales | instances | naive builds failing | naive views differing from exact | exact failures | build time exact/naive | walk time exact/naive |\n\
            |---|---:|---:|---|---|---:|---:|---:|\n";
    for (family, row) in &j.by_family {
        out += &row.line(family, "all");
    }
    out += &j.total.line("**all**", "all");
    if j.unmatched > 0 {
        out += &format!(
            "\n{} exact instances had no naive counterpart.\n",
            j.unmatched
        );
    }
    write_stdout(&out)
}

/// The comparison of an exact and a naive run.
pub(crate) struct Joined {
    /// Per family and scale, in the order of the exact run.
    pub rows: Vec<((String, i32), Row)>,
    /// Per family, all scales.
    pub by_family: Vec<(String, Row)>,
    /// Everything.
    pub total: Row,
    /// Exact instances without a naive counterpart.
    pub unmatched: usize,
}

/// Joins the records of an exact run `er` and a naive run `nr` by family, scale, instance
/// and seed (the scenes must be the same).
pub(crate) fn join(er: &[Record], nr: &[Record]) -> Result<Joined, Failure> {
    let key = |r: &Record| (r.family.clone(), r.scale, r.instance, r.seed);
    let naive_by_key: BTreeMap<_, &Record> = nr.iter().map(|r| (key(r), r)).collect();
    let mut rows: Vec<((String, i32), Row)> = Vec::new();
    let mut by_family: Vec<(String, Row)> = Vec::new();
    let mut total = Row::default();
    let mut unmatched = 0;
    for ((family, scale), rs) in groups(er) {
        let mut row = Row::default();
        for e in rs {
            let Some(n) = naive_by_key.get(&key(e)) else {
                unmatched += 1;
                continue;
            };
            if n.fingerprint != e.fingerprint {
                return Err(Failure::bad_input(format!(
                    "{} scale {} instance {}: the two runs generated different scenes",
                    e.family, e.scale, e.instance
                )));
            }
            row.add(e, n);
        }
        match by_family.iter_mut().find(|(f, _)| *f == family) {
            Some((_, r)) => r.merge(&row),
            None => {
                let mut r = Row::default();
                r.merge(&row);
                by_family.push((family.clone(), r));
            }
        }
        total.merge(&row);
        rows.push(((family, scale), row));
    }
    Ok(Joined {
        rows,
        by_family,
        total,
        unmatched,
    })
}
