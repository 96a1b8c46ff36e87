//! `vcx build SCENE.json [-o OUT.vcx] [--seed N] [--no-compaction] [--stats-json]`: build
//! the visibility complex of a scene and report its size.
//!
//! The scene is loaded and validated as by `vcx check` (bad input: exit status 2). The
//! complex is then built with the rotational sweep ([`vcx::partition::build_by_sweep`]) and
//! checked with [`vcx::partition::Complex::validate`]. A failure of either is a bug in vcx,
//! not bad input: `error: SCENE: internal: …` and exit status 3 ([`EXIT_INTERNAL`]).
//!
//! Output, one line on stdout:
//!
//! * by default a summary for people: `SCENE: N objects, B free bitangents (V complex
//!   vertices), F faces, C cylinders; built in T s (rotational sweep, no history)`;
//! * with `--stats-json` exactly one JSON object, keys in this order:
//!   `objects`, `free_bitangents` (undirected free bitangent segments), `complex_vertices`
//!   (directed free bitangents, `2 × free_bitangents`), `faces`, `cylinders`
//!   (`3·objects + 1 + 3·complex_vertices`), `build_seconds` (wall time of the build alone,
//!   not of loading or validation), then `history_nodes`, `history_links`, `history_depth`
//!   — all `null` — and `history`, a string saying why: the sweep builds the canonical
//!   partition without the history DAG; the randomized incremental construction will fill
//!   these.
//!
//! With `-o FILE.vcx` the scene and complex are also written in the binary complex format
//! (`docs/format.md`; the header records `--seed` for the randomized construction) and the
//! summary ends with `; wrote FILE (B bytes)`, or `; wrote FILE (B bytes, history H
//! bytes)` (`--stats-json`: keys `file_bytes`, `file_history_bytes`, the latter `null`
//! without history). `--history` says whether the file stores the construction history
//! (the point-location structure of §4.2):
//!
//! * `auto` (default): when the scene has a mirror, a refractive object or a screen (for
//!   point location of rays leaving an object), unless `--method sweep` is given (the
//!   sweep builds no history);
//! * `always`: always (with `--method sweep`: an error, exit status 2);
//! * `never`: never (walks, primary and ray trees, do not read it).
//!
//! A history is written only with the randomized construction, whose live partition is the
//! file's complex.
//!
//! `--no-compaction`: build the history without search path compaction (§4.4;
//! [`vcx::partition::BuildOptions::compaction`]): an insertion's split and merge are
//! recorded as two steps, with a piece node between a destroyed cylinder and each new one
//! where the destroyed one has several children and the new one several parents. The live
//! partition (and so the complex) is the same; the summary and `--stats-json` report the
//! uncompacted history's nodes, links and depth (`--stats-json` adds the key
//! `"compaction": false`), and `-o` writes it with the header's compacted flag clear.
//! With `--method sweep` (no history) it is an error (exit status 2).
//!
//! The scene may itself be a `.vcx` file (its scene is rebuilt).
//!
//! `--region X0,Y0,X1,Y1` (scene units; a closed box): the viewpoints will stay in this
//! box, so only the cylinders a view or ray tree from it can enter are kept
//! ([`vcx::partition::Complex::prune_to_region`]; a conservative superset decided
//! exactly, see `core/src/partition/region.rs`). The summary ends with `; region
//! X0,Y0,X1,Y1: kept K of C cylinders` (`--stats-json`: `cylinders` is K, plus `region`
//! `[x0, y0, x1, y1]` and `full_cylinders` C), and `-o` writes format version 4 with the
//! region: the whole complex as version 3 stores it and a bit per cylinder, whether it is
//! kept (version 2, every kept cylinder stored, with `--explicit-cylinders`). Such a file has no history: `--history always` with `--region` is an error
//! (exit status 2), `auto` writes none. Behind mirrors, refractive objects and screens
//! every cylinder is kept: ray trees walk there from eyes outside the box.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::{json, Value};
use vcx::partition::{build_by_sweep, BuildOptions, Complex, History};
use vcx::SceneRef;

use super::{write_stdout, Failure};

/// Exit status when the complex cannot be built or fails its own checks (a bug in vcx).
pub const EXIT_INTERNAL: u8 = 3;

/// Why the history fields of `--stats-json` are `null`.
pub const HISTORY_NOT_BUILT: &str = "not built: the rotational sweep builds the canonical \
     partition without history (use --method ric)";

