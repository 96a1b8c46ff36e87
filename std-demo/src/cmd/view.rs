//! `vcx view SCENE.json (--at X,Y | --at-file FILE) [--from DEG --to DEG] [--depth D]
//! [--json]`: what a viewpoint sees all around, as exact angular intervals, and with
//! `--depth D` its ray tree through mirrors and refractive objects.
//!
//! The complex is built once per invocation (validated as by `vcx build`; a failure is
//! internal, exit status 3). At depth 0 it is built over the scene **without its screens**:
//! views treat screens as transparent, so a screen is never seen and never bounds an
//! interval; the view is exact ([`vcx::walk::view`]). At depth D > 0 the complex includes
//! the screens and [`vcx::walk::ray_tree`] walks through them; primary boundaries are
//! exact, deeper ones are mapped back to primary angles in `f64`. Floats appear only in
//! the printed angles.
//!
//! * `--at X,Y`: the viewpoint, as for `vcx locate` (decimal numbers rounded to the 2⁻³²
//!   query grid, `|X|, |Y| ≤ 2²⁰`; a viewpoint on a bitangent or an edge's extension is
//!   decided by the symbolic perturbation, the output stays exact).
//! * `--at-file FILE`: one `X,Y` per line; blank lines and everything from `#` to the end
//!   of a line are skipped. One view is printed per point, in order. Every line is checked
//!   before anything is printed: a bad line is bad input and the message names its number.
//! * `--from DEG --to DEG`: only the directions counter-clockwise from `DEG` to `DEG`
//!   (degrees, any finite value, taken modulo 360; the range may wrap through 0;
//!   `from == to` modulo 360 is the full circle starting at `from`). The output is the
//!   full view restricted to that range: the first interval starts at `from` (its `vertex`
//!   is `null` unless `from` is itself a boundary), the last ends at `to`, in order from
//!   `from`. A boundary within 10⁻¹³ radian of `from` or `to` counts as lying on it
//!   (degrees cannot be converted to radians exactly).
//! * `--depth D`: the depth of the ray tree, 0 to 16: at most D reflections (mirrors) or
//!   passes through refractive objects (tangent law, DESIGN.md §6) after the primary hit.
//!   `path` then lists the objects along the ray, primary first, screens left out.
//!
//! Output with `--json`: one line per viewpoint, exactly
//! `{"intervals": [{"start": rad, "end": rad, "path": [ids], "vertex": [object, vertex] |
//! null}, …]}` — angles in radians in `[0, 2π)`, counter-clockwise from +x; the `end` of an
//! interval is the `start` of the next, and the last one's `end` is the first one's `start`
//! (for the full circle; with `--from/--to` it is `to`); `path` is `[object]`, or `[]` when
//! the directions escape to infinity (at depth D: the branch, at most D + 1 objects); `vertex` is the vertex causing the start boundary,
//! as `[object id, vertex id]` as written in the scene file, or `null` (a view with a
//! single interval covering the full circle, or a clipped first interval). Without
//! `--json`: a header line and a table in degrees per viewpoint, tables separated by a
//! blank line.
//!
//! Errors (exit status 2, one `error: ` line): malformed or out-of-range numbers, an
//! unreadable at-file or a bad line in it, a `--depth` that is not 0 to 16, and a viewpoint inside
//! or on the boundary of an object — screens included, which the line names — or, with a
//! `.vcx` file pruned to a region (`vcx build --region`), outside that region.

use core::f64::consts::TAU;
use std::path::{Path, PathBuf};

use serde_json::{json, Value};
use vcx::partition::{point_in_scene, Location};
use vcx::walk::{ray_tree, view, ViewInterval, WalkError};
use vcx::{Material, ObjectId, QueryPoint, SceneRef, SubScene};
use vcx_demo::SceneFile;

use super::build::EXIT_INTERNAL;
use super::locate::{describe, in_object, number, parse_pair, query_point};
use super::{write_stdout, Failure};

