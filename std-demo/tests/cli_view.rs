//! `vcx view`, run as the built binary: a hand-made scene worked out on paper (with a
//! screen that must stay invisible), a viewpoint on two bitangents, the invariants of every
//! view on the example scenes (with `vcx locate` as a second opinion), `--from/--to` as the
//! exact restriction of the full view, `--at-file`, and every bad input giving exit status 2
//! and exactly one `error: ` line.

use core::f64::consts::TAU;
use std::path::{Path, PathBuf};

use serde_json::Value;

mod common;
use common::{example, temp_path, vcx};

/// Paper scene. The viewpoint is the origin; no two vertices are collinear with it and no
/// edge's line passes through it.
///
/// * 0 "east", opaque, `[2, 3] × [-1, 1]`, counter-clockwise: seen from (2, -1) (vertex 0,
///   at −26.57°) to (2, 1) (vertex 3, at 26.57°), through θ = 0.
/// * 1 "north", opaque, `[-1, 1] × [3, 4]`, written **clockwise**: from (1, 3) (written
///   vertex 3, 71.57°) to (-1, 3) (written vertex 0, 108.43°).
/// * 2 "west", mirror (seen like an opaque object at depth 0), `[-5, -4] × [-1, 3]`: from
///   (-4, 3) (vertex 2, 143.13°) to (-4, -1) (vertex 1, 194.04°).
/// * 3 "south", opaque, `[-2, 1] × [-5, -2]`: from (-2, -2) (vertex 3, 225°) to (1, -2)
///   (vertex 2, 296.57°).
/// * 4 "glass", screen, `[2, 3] × [2, 3]`, in the gap between east and north: transparent,
///   so the gap from 26.57° to 71.57° sees nothing.
const PAPER: &str = r#"{"objects": [
  {"name": "east", "material": "opaque", "vertices": [[2, -1], [3, -1], [3, 1], [2, 1]]},
  {"name": "north", "material": "opaque", "vertices": [[-1, 3], [-1, 4], [1, 4], [1, 3]]},
  {"name": "west", "material": "mirror", "vertices": [[-5, -1], [-4, -1], [-4, 3], [-5, 3]]},
  {"name": "south", "material": "opaque", "vertices": [[-2, -5], [1, -5], [1, -2], [-2, -2]]},
  {"name": "glass", "material": "screen", "vertices": [[2, 2], [3, 2], [3, 3], [2, 3]]}
]}"#;