/// Whether `-o` stores the construction history.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum HistoryChoice {
    /// When the scene has mirrors, refractive objects or screens (a walk can need point
    /// location from a secondary ray).
    Auto,
    /// Always.
    Always,
    /// Never.
    Never,
}

/// How to build the complex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// Randomized incremental construction with history (§4 of the paper).
    Ric,
    /// Rotational sweep: the canonical partition without history.
    Sweep,
}

/// Arguments of `vcx build`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (JSON, or a binary complex file `.vcx`).
    pub scene: PathBuf,
    /// Print the statistics as one JSON object instead of a summary line.
    #[arg(long)]
    pub stats_json: bool,
    /// Seed of the random insertion order (same seed, same history).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Insert the screens first, then the other objects in random order (§7).
    #[arg(long)]
    pub screens_first: bool,
    /// Construction method [default: ric].
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Write the scene and complex to this binary complex file (`docs/format.md`).
    #[arg(short = 'o', long = "output", value_name = "FILE.vcx")]
    pub output: Option<PathBuf>,
    /// With `-o`: store the construction history in the file (`auto`: when the scene has
    /// mirrors, refractive objects or screens).
    #[arg(long, value_enum, default_value_t = HistoryChoice::Auto)]
    pub history: HistoryChoice,
    /// Keep only the cylinders views and ray trees from viewpoints in this box need
    /// (`X0,Y0,X1,Y1`, scene units; every cylinder behind a mirror, refractive object or
    /// screen is kept; no history).
    #[arg(long, value_name = "X0,Y0,X1,Y1", allow_hyphen_values = true)]
    pub region: Option<String>,
    /// With `-o`: store every cylinder (format version 1; with `--region` every kept one,
    /// version 2), for readers that predate version 3 (4); by default a file without
    /// history stores only the cylinders at θ = 0 and the reader replays the rest from the
    /// vertices (version 3; with `--region` version 4, plus a bit per kept cylinder).
    #[arg(long)]
    pub explicit_cylinders: bool,
    /// Build the history without search path compaction (§4.4): split and merge as two
    /// steps, to measure what compaction saves (the complex is the same).
    #[arg(long)]
    pub no_compaction: bool,
}

/// Parses `X0,Y0,X1,Y1` (scene units, rounded to the grid) into a box; `what` names the
/// option in errors.
pub fn parse_region(what: &str, text: &str) -> Result<vcx::partition::Region, Failure> {
    let bad = |why: String| Failure::bad_input(format!("{what} {text:?}: {why}"));
    let v: Vec<f64> = text
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| bad(format!("not four numbers X0,Y0,X1,Y1 ({e})")))?;
    let [x0, y0, x1, y1] = v[..] else {
        return Err(bad(format!(
            "{} numbers, expected four: X0,Y0,X1,Y1",
            v.len()
        )));
    };
    let point = |x: f64, y: f64| {
        vcx::Point::from_f64(x, y).map(|(p, _)| p).map_err(|e| {
            bad(match e {
                vcx::geom::CoordinateError::NotFinite => "not a finite number".to_string(),
                _ => "outside ±16384 (the coordinate range)".to_string(),
            })
        })
    };
    vcx::partition::Region::new(point(x0, y0)?, point(x1, y1)?)
        .ok_or_else(|| bad("X0 ≤ X1 and Y0 ≤ Y1 are needed".to_string()))
}

/// Whether rays in this scene can leave an object (point location on its sheet, which
/// `--history auto` stores the history for): it has a mirror, a refractive object or a
/// screen. Walks never read the history.
pub fn needs_history(scene: &SceneRef<'_>) -> bool {
    scene
        .objects()
        .iter()
        .any(|o| o.material != vcx::Material::Opaque)
}

/// A built complex and how long building it took.
pub struct Built {
    /// The complex (validated).
    pub complex: Complex,
    /// The whole complex when `complex` is pruned to a region: what a version-4 region
    /// file stores (`vcx::format::encode_region`).
    pub whole: Option<Complex>,
    /// The construction history (randomized incremental construction only).
    pub history: Option<History>,
    /// Wall time of the construction alone, in seconds.
    pub seconds: f64,
}

/// Builds the complex of a validated scene and checks it; any failure is internal
/// (exit status 3) and names the scene file.
pub fn build_checked(path: &Path, scene: &SceneRef<'_>) -> Result<Built, Failure> {
    build_with(path, scene, Method::Sweep, &BuildOptions::default())
}