/// Arguments of `vcx view`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (JSON).
    pub scene: PathBuf,
    /// The viewpoint, `X,Y` in scene units (this or --at-file is required).
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub at: Option<String>,
    /// A file of viewpoints, one `X,Y` per line (`#` comments and blank lines skipped);
    /// one view is printed per point.
    #[arg(long, value_name = "FILE")]
    pub at_file: Option<PathBuf>,
    /// Start of the angular range, in degrees counter-clockwise from +x (with --to).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub from: Option<String>,
    /// End of the angular range, in degrees (with --from; equal to --from: full circle).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub to: Option<String>,
    /// Ray-tree depth: 0 is what is seen directly; D follows up to D reflections or
    /// refractions (screens are transparent).
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub depth: Option<String>,
    /// Print one JSON object per viewpoint instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// A boundary this close to `from` or `to` (radians) counts as lying on it.
const SNAP: f64 = 1e-13;

/// One printed interval: angles in radians, ids as in the scene file.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Start direction, radians in `[0, 2π)`.
    pub start: f64,
    /// End direction (the next row's start).
    pub end: f64,
    /// The branch of the ray tree: objects along the ray, primary first, screens left out
    /// (one object or none at depth 0).
    pub path: Vec<ObjectId>,
    /// The vertex causing the start boundary: (object id, written vertex id).
    pub vertex: Option<(ObjectId, usize)>,
}

/// The angular range of `--from/--to`: start in radians in `[0, 2π)`, length in `(0, 2π]`.
#[derive(Clone, Copy, Debug)]
struct Range {
    from: f64,
    to: f64,
    len: f64,
    from_deg: f64,
    to_deg: f64,
}

/// One viewpoint to view: how it was written, where it came from (for messages) and the
/// point.
pub(crate) struct Viewpoint {
    at: String,
    origin: Option<String>,
    pub(crate) q: QueryPoint,
}

/// Parses the arguments, builds the complex once, computes and prints every view.
pub fn run(args: &Args) -> Result<(), Failure> {
    let depth = match &args.depth {
        None => 0,
        Some(d) => match d.trim().parse::<usize>() {
            Ok(v) if v <= MAX_DEPTH => v,
            _ => {
                return Err(Failure::bad_input(format!(
                    "--depth {d}: the ray-tree depth must be a whole number from 0 to {MAX_DEPTH}"
                )))
            }
        },
    };
    // Checked here rather than by clap so that the error stays one line.
    let range = match (&args.from, &args.to) {
        (Some(f), Some(t)) => Some(parse_range(f, t)?),
        (None, None) => None,
        _ => {
            return Err(Failure::bad_input(
                "--from and --to go together (from == to for the full circle)",
            ))
        }
    };
    let points = match (&args.at, &args.at_file) {
        (Some(_), Some(_)) => {
            return Err(Failure::bad_input(
                "give either --at or --at-file, not both",
            ))
        }
        (Some(at), None) => {
            let (x, y) = parse_pair("--at", at)?;
            vec![Viewpoint {
                at: format!("({}, {})", number(x), number(y)),
                origin: None,
                q: query_point("--at", at, x, y)?,
            }]
        }
        (None, Some(path)) => read_points(path)?,
        (None, None) => return Err(Failure::bad_input("--at or --at-file is required")),
    };

    // JSON or `.vcx`: a stored complex is used where it is the one needed (crate::input).
    let input = crate::input::load(&args.scene)?;
    let file = &input.file;
    let scene = file.scene.as_ref();
    // Screens count here: a viewpoint inside a screen is an error too.
    for p in &points {
        if let Some(l) = point_in_scene(&scene, p.q) {
            return Err(located(&args.scene, p, file, l));
        }
    }
    let non_screen_ids = scene
        .objects()
        .iter()
        .enumerate()
        .filter(|(_, o)| o.material != Material::Screen)
        .map(|(i, _)| ObjectId(i as u32));
    let sub = SubScene::new(scene, non_screen_ids);
    let sub_scene = sub.as_ref();
    // Depth 0 walks the complex of the scene without its screens; ray trees need the
    // screens in the complex (secondary walks continue behind them).
    let built = if depth == 0 {
        input.built(&args.scene, &sub_scene)?
    } else {
        input.built(&args.scene, &scene)?
    };

    let mut text = String::new();
    for (i, p) in points.iter().enumerate() {
        if depth > 0 {
            let tree = ray_tree(&built.complex, &scene, p.q, depth).map_err(|e| match e {
                WalkError::OutsideRegion(_) => outside(&args.scene, p, &e),
                e => Failure {
                    message: format!(
                        "{}: internal: ray tree from {}: {e}",
                        args.scene.display(),
                        p.at
                    ),
                    code: EXIT_INTERNAL,
                },
            })?;
            let full = tree_rows(&scene, &tree);
            emit(args, file, p, i, range, full, &mut text);
            continue;
        }
        let intervals = match view(&built.complex, &sub_scene, p.q) {
            Ok(v) => v,
            Err(WalkError::NotFree(l)) => {
                let l = match l {
                    Location::Inside { object } => Location::Inside {
                        object: sub.original(object).unwrap_or(object),
                    },
                    Location::OnBoundary { object } => Location::OnBoundary {
                        object: sub.original(object).unwrap_or(object),
                    },
                    other => other,
                };
                return Err(located(&args.scene, p, file, l));
            }
            Err(e @ WalkError::OutsideRegion(_)) => return Err(outside(&args.scene, p, &e)),
            Err(e) => {
                return Err(Failure {
                    message: format!(
                        "{}: internal: view from {}: {e}",
                        args.scene.display(),
                        p.at
                    ),
                    code: EXIT_INTERNAL,
                })
            }
        };
        let full = full_rows(&scene, &sub, &intervals);
        emit(args, file, p, i, range, full, &mut text);
    }
    write_stdout(&text)
}