/// A fresh file in a per-process temporary directory.
fn temp_file(name: &str, text: &str) -> PathBuf {
    let path = temp_path(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// [`common::ok`], and stdout ends with a newline.
fn ok(args: &[&str]) -> String {
    let stdout = common::ok(args);
    assert!(stdout.ends_with('\n'), "{args:?}: {stdout}");
    stdout
}

/// [`common::fails`], the line ending with a newline; returns the line.
fn fails(args: &[&str], expect: &[&str]) -> String {
    let stderr = common::fails(args, expect);
    assert!(stderr.ends_with('\n'), "{args:?}: {stderr}");
    stderr.trim_end().to_string()
}

/// One interval of `--json` output.
#[derive(Clone, Debug, PartialEq)]
struct Interval {
    start: f64,
    end: f64,
    path: Vec<u64>,
    vertex: Option<(u64, u64)>,
}

/// Parses one `--json` line, checking its exact shape.
fn parse_view(line: &str) -> Vec<Interval> {
    let v: Value = serde_json::from_str(line).unwrap();
    let top = v.as_object().unwrap();
    assert_eq!(top.keys().collect::<Vec<_>>(), ["intervals"], "{line}");
    top["intervals"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| {
            let o = i.as_object().unwrap();
            assert_eq!(
                o.keys().collect::<Vec<_>>(),
                ["start", "end", "path", "vertex"],
                "{line}"
            );
            let path: Vec<u64> = o["path"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| p.as_u64().unwrap())
                .collect();
            assert!(path.len() <= 1, "{line}");
            let vertex = match &o["vertex"] {
                Value::Null => None,
                Value::Array(a) => {
                    assert_eq!(a.len(), 2, "{line}");
                    Some((a[0].as_u64().unwrap(), a[1].as_u64().unwrap()))
                }
                other => panic!("vertex {other}"),
            };
            Interval {
                start: o["start"].as_f64().unwrap(),
                end: o["end"].as_f64().unwrap(),
                path,
                vertex,
            }
        })
        .collect()
}

/// `vcx view SCENE --at AT --json [extra…]`: the one line, parsed.
fn view(scene: &Path, at: &str, extra: &[&str]) -> Vec<Interval> {
    let mut args = vec!["view", scene.to_str().unwrap(), "--at", at, "--json"];
    args.extend_from_slice(extra);
    let out = ok(&args);
    assert_eq!(out.lines().count(), 1, "{out}");
    parse_view(out.trim_end())
}

/// The invariants of a full view: starts in [0, 2π) strictly increasing, each end the next
/// start and the last end the first start (so the intervals cover the circle once, counter-
/// clockwise), neighbours see different things, a boundary vertex exactly where there is a
/// boundary, and no screen anywhere.
fn check_full(view: &[Interval], screens: &[u64], what: &str) {
    assert!(!view.is_empty(), "{what}");
    for (i, v) in view.iter().enumerate() {
        assert!((0.0..TAU).contains(&v.start), "{what}: {v:?}");
        let next = &view[(i + 1) % view.len()];
        assert_eq!(v.end, next.start, "{what}: {i}");
        if view.len() > 1 {
            assert_ne!(v.path, next.path, "{what}: {i}");
            assert!(v.vertex.is_some(), "{what}: {v:?}");
        }
        for s in screens {
            assert!(!v.path.contains(s), "{what}: screen {s} seen: {v:?}");
            assert!(v.vertex.is_none_or(|(o, _)| o != *s), "{what}: {v:?}");
        }
    }
    for w in view.windows(2) {
        assert!(w[0].start < w[1].start, "{what}: {w:?}");
    }
    if view.len() == 1 {
        assert_eq!(view[0].vertex, None, "{what}");
        assert_eq!(view[0].start, view[0].end, "{what}");
    }
}

/// An expected interval: a point on its start ray, its path, its boundary vertex.
type Expected = ((f64, f64), &'static [u64], (u64, u64));

/// Angle of (x, y) in [0, 2π).
fn angle(x: f64, y: f64) -> f64 {
    y.atan2(x).rem_euclid(TAU)
}

#[test]
fn paper_scene_view_from_the_origin() {
    let scene = temp_file("paper.json", PAPER);
    let got = view(&scene, "0,0", &[]);
    check_full(&got, &[4], "paper");
    // (start direction, path, vertex), worked out in the comment on PAPER.
    let expected: [Expected; 8] = [
        ((2.0, 1.0), &[], (0, 3)),
        ((1.0, 3.0), &[1], (1, 3)),
        ((-1.0, 3.0), &[], (1, 0)),
        ((-4.0, 3.0), &[2], (2, 2)),
        ((-4.0, -1.0), &[], (2, 1)),
        ((-2.0, -2.0), &[3], (3, 3)),
        ((1.0, -2.0), &[], (3, 2)),
        ((2.0, -1.0), &[0], (0, 0)),
    ];
    assert_eq!(got.len(), expected.len(), "{got:?}");
    for (g, ((x, y), path, vertex)) in got.iter().zip(expected) {
        assert!((g.start - angle(x, y)).abs() < 1e-12, "{g:?} vs ({x}, {y})");
        assert_eq!(g.path, path, "{g:?}");
        assert_eq!(g.vertex, Some(vertex), "{g:?}");
    }
    // --depth 0 is what is seen directly: the same.
    assert_eq!(view(&scene, "0,0", &["--depth", "0"]), got);

    // The table names the objects and ends with the interval through θ = 0.
    let table = ok(&["view", scene.to_str().unwrap(), "--at", "0,0"]);
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(lines.len(), 2 + 8, "{table}");
    assert!(
        lines[0].contains("view from (0, 0): 8 intervals"),
        "{table}"
    );
    assert!(lines[3].contains("object 1 \"north\""), "{table}");
    assert!(lines[9].contains("object 0 \"east\"") && lines[9].contains("object 0 vertex 0"));
    assert!(!table.contains("glass"), "{table}");
}

#[test]
fn viewpoint_on_two_bitangents() {
    // The origin lies on the free bitangents (2, 1)–(-2, -1) and (2, -1)–(-2, 1): the
    // perturbation decides the walk, the output stays exact.
    let scene = temp_file(
        "bitangents.json",
        r#"{"objects": [
          {"material": "opaque", "vertices": [[2, -1], [3, -1], [3, 1], [2, 1]]},
          {"material": "opaque", "vertices": [[-3, -1], [-2, -1], [-2, 1], [-3, 1]]}
        ]}"#,
    );
    let got = view(&scene, "0,0", &[]);
    check_full(&got, &[], "bitangents");
    let expected: [Expected; 4] = [
        ((2.0, 1.0), &[], (0, 3)),
        ((-2.0, 1.0), &[1], (1, 2)),
        ((-2.0, -1.0), &[], (1, 1)),
        ((2.0, -1.0), &[0], (0, 0)),
    ];
    assert_eq!(got.len(), 4, "{got:?}");
    for (g, ((x, y), path, vertex)) in got.iter().zip(expected) {
        assert!((g.start - angle(x, y)).abs() < 1e-12, "{g:?} vs ({x}, {y})");
        assert_eq!(g.path, path, "{g:?}");
        assert_eq!(g.vertex, Some(vertex), "{g:?}");
    }
}

#[test]
fn only_screens_give_one_full_circle_interval() {
    let scene = temp_file(
        "screens.json",
        r#"{"objects": [{"material": "screen", "vertices": [[0, 0], [1, 0], [0, 1]]}]}"#,
    );
    let got = view(&scene, "3,3", &[]);
    check_full(&got, &[0], "screens");
    assert_eq!(
        got,
        [Interval {
            start: 0.0,
            end: 0.0,
            path: vec![],
            vertex: None
        }]
    );
    let part = view(&scene, "3,3", &["--from", "10", "--to", "20"]);
    assert_eq!(part.len(), 1);
    assert!((part[0].start - 10f64.to_radians()).abs() < 1e-12);
    assert!((part[0].end - 20f64.to_radians()).abs() < 1e-12);
    assert_eq!((part[0].path.len(), part[0].vertex), (0, None));
}

/// The ids of the screens of a scene file.
fn screens(path: &Path) -> Vec<u64> {
    let v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["objects"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .filter(|(_, o)| o["material"] == "screen")
        .map(|(i, _)| i as u64)
        .collect()
}

/// Candidate viewpoints over `[lo, hi]²` at odd offsets; those inside or on an object are
/// refused with exit status 2 and dropped. Returns the free ones with their views.
fn free_views(scene: &Path, lo: f64, hi: f64, n: usize) -> Vec<(String, Vec<Interval>)> {
    let mut views = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let x = lo + (hi - lo) * (i as f64 + 0.37) / n as f64;
            let y = lo + (hi - lo) * (j as f64 + 0.61) / n as f64;
            let at = format!("{x},{y}");
            let args = ["view", scene.to_str().unwrap(), "--at", &at, "--json"];
            let out = vcx(&args);
            if out.status.code() == Some(2) {
                fails(&args, &["point (", "object "]);
                continue;
            }
            let stdout = String::from_utf8(out.stdout).unwrap();
            assert_eq!(out.status.code(), Some(0), "{args:?}");
            views.push((at, parse_view(stdout.trim_end())));
        }
    }
    views
}