/// Builds with the given method and validates the result.
pub fn build_with(
    path: &Path,
    scene: &SceneRef<'_>,
    method: Method,
    options: &BuildOptions,
) -> Result<Built, Failure> {
    let internal = |e: vcx::partition::ComplexError| Failure {
        message: format!("{}: internal: {e}", path.display()),
        code: EXIT_INTERNAL,
    };
    let start = Instant::now();
    let (complex, history, seconds) = match method {
        Method::Sweep => {
            let c = build_by_sweep(scene).map_err(internal)?;
            (c, None, start.elapsed().as_secs_f64())
        }
        Method::Ric => {
            let h = History::build(scene, options).map_err(internal)?;
            let seconds = start.elapsed().as_secs_f64();
            (h.complex(scene).map_err(internal)?, Some(h), seconds)
        }
    };
    complex.validate(scene).map_err(internal)?;
    Ok(Built {
        complex,
        whole: None,
        history,
        seconds,
    })
}

/// Loads the scene, builds and validates the complex, prints the statistics.
pub fn run(args: &Args) -> Result<(), Failure> {
    let file = super::check::load(&args.scene)?;
    let scene = file.scene.as_ref();
    let first = if args.screens_first {
        let screens = scene.objects().iter().enumerate();
        screens
            .filter(|(_, o)| o.material == vcx::Material::Screen)
            .map(|(i, _)| vcx::ObjectId(i as u32))
            .collect()
    } else {
        Vec::new()
    };
    if args.no_compaction && args.method == Some(Method::Sweep) {
        return Err(Failure::bad_input(
            "--no-compaction is about the history of the randomized construction: the \
             rotational sweep (--method sweep) builds none",
        ));
    }
    let options = BuildOptions {
        seed: args.seed,
        first,
        compaction: !args.no_compaction,
        ..Default::default()
    };
    let region = match &args.region {
        Some(text) => {
            if args.history == HistoryChoice::Always {
                return Err(Failure::bad_input(
                    "--region writes no history: a pruned complex has only what walks from \
                     the box need, and point location needs the whole (drop --history always)",
                ));
            }
            Some(parse_region("--region", text)?)
        }
        None => None,
    };
    let write_history = args.output.is_some()
        && region.is_none()
        && match args.history {
            HistoryChoice::Never => false,
            HistoryChoice::Auto => args.method != Some(Method::Sweep) && needs_history(&scene),
            HistoryChoice::Always => {
                if args.method == Some(Method::Sweep) {
                    return Err(Failure::bad_input(
                        "--history always needs the randomized construction: the rotational \
                         sweep (--method sweep) builds no history"
                            .to_string(),
                    ));
                }
                true
            }
        };
    let method = if write_history {
        Method::Ric
    } else {
        args.method.unwrap_or(Method::Ric)
    };
    let mut built = build_with(&args.scene, &scene, method, &options)?;
    let full_cylinders = built.complex.cylinders().len();
    if let Some(r) = region {
        let pruned = built
            .complex
            .prune_to_region(&scene, r)
            .map_err(|e| Failure::bad_input(format!("{}: --region: {e}", args.scene.display())))?;
        built.whole = Some(core::mem::replace(&mut built.complex, pruned));
        // The pruned complex passes the checks a loader runs on it.
        built.complex.validate(&scene).map_err(|e| Failure {
            message: format!("{}: internal: pruned complex: {e}", args.scene.display()),
            code: EXIT_INTERNAL,
        })?;
    }
    let written = match &args.output {
        Some(out) => Some((out, write_vcx(out, &scene, &built, write_history, args)?)),
        None => None,
    };
    let text = if args.stats_json {
        let mut stats = stats_json(scene.len(), &built);
        if args.no_compaction {
            stats["compaction"] = json!(false);
        }
        if let Some(r) = built.complex.region() {
            let ((x0, y0), (x1, y1)) = (r.min().to_f64(), r.max().to_f64());
            stats["region"] = json!([x0, y0, x1, y1]);
            stats["full_cylinders"] = json!(full_cylinders);
        }
        if let Some((_, (bytes, history))) = written {
            stats["file_bytes"] = json!(bytes);
            stats["file_history_bytes"] = json!(history);
        }
        let mut line = stats.to_string();
        line.push('\n');
        line
    } else {
        let mut line = summary(&args.scene, scene.len(), &built);
        if let Some(r) = built.complex.region() {
            let ((x0, y0), (x1, y1)) = (r.min().to_f64(), r.max().to_f64());
            line.push_str(&format!(
                "; region {x0},{y0},{x1},{y1}: kept {} of {full_cylinders} cylinders",
                built.complex.cylinders().len()
            ));
        }
        if let Some((out, (bytes, history))) = written {
            let history = history.map_or(String::new(), |h| format!(", history {h} bytes"));
            line.push_str(&super::one_line(&format!(
                "; wrote {} ({bytes} bytes{history})",
                out.display()
            )));
        }
        format!("{line}\n")
    };
    write_stdout(&text)
}