/// A viewpoint outside the region a `.vcx` file was pruned to (`vcx build --region`): bad
/// input, exit status 2.
fn outside(path: &Path, p: &Viewpoint, e: &WalkError) -> Failure {
    Failure::bad_input(format!("{}: viewpoint {}: {e}", path.display(), p.at))
}

/// Deepest ray tree the command computes.
const MAX_DEPTH: usize = 16;

/// Restricts the rows to the range and appends them as JSON or a table.
fn emit(
    args: &Args,
    file: &SceneFile,
    p: &Viewpoint,
    i: usize,
    range: Option<Range>,
    full: Vec<Row>,
    text: &mut String,
) {
    let rows = match range {
        Some(r) => restrict(&full, r),
        None => full,
    };
    if args.json {
        text.push_str(&to_json(&rows).to_string());
        text.push('\n');
    } else {
        if i > 0 {
            text.push('\n');
        }
        text.push_str(&table(&args.scene, file, &p.at, range, &rows));
    }
}

/// A branch for people: the objects along the ray joined by arrows, or "nothing".
fn describe_path(file: &SceneFile, path: &[ObjectId]) -> String {
    if path.is_empty() {
        return describe(file, None);
    }
    path.iter()
        .map(|&o| describe(file, Some(o)))
        .collect::<Vec<_>>()
        .join(" -> ")
}

/// A ray tree as rows in scene-file ids.
fn tree_rows(scene: &SceneRef<'_>, tree: &[vcx::walk::TreeInterval]) -> Vec<Row> {
    let n = tree.len();
    tree.iter()
        .enumerate()
        .map(|(i, t)| Row {
            start: t.start,
            end: tree.get((i + 1) % n).map_or(t.start, |u| u.start),
            path: t.branch.clone(),
            vertex: t.start_vertex.and_then(|k| written_vertex(scene, k)),
        })
        .collect()
}

/// The failure for a viewpoint inside or on an object; an at-file line is named.
fn located(path: &Path, p: &Viewpoint, file: &SceneFile, l: Location) -> Failure {
    let f = in_object(path, &p.at, file, l);
    match &p.origin {
        Some(o) => Failure::bad_input(format!("{o}: {}", f.message)),
        None => f,
    }
}

/// Parses `--from` and `--to` (degrees, finite).
fn parse_range(from: &str, to: &str) -> Result<Range, Failure> {
    let degrees = |option: &str, text: &str| -> Result<f64, Failure> {
        let t = text.trim();
        match t.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v.rem_euclid(360.0)),
            Ok(_) => Err(Failure::bad_input(format!(
                "{option} {text:?}: {t:?} is not finite"
            ))),
            Err(_) => Err(Failure::bad_input(format!(
                "{option} {text:?}: {t:?} is not a number (degrees)"
            ))),
        }
    };
    let (from_deg, to_deg) = (degrees("--from", from)?, degrees("--to", to)?);
    let radians = |d: f64| {
        let r = d.to_radians();
        if r >= TAU {
            0.0
        } else {
            r
        }
    };
    let (f, t) = (radians(from_deg), radians(to_deg));
    let len = if from_deg == to_deg {
        TAU
    } else {
        (t - f).rem_euclid(TAU)
    };
    Ok(Range {
        from: f,
        to: if from_deg == to_deg { f } else { t },
        len,
        from_deg,
        to_deg,
    })
}