#[test]
fn example_views_cover_the_circle_and_agree_with_locate() {
    for (name, lo, hi) in [
        ("grid", -2.0, 82.0),
        ("hall", 0.0, 40.0),
        ("mixed", 0.0, 60.0),
    ] {
        let path = example(name);
        let screens = screens(&path);
        let views = free_views(&path, lo, hi, 6);
        assert!(
            views.len() >= 10,
            "{name}: only {} free points",
            views.len()
        );
        for (at, v) in &views {
            check_full(v, &screens, &format!("{name} at {at}"));
        }
        // Without screens, `vcx locate` (cylinder scan) must see the same object ahead in
        // the middle of every interval that is not too thin for a float direction.
        if !screens.is_empty() {
            continue;
        }
        for (at, v) in views.iter().take(3) {
            for i in v {
                let width = if v.len() == 1 {
                    TAU
                } else {
                    (i.end - i.start).rem_euclid(TAU)
                };
                if width < 1e-6 {
                    continue;
                }
                let mid = i.start + width / 2.0;
                let dir = format!("{},{}", mid.cos(), mid.sin());
                let out = ok(&[
                    "locate",
                    path.to_str().unwrap(),
                    "--at",
                    at,
                    "--dir",
                    &dir,
                    "--json",
                ]);
                let l: Value = serde_json::from_str(out.trim_end()).unwrap();
                let forward: Vec<u64> = l["forward"].as_u64().into_iter().collect();
                assert_eq!(forward, i.path, "{name} at {at} towards {dir}: {i:?}");
            }
        }
    }
}