/// Encodes the scene and complex (and the history if `with_history`) and writes the file;
/// returns its length in bytes and the history part's, if written.
fn write_vcx(
    out: &Path,
    scene: &SceneRef<'_>,
    built: &Built,
    with_history: bool,
    args: &Args,
) -> Result<(usize, Option<usize>), Failure> {
    let bytes = encode_vcx(
        &args.scene,
        scene,
        built,
        with_history,
        args.seed,
        args.explicit_cylinders,
    )?;
    std::fs::write(out, &bytes)
        .map_err(|e| Failure::bad_input(format!("cannot write {}: {e}", out.display())))?;
    Ok((bytes.len(), history_part_bytes(&bytes)))
}

/// The bytes `vcx build PATH -o FILE` writes (`seed`: of the randomized construction;
/// `explicit`: `--explicit-cylinders`); also measured by `vcx bench figures`.
pub(crate) fn encode_vcx(
    path: &Path,
    scene: &SceneRef<'_>,
    built: &Built,
    with_history: bool,
    seed: u64,
    explicit: bool,
) -> Result<Vec<u8>, Failure> {
    let options = vcx::format::EncodeOptions {
        seed: built.history.is_some().then_some(seed),
        // The file's flag is the history's own (`History::is_compacted`) when it has one.
        compacted: built.history.as_ref().is_some_and(|h| h.is_compacted()),
        explicit_cylinders: explicit,
    };
    let history = built.history.as_ref().filter(|_| with_history);
    // A region file (version 4) stores the whole complex and which cylinders it keeps.
    let encoded = match (&built.whole, built.complex.region()) {
        (Some(whole), Some(region)) if !explicit => {
            vcx::format::encode_region(scene, whole, region, &options)
        }
        _ => vcx::format::encode(scene, &built.complex, history, &options),
    };
    encoded.map_err(|e| Failure {
        message: format!("{}: internal: cannot encode: {e}", path.display()),
        code: EXIT_INTERNAL,
    })
}

/// The history part's length in an encoded file, if it has one.
pub(crate) fn history_part_bytes(bytes: &[u8]) -> Option<usize> {
    match vcx::format::Header::read_unchecked(bytes) {
        Ok(h) if h.has_history() => Some(h.history_bytes as usize),
        _ => None,
    }
}

/// The `--stats-json` object.
pub fn stats_json(objects: usize, built: &Built) -> Value {
    let c = &built.complex;
    let mut v = json!({
        "objects": objects,
        "free_bitangents": c.free_bitangents(),
        "complex_vertices": c.vertices().len(),
        "faces": c.faces(),
        "cylinders": c.cylinders().len(),
        "build_seconds": built.seconds,
    });
    match &built.history {
        Some(h) => {
            let st = h.stats();
            v["method"] = json!("ric");
            v["history_nodes"] = json!(st.nodes);
            v["history_links"] = json!(st.links);
            v["history_depth"] = json!(st.depth);
        }
        None => {
            v["method"] = json!("sweep");
            v["history_nodes"] = Value::Null;
            v["history_links"] = Value::Null;
            v["history_depth"] = Value::Null;
            v["history"] = json!(HISTORY_NOT_BUILT);
        }
    }
    v
}

/// The one-line summary for people.
pub fn summary(path: &Path, objects: usize, built: &Built) -> String {
    let c = &built.complex;
    super::one_line(&format!(
        "{}: {objects} objects, {} free bitangents ({} complex vertices), {} faces, \
         {} cylinders; built in {:.3} s ({})",
        path.display(),
        c.free_bitangents(),
        c.vertices().len(),
        c.faces(),
        c.cylinders().len(),
        built.seconds,
        match &built.history {
            Some(h) => {
                let st = h.stats();
                format!(
                    "randomized incremental, history {} nodes, {} links, depth {}{}",
                    st.nodes,
                    st.links,
                    st.depth,
                    if h.is_compacted() {
                        ""
                    } else {
                        ", uncompacted"
                    }
                )
            }
            None => "rotational sweep, no history".to_string(),
        }
    ))
}