/// Reads the viewpoints of an at-file; a bad line is bad input naming `FILE:LINE`.
pub(crate) fn read_points(path: &Path) -> Result<Vec<Viewpoint>, Failure> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Failure::bad_input(format!("cannot read {}: {e}", path.display())))?;
    let mut points = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let content = line.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let label = format!("{}:{}:", path.display(), i + 1);
        let (x, y) = parse_pair(&label, content)?;
        let q = query_point(&label, content, x, y)?;
        points.push(Viewpoint {
            at: format!("({}, {})", number(x), number(y)),
            origin: Some(format!("{}:{}", path.display(), i + 1)),
            q,
        });
    }
    Ok(points)
}

/// The object of the whole scene owning the global vertex `k`, and the vertex id as written.
fn written_vertex(scene: &SceneRef<'_>, k: usize) -> Option<(ObjectId, usize)> {
    let objects = scene.objects();
    let i = objects.partition_point(|o| o.first_vertex() + o.len() <= k);
    let o = objects.get(i)?;
    (o.first_vertex() <= k).then(|| {
        (
            ObjectId(i as u32),
            o.written_vertex_id(k - o.first_vertex()),
        )
    })
}

/// The full view as rows in scene-file ids; each row ends where the next starts, the last
/// where the first starts.
fn full_rows(scene: &SceneRef<'_>, sub: &SubScene<'_>, intervals: &[ViewInterval]) -> Vec<Row> {
    let starts: Vec<f64> = intervals.iter().map(|v| v.start.radians()).collect();
    intervals
        .iter()
        .enumerate()
        .map(|(i, v)| Row {
            start: starts[i],
            end: starts[(i + 1) % starts.len()],
            path: v.object.and_then(|o| sub.original(o)).into_iter().collect(),
            vertex: v.start_vertex.and_then(|k| written_vertex(scene, k)),
        })
        .collect()
}

/// The restriction of a full view (rows sorted by start, wrapping) to a range.
fn restrict(full: &[Row], r: Range) -> Vec<Row> {
    let n = full.len();
    if n == 0 {
        return Vec::new();
    }
    // Counter-clockwise offset of each start from `from`, in [0, 2π).
    let offset: Vec<f64> = full
        .iter()
        .map(|row| (row.start - r.from).rem_euclid(TAU))
        .collect();
    // The first interval starting at or after `from`; the one before it contains `from`.
    let mut k0 = 0;
    for i in 1..n {
        if offset[i] < offset[k0] {
            k0 = i;
        }
    }
    let before = (k0 + n - 1) % n;
    let (first, on_boundary) = if n > 1 && TAU - offset[before] <= SNAP {
        (before, true)
    } else if n > 1 && offset[k0] <= SNAP {
        (k0, true)
    } else {
        (before, false)
    };
    let mut rows = vec![Row {
        start: r.from,
        end: r.to,
        path: full[first].path.clone(),
        vertex: if on_boundary {
            full[first].vertex
        } else {
            None
        },
    }];
    // After the others, the rest of the interval that `from` cuts, if the range reaches it.
    let again = usize::from(!on_boundary && n > 1);
    for step in 1..n + again {
        let i = (first + step) % n;
        if offset[i] >= r.len - SNAP {
            break;
        }
        rows.push(Row {
            end: r.to,
            ..full[i].clone()
        });
    }
    for i in 0..rows.len() - 1 {
        rows[i].end = rows[i + 1].start;
    }
    rows
}

/// The `--json` object of one view.
pub fn to_json(rows: &[Row]) -> Value {
    let intervals: Vec<Value> = rows
        .iter()
        .map(|row| {
            json!({
                "start": row.start,
                "end": row.end,
                "path": row.path.iter().map(|o| o.0).collect::<Vec<u32>>(),
                "vertex": row.vertex.map_or(Value::Null, |(o, v)| json!([o.0, v])),
            })
        })
        .collect();
    json!({ "intervals": intervals })
}