/// The restriction of a full view to the directions counter-clockwise from `from` to `to`
/// (degrees), computed independently of the binary: each interval, as an arc of offsets
/// from `from`, is intersected with `[0, len)` (twice, for the arc that wraps), pieces of
/// positive width are sorted. A piece keeps its vertex iff it was not clipped at its start
/// (a boundary within `tol` of `from` counts as lying on it).
fn restriction(full: &[Interval], from: f64, to: f64) -> Vec<Interval> {
    let tol = 1e-12;
    let f = from.rem_euclid(360.0).to_radians();
    let t = to.rem_euclid(360.0).to_radians();
    let len = if from.rem_euclid(360.0) == to.rem_euclid(360.0) {
        TAU
    } else {
        (t - f).rem_euclid(TAU)
    };
    let piece = |lo: f64, hi: f64, i: &Interval, vertex| Interval {
        start: (f + lo).rem_euclid(TAU),
        end: (f + hi).rem_euclid(TAU),
        path: i.path.clone(),
        vertex,
    };
    if full.len() == 1 {
        // No boundary at all: one piece, never cut.
        return vec![piece(0.0, len, &full[0], None)];
    }
    let mut pieces: Vec<(f64, Interval)> = Vec::new();
    for i in full {
        let width = (i.end - i.start).rem_euclid(TAU);
        let mut a = (i.start - f).rem_euclid(TAU);
        if TAU - a < tol {
            a -= TAU;
        }
        for shift in [0.0, -TAU] {
            let (lo, hi) = ((a + shift).max(0.0), (a + shift + width).min(len));
            if hi - lo > tol {
                let vertex = if a + shift > -tol { i.vertex } else { None };
                pieces.push((lo, piece(lo, hi, i, vertex)));
            }
        }
    }
    pieces.sort_by(|p, q| p.0.total_cmp(&q.0));
    pieces.into_iter().map(|(_, p)| p).collect()
}

/// Distance on the circle.
fn circle_distance(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(TAU);
    d.min(TAU - d)
}

fn assert_same(got: &[Interval], want: &[Interval], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: {got:?} vs {want:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(
            circle_distance(g.start, w.start) < 1e-12,
            "{what}: {g:?} vs {w:?}"
        );
        assert!(
            circle_distance(g.end, w.end) < 1e-12,
            "{what}: {g:?} vs {w:?}"
        );
        assert!((0.0..TAU).contains(&g.start), "{what}: {g:?}");
        assert_eq!(
            (&g.path, g.vertex),
            (&w.path, w.vertex),
            "{what}: {g:?} vs {w:?}"
        );
    }
    for w in got.windows(2) {
        assert_eq!(w[0].end, w[1].start, "{what}");
    }
}

#[test]
fn from_to_is_the_restriction_of_the_full_view() {
    let paper = temp_file("paper.json", PAPER);
    let mixed = example("mixed");
    let cases: Vec<(PathBuf, &str)> = vec![
        (paper.clone(), "0,0"),
        (paper.clone(), "-0.5,1.25"),
        (mixed.clone(), "0.3,0.1"),
        (mixed.clone(), "30.1,29.7"),
    ];
    for (scene, at) in &cases {
        let full = view(scene, at, &[]);
        let b0 = full[0].start.to_degrees();
        let b2 = full[2 % full.len()].start.to_degrees();
        let ranges: Vec<(f64, f64)> = vec![
            (0.0, 90.0),
            (300.0, 30.0),
            (-60.0, 30.0),
            (30.0, 390.5),
            (10.0, 10.0),
            (0.0, 0.0),
            (0.0, 360.0),
            (359.5, 0.25),
            (100.0, 100.001),
            // On boundaries: the first interval keeps its vertex; ending on a boundary
            // adds no empty interval.
            (b0, b0),
            (b0, b2),
            (b2, b0),
            (b0 + 1e-6, b2 - 1e-6),
        ];
        for (from, to) in ranges {
            let (fs, ts) = (format!("{from}"), format!("{to}"));
            let got = view(scene, at, &["--from", &fs, "--to", &ts]);
            let what = format!("{} at {at} from {fs} to {ts}", scene.display());
            assert_same(&got, &restriction(&full, from, to), &what);
            let f = from.rem_euclid(360.0).to_radians();
            assert!(circle_distance(got[0].start, f) < 1e-12, "{what}");
            let t = to.rem_euclid(360.0).to_radians();
            assert!(
                circle_distance(got.last().unwrap().end, t) < 1e-12,
                "{what}"
            );
        }
    }
}

#[test]
fn at_file_prints_one_view_per_point() {
    let paper = temp_file("paper.json", PAPER);
    let points = ["0,0", "-0.5,1.25", "1.5,-1.5", "-3, 0.5"];
    let text = format!(
        "# viewpoints\n{}\n\n   \n{}  # comment\n{}\n{}\n",
        points[0], points[1], points[2], points[3]
    );
    let file = temp_file("points.txt", &text);
    let out = ok(&[
        "view",
        paper.to_str().unwrap(),
        "--at-file",
        file.to_str().unwrap(),
        "--json",
    ]);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), points.len(), "{out}");
    for (line, at) in lines.iter().zip(points) {
        let single = view(&paper, at, &[]);
        assert_eq!(parse_view(line), single, "{at}");
        check_full(&single, &[4], at);
    }
    // With a range, each line is that point's restricted view.
    let out = ok(&[
        "view",
        paper.to_str().unwrap(),
        "--at-file",
        file.to_str().unwrap(),
        "--from",
        "80",
        "--to",
        "-80",
        "--json",
    ]);
    for (line, at) in out.lines().zip(points) {
        assert_eq!(
            parse_view(line),
            view(&paper, at, &["--from", "80", "--to", "-80"]),
            "{at}"
        );
    }
    // The table: one block per point, separated by blank lines.
    let table = ok(&[
        "view",
        paper.to_str().unwrap(),
        "--at-file",
        file.to_str().unwrap(),
    ]);
    assert_eq!(table.split("\n\n").count(), points.len(), "{table}");
    assert_eq!(
        table.matches(": view from (").count(),
        points.len(),
        "{table}"
    );
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    let paper = temp_file("paper.json", PAPER);
    let s = paper.to_str().unwrap();
    // The viewpoint inside or on an object, screens included.
    let line = fails(&["view", s, "--at", "2.5,0"], &["inside object 0 \"east\""]);
    assert!(line.contains("(2.5, 0)"), "{line}");
    fails(
        &["view", s, "--at", "2,0.5"],
        &["on the boundary of object 0"],
    );
    fails(
        &["view", s, "--at", "2,-1"],
        &["on the boundary of object 0"],
    );
    fails(
        &["view", s, "--at", "2.5,2.5"],
        &["inside object 4 \"glass\""],
    );
    fails(
        &["view", s, "--at", "3,2.5"],
        &["on the boundary of object 4"],
    );
    fails(
        &["view", s, "--at", "-4.5,0", "--json"],
        &["inside object 2"],
    );
    // --depth: a whole number from 0 to 16.
    for d in ["17", "-1", "x", ""] {
        let line = fails(&["view", s, "--at", "0,0", "--depth", d], &[]);
        assert_eq!(
            line,
            format!("error: --depth {d}: the ray-tree depth must be a whole number from 0 to 16")
        );
    }
    // Malformed numbers.
    fails(
        &["view", s, "--at", "1,x"],
        &["--at", "\"x\" is not a number"],
    );
    fails(&["view", s, "--at", "1"], &["--at", "two numbers"]);
    fails(&["view", s, "--at", "1,2,3"], &["--at", "two numbers"]);
    fails(&["view", s, "--at", "nan,0"], &["--at", "not finite"]);
    fails(&["view", s, "--at", "3e7,0"], &["--at", "out of range"]);
    fails(
        &["view", s, "--at", "0,0", "--from", "abc", "--to", "1"],
        &["--from", "\"abc\""],
    );
    fails(
        &["view", s, "--at", "0,0", "--from", "1", "--to", "inf"],
        &["--to", "not finite"],
    );
    fails(
        &["view", s, "--at", "0,0", "--from", "1"],
        &["--from and --to"],
    );
    fails(
        &["view", s, "--at", "0,0", "--to", "1"],
        &["--from and --to"],
    );
    fails(&["view", s], &["--at or --at-file"]);
    // At-files: the bad line's number; a point in an object, with its line; missing file.
    let bad = temp_file("bad.txt", "0,0\n# fine\n\n1,y\n");
    let b = bad.to_str().unwrap();
    fails(
        &["view", s, "--at-file", b],
        &[&format!("{b}:4:"), "\"y\" is not a number"],
    );
    let far = temp_file("far.txt", "0,0\n2e7, 1\n");
    let f = far.to_str().unwrap();
    fails(
        &["view", s, "--at-file", f, "--json"],
        &[&format!("{f}:2:"), "out of range"],
    );
    let inside = temp_file("inside.txt", "0,0\n\n2.5,2.5\n");
    let i = inside.to_str().unwrap();
    fails(
        &["view", s, "--at-file", i],
        &[&format!("{i}:3:"), "inside object 4"],
    );
    fails(
        &["view", s, "--at-file", "/nonexistent/points.txt"],
        &["cannot read"],
    );
    fails(&["view", s, "--at", "0,0", "--at-file", i], &["not both"]);
    // A bad scene file.
    let broken = temp_file("broken.json", "{\"objects\": [");
    fails(
        &["view", broken.to_str().unwrap(), "--at", "0,0"],
        &["broken.json"],
    );
}