/// The table for people: a header line, a column line, one line per interval (degrees).
fn table(path: &Path, file: &SceneFile, at: &str, range: Option<Range>, rows: &[Row]) -> String {
    let what = match range {
        Some(r) if r.len == TAU => format!(", full circle from {}°", number(r.from_deg)),
        Some(r) => format!(
            ", from {}° to {}° counter-clockwise",
            number(r.from_deg),
            number(r.to_deg)
        ),
        None => String::new(),
    };
    let count = if rows.len() == 1 {
        "1 interval".to_string()
    } else {
        format!("{} intervals", rows.len())
    };
    let mut out = super::one_line(&format!(
        "{}: view from {at}{what}: {count}",
        path.display()
    ));
    out.push('\n');
    out.push_str(&format!(
        "{:>12}  {:>12}  {:<24}  {}\n",
        "start (deg)", "end (deg)", "sees", "boundary vertex"
    ));
    for row in rows {
        let vertex = match row.vertex {
            Some((o, v)) => format!("object {} vertex {v}", o.0),
            None => "-".to_string(),
        };
        out.push_str(&super::one_line(&format!(
            "{:>12.6}  {:>12.6}  {:<24}  {vertex}",
            row.start.to_degrees(),
            row.end.to_degrees(),
            describe_path(file, &row.path),
        )));
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(start: f64, end: f64, object: Option<u32>, vertex: Option<usize>) -> Row {
        Row {
            start,
            end,
            path: object.map(ObjectId).into_iter().collect(),
            vertex: vertex.map(|v| (ObjectId(object.unwrap_or(0)), v)),
        }
    }

    fn range(from: f64, to: f64) -> Range {
        parse_range(&from.to_string(), &to.to_string()).unwrap()
    }

    #[test]
    fn restriction() {
        let (a, b, c) = (1.0, 3.0, 5.0);
        let full = [
            row(a, b, Some(1), Some(0)),
            row(b, c, None, Some(1)),
            row(c, a, Some(2), Some(2)),
        ];
        // Inside the interval from c, wrapping through 0 into the one from a.
        let r = restrict(&full, range(330.0, 90.0));
        assert_eq!(r.len(), 2);
        assert!((r[0].start - 330f64.to_radians()).abs() < 1e-15);
        assert_eq!(
            (r[0].end, r[0].path.first().copied(), r[0].vertex),
            (a, Some(ObjectId(2)), None)
        );
        assert_eq!(
            (r[1].start, r[1].path.first().copied()),
            (a, Some(ObjectId(1)))
        );
        assert!((r[1].end - 90f64.to_radians()).abs() < 1e-15);
        // Starting on a boundary keeps its vertex; the full circle ends where it starts.
        let r = restrict(&full, range(b.to_degrees(), b.to_degrees()));
        assert_eq!(r.len(), 3);
        assert_eq!(r[0].vertex, full[1].vertex);
        assert_eq!(r[2].end, r[0].start);
        // The full circle from inside an interval: it is cut in two.
        let r = restrict(&full, range(120.0, 120.0));
        assert_eq!(r.len(), 4);
        assert_eq!(
            (r[0].path.first().copied(), r[0].vertex),
            (Some(ObjectId(1)), None)
        );
        assert_eq!(
            (r[3].start, r[3].path.first().copied(), r[3].vertex),
            (a, full[0].path.first().copied(), full[0].vertex)
        );
        assert_eq!(r[3].end, r[0].start);
        assert!((r[0].start - 120f64.to_radians()).abs() < 1e-15);
        // A range inside one interval.
        let r = restrict(&full, range(100.0, 110.0));
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].path.first().copied(), Some(ObjectId(1)));
        // Ending on a boundary drops the empty interval after it.
        let r = restrict(&full, range(100.0, b.to_degrees()));
        assert_eq!(r.len(), 1);
        // A single full-circle interval.
        let one = [row(0.0, 0.0, None, None)];
        let r = restrict(&one, range(10.0, 10.0));
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].start, r[0].end);
    }
}