/// `--depth D`: branches of at most D + 1 objects, primary first, no screens; the intervals
/// cover the circle once; and each branch starts with what depth 0 sees there.
#[test]
fn ray_trees_extend_the_direct_view() {
    for name in ["hall", "mixed"] {
        let path = example(name);
        let shown = screens(&path);
        let direct = view(&path, "29.5,30.25", &[]);
        for depth in ["1", "3"] {
            let out = ok(&[
                "view",
                path.to_str().unwrap(),
                "--at",
                "29.5,30.25",
                "--json",
                "--depth",
                depth,
            ]);
            let v: Value = serde_json::from_str(out.trim_end()).unwrap();
            let rows = v["intervals"].as_array().unwrap();
            let d: usize = depth.parse().unwrap();
            assert!(rows.len() >= direct.len(), "{name} depth {depth}");
            for (i, r) in rows.iter().enumerate() {
                let p: Vec<u64> = r["path"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_u64().unwrap())
                    .collect();
                assert!(p.len() <= d + 1, "{name}: {r}");
                assert!(
                    p.iter().all(|o| !shown.contains(o)),
                    "{name}: screen in {r}"
                );
                let next = &rows[(i + 1) % rows.len()];
                assert_eq!(r["end"], next["start"], "{name}");
                if rows.len() > 1 {
                    assert_ne!(r["path"], next["path"], "{name}: neighbours");
                }
                // The primary object is what depth 0 sees in the middle of the interval.
                let (s, e) = (r["start"].as_f64().unwrap(), r["end"].as_f64().unwrap());
                let mid = (s + (e - s).rem_euclid(TAU) / 2.0).rem_euclid(TAU);
                let seen = direct
                    .iter()
                    .find(|iv| {
                        (mid - iv.start).rem_euclid(TAU)
                            < (iv.end - iv.start)
                                .rem_euclid(TAU)
                                .max(if direct.len() == 1 { TAU } else { 0.0 })
                    })
                    .map(|iv| iv.path.clone())
                    .unwrap();
                assert_eq!(
                    p.first().copied(),
                    seen.first().copied(),
                    "{name} depth {depth}: {r}"
                );
            }
        }
    }
}
