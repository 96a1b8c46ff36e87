//! `vcx build` and `vcx locate`, run as the built binary: the statistics are consistent on
//! the example scenes and on hand-made ones, locate answers what is worked out on paper,
//! and every bad input gives exit status 2 and exactly one `error: ` line.

use core::sync::atomic::{AtomicUsize, Ordering};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

const VCX: &str = env!("CARGO_BIN_EXE_vcx");

/// The keys of `vcx build --stats-json`, in order.
const STATS_KEYS: [&str; 10] = [
    "objects",
    "free_bitangents",
    "complex_vertices",
    "faces",
    "cylinders",
    "build_seconds",
    "method",
    "history_nodes",
    "history_links",
    "history_depth",
];

/// A fresh file in a per-process temporary directory.
fn temp_file(name: &str, text: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!("vcx-cli-build-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let path = dir.join(format!("{n}-{name}"));
    std::fs::write(&path, text).unwrap();
    path
}

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.json"))
}

fn vcx(args: &[&str]) -> Output {
    Command::new(VCX).args(args).output().unwrap()
}

/// Requires exit 0, empty stderr and exactly one line on stdout; returns it.
fn one_line_ok(args: &[&str]) -> String {
    let out = vcx(args);
    let stdout = String::from_utf8(out.stdout).unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
    assert!(stderr.is_empty(), "{args:?}: {stderr}");
    assert_eq!(stdout.lines().count(), 1, "{args:?}: {stdout}");
    assert!(stdout.ends_with('\n'), "{args:?}: {stdout}");
    stdout.trim_end().to_string()
}

/// Requires exit 2, empty stdout and one `error: ` line containing every string of
/// `expect`; returns the line.
fn fails(args: &[&str], expect: &[&str]) -> String {
    let out = vcx(args);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(out.stdout.is_empty(), "{args:?}: stdout not empty");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
    assert!(stderr.ends_with('\n'), "{args:?}: {stderr}");
    assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    for e in expect {
        assert!(stderr.contains(e), "{args:?}: {e:?} not in {stderr}");
    }
    stderr
}

/// `vcx build --stats-json` on a file, by both methods: every key, in order; both give
/// the same (canonical) complex; the parsed object of the randomized construction.
fn stats(path: &Path) -> serde_json::Map<String, Value> {
    let line = one_line_ok(&["build", path.to_str().unwrap(), "--stats-json"]);
    let value: Value = serde_json::from_str(&line).unwrap();
    let object = value.as_object().unwrap().clone();
    let keys: Vec<&str> = object.keys().map(String::as_str).collect();
    assert_eq!(keys, STATS_KEYS, "{line}");
    assert_eq!(object["method"], "ric");
    for key in ["history_nodes", "history_links", "history_depth"] {
        assert!(object[key].is_u64(), "{key}: {line}");
    }
    assert!(
        object["history_nodes"].as_u64() >= object["cylinders"].as_u64(),
        "{line}"
    );
    let sweep = one_line_ok(&[
        "build",
        path.to_str().unwrap(),
        "--stats-json",
        "--method",
        "sweep",
    ]);
    let sweep: Value = serde_json::from_str(&sweep).unwrap();
    assert!(
        sweep["history_nodes"].is_null()
            && sweep["history"].as_str().unwrap().starts_with("not built")
    );
    for key in ["free_bitangents", "complex_vertices", "faces", "cylinders"] {
        assert_eq!(
            sweep[key], object[key],
            "{key}: sweep and randomized construction differ"
        );
    }
    let seconds = object["build_seconds"].as_f64().unwrap();
    assert!(seconds.is_finite() && seconds >= 0.0, "{line}");
    object
}

fn count(stats: &serde_json::Map<String, Value>, key: &str) -> u64 {
    stats[key]
        .as_u64()
        .unwrap_or_else(|| panic!("{key}: {stats:?}"))
}

/// The counts satisfy `cylinders = 3n + 1 + 3V` and `V = 2B`.
fn check_counts(stats: &serde_json::Map<String, Value>) {
    let n = count(stats, "objects");
    let b = count(stats, "free_bitangents");
    let v = count(stats, "complex_vertices");
    let c = count(stats, "cylinders");
    assert_eq!(c, 3 * n + 1 + 3 * v, "{stats:?}");
    assert_eq!(v, 2 * b, "{stats:?}");
    assert!(count(stats, "faces") >= 1, "{stats:?}");
}

/// A scene file of opaque objects given by their vertex lists.
fn scene(objects: &[&str]) -> String {
    let list: Vec<String> = objects
        .iter()
        .map(|v| format!(r#"{{"material": "opaque", "vertices": {v}}}"#))
        .collect();
    format!("{{\"objects\": [\n{}\n]}}\n", list.join(",\n"))
}

#[test]
fn stats_on_the_example_scenes() {
    for (name, objects) in [("grid", 64), ("hall", 16), ("mixed", 30)] {
        let s = stats(&example(name));
        assert_eq!(count(&s, "objects"), objects, "{name}");
        assert!(count(&s, "free_bitangents") > 0, "{name}");
        check_counts(&s);
    }
}

#[test]
fn summary_is_one_line() {
    let path = example("hall");
    let line = one_line_ok(&["build", path.to_str().unwrap()]);
    assert!(line.starts_with(path.to_str().unwrap()), "{line}");
    for part in [
        "16 objects",
        "free bitangents",
        "cylinders",
        "randomized incremental, history",
    ] {
        assert!(line.contains(part), "{part:?} not in {line}");
    }
}

#[test]
fn two_triangles_have_four_free_bitangents() {
    // In general position, and with the bases on one line (a degenerate common tangent).
    for (name, a, b) in [
        (
            "general",
            "[[0, 0], [2, 0.5], [1, 2]]",
            "[[5, 0.25], [7, 0], [6, 3]]",
        ),
        (
            "collinear-bases",
            "[[0, 0], [2, 0], [1, 2]]",
            "[[5, 0], [7, 0], [6, 2]]",
        ),
    ] {
        let path = temp_file(&format!("{name}.json"), &scene(&[a, b]));
        let s = stats(&path);
        assert_eq!(count(&s, "objects"), 2, "{name}");
        assert_eq!(count(&s, "free_bitangents"), 4, "{name}: {s:?}");
        check_counts(&s);
    }
}

#[test]
fn a_single_object_and_an_empty_scene() {
    let one = temp_file("one.json", &scene(&["[[0, 0], [1, 0], [0, 1]]"]));
    let s = stats(&one);
    assert_eq!(count(&s, "free_bitangents"), 0);
    assert_eq!(count(&s, "cylinders"), 4);
    let empty = temp_file("empty.json", "{\"objects\": []}");
    let s = stats(&empty);
    assert_eq!(count(&s, "objects"), 0);
    assert_eq!(count(&s, "cylinders"), 1);
    // From anywhere in an empty scene, nothing ahead and nothing behind.
    let answer = locate(&empty, "3,4", "1,-1");
    assert_eq!((answer.0, answer.1), (None, None));
}

/// Boxes 0 and 1 left and right of the origin, box 2 further right:
///
/// ```text
///   y=1  +---+       +---+   +-+
///        | 0 |   o   | 1 |   |2|
///   y=-1 +---+       +---+   +-+
///       -3  -1   0   1   3   5 6
/// ```
fn three_boxes() -> PathBuf {
    temp_file(
        "boxes.json",
        &scene(&[
            "[[-3, -1], [-1, -1], [-1, 1], [-3, 1]]",
            "[[1, -1], [3, -1], [3, 1], [1, 1]]",
            "[[5, -1], [6, -1], [6, 1], [5, 1]]",
        ]),
    )
}

/// `vcx locate --json`: (forward, backward, cylinder).
fn locate(path: &Path, at: &str, dir: &str) -> (Option<u64>, Option<u64>, u64) {
    let at = format!("--at={at}");
    let dir = format!("--dir={dir}");
    let line = one_line_ok(&["locate", path.to_str().unwrap(), &at, &dir, "--json"]);
    let value: Value = serde_json::from_str(&line).unwrap();
    let object = value.as_object().unwrap();
    let keys: Vec<&str> = object.keys().map(String::as_str).collect();
    assert_eq!(keys, ["forward", "backward", "cylinder"], "{line}");
    let id = |key: &str| match &object[key] {
        Value::Null => None,
        v => Some(v.as_u64().unwrap()),
    };
    (
        id("forward"),
        id("backward"),
        object["cylinder"].as_u64().unwrap(),
    )
}

#[test]
fn locate_agrees_with_paper() {
    let path = three_boxes();
    let fb = |at: &str, dir: &str| {
        let (f, b, _) = locate(&path, at, dir);
        (f, b)
    };
    // From the origin: box 1 ahead looking +x (box 2 is hidden), box 0 behind.
    assert_eq!(fb("0,0", "1,0"), (Some(1), Some(0)));
    assert_eq!(fb("0,0", "-1,0"), (Some(0), Some(1)));
    // Only the direction matters, exactly: 0.5,0 and 1e-3,0 are +x too.
    assert_eq!(fb("0,0", "0.5,0"), (Some(1), Some(0)));
    assert_eq!(fb("0,0", "1e-3,0"), (Some(1), Some(0)));
    // Up or down: nothing either way.
    assert_eq!(fb("0,0", "0,1"), (None, None));
    assert_eq!(fb("0,0", "0,-7"), (None, None));
    // From (0, 0.5) with slope 0.1: hits box 1 at y = 0.6, box 0 behind at y = 0.4.
    assert_eq!(fb("0,0.5", "1,0.1"), (Some(1), Some(0)));
    // Slope 1: passes over box 1 (y = 1.5 at x = 1), box 0 behind (y = -0.5 at x = -1).
    assert_eq!(fb("0,0.5", "1,1"), (None, Some(0)));
    // Between boxes 1 and 2.
    assert_eq!(fb("4,0", "1,0"), (Some(2), Some(1)));
    assert_eq!(fb("4,0", "-1,0"), (Some(1), Some(2)));
    // Outside everything.
    assert_eq!(fb("10,0", "1,0"), (None, Some(2)));
    assert_eq!(fb("10,0", "-1,0"), (Some(2), None));
    assert_eq!(fb("-5,0.25", "1,0"), (Some(0), None));
    // The same ray from two points of it lies in the same cylinder.
    assert_eq!(
        locate(&path, "0,0", "1,0").2,
        locate(&path, "0.5,0", "1,0").2
    );
}

#[test]
fn locate_summary_and_negative_values() {
    let path = three_boxes();
    let p = path.to_str().unwrap();
    // Negative values after a space, not only after `=`.
    let line = one_line_ok(&["locate", p, "--at", "-5,0", "--dir", "-1,0"]);
    assert!(
        line.contains("forward nothing, backward object 0"),
        "{line}"
    );
    let line = one_line_ok(&["locate", p, "--at", "0,0", "--dir", "1,0"]);
    assert!(
        line.contains("forward object 1, backward object 0"),
        "{line}"
    );
    // A direction with exponents far apart is rounded, and says so.
    let line = one_line_ok(&["locate", p, "--at", "0,0", "--dir", "1,1e-300"]);
    assert!(line.contains("rounded"), "{line}");
    assert!(line.contains("forward object 1"), "{line}");
}

#[test]
fn locate_in_or_on_an_object() {
    let path = three_boxes();
    let p = path.to_str().unwrap();
    fails(
        &["locate", p, "--at", "2,0", "--dir", "1,0"],
        &[p, "point (2, 0) is inside object 1"],
    );
    fails(
        &["locate", p, "--at", "5.5,0.5", "--dir", "0,1", "--json"],
        &["is inside object 2"],
    );
    fails(
        &["locate", p, "--at", "-1,0", "--dir", "1,0"],
        &[p, "point (-1, 0) is on the boundary of object 0"],
    );
    fails(
        &["locate", p, "--at", "3,1", "--dir", "1,0"],
        &["is on the boundary of object 1"],
    );
}

#[test]
fn locate_bad_arguments() {
    let path = three_boxes();
    let p = path.to_str().unwrap();
    let cases: &[(&str, &str, &[&str])] = &[
        ("0,0", "0,0", &["--dir", "zero vector"]),
        ("0,0", "-0,0.0", &["--dir", "zero vector"]),
        ("abc,0", "1,0", &["--at", "\"abc\" is not a number"]),
        ("0,0", "1,x", &["--dir", "\"x\" is not a number"]),
        ("0", "1,0", &["--at", "two numbers"]),
        ("0,0", "1,2,3", &["--dir", "two numbers"]),
        ("", "1,0", &["--at", "two numbers"]),
        ("0,0", ",", &["--dir", "not a number"]),
        ("nan,0", "1,0", &["--at", "not finite"]),
        ("0,0", "inf,1", &["--dir", "not finite"]),
        ("2e6,0", "1,0", &["--at", "out of range"]),
        ("0,-1e300", "1,0", &["--at", "out of range"]),
        ("0,0", "1e999,0", &["--dir", "not finite"]),
    ];
    for (at, dir, expect) in cases {
        let at = format!("--at={at}");
        let dir = format!("--dir={dir}");
        fails(&["locate", p, &at, &dir], expect);
        fails(&["locate", p, &at, &dir, "--json"], expect);
    }
}

#[test]
fn bad_scene_files() {
    let missing = std::env::temp_dir().join("vcx-cli-build-no-such-file.json");
    let m = missing.to_str().unwrap();
    fails(&["build", m], &[m]);
    fails(&["build", m, "--stats-json"], &[m]);
    fails(&["locate", m, "--at", "0,0", "--dir", "1,0"], &[m]);
    let bad = temp_file("bad.json", "{\"objects\": [");
    let b = bad.to_str().unwrap();
    fails(&["build", b], &[b, "invalid JSON"]);
    fails(
        &["locate", b, "--at", "0,0", "--dir", "1,0"],
        &[b, "invalid JSON"],
    );
}

/// `vcx build --no-compaction` (search path compaction off, §4.4): the same complex and a
/// larger history (the mixed scene has insertions that both split and merge), reported
/// by `--stats-json` with `"compaction": false` and written with the compacted flag clear,
/// which `vcx inspect --json` (a full decode) reads back with the same node count; with
/// `--method sweep` (no history) it is an error.
#[test]
fn no_compaction_builds_a_larger_history_of_the_same_complex() {
    let path = example("mixed");
    let p = path.to_str().unwrap();
    let dir = std::env::temp_dir().join(format!("vcx-cli-build-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let (a, b) = (out("compacted.vcx"), out("uncompacted.vcx"));
    let parse = |line: String| -> Value { serde_json::from_str(&line).unwrap() };
    let with = parse(one_line_ok(&[
        "build",
        p,
        "--stats-json",
        "--history",
        "always",
        "-o",
        &a,
    ]));
    let without = parse(one_line_ok(&[
        "build",
        p,
        "--stats-json",
        "--history",
        "always",
        "--no-compaction",
        "-o",
        &b,
    ]));
    assert!(with.get("compaction").is_none(), "{with}");
    assert_eq!(without["compaction"], false, "{without}");
    for key in ["free_bitangents", "complex_vertices", "faces", "cylinders"] {
        assert_eq!(with[key], without[key], "{key}");
    }
    for key in ["history_nodes", "history_links"] {
        assert!(
            without[key].as_u64() > with[key].as_u64(),
            "{key}: {with} {without}"
        );
    }
    assert!(without["history_depth"].as_u64() >= with["history_depth"].as_u64());
    for (file, stats, compacted) in [(&a, &with, true), (&b, &without, false)] {
        let info = parse(one_line_ok(&["inspect", file, "--json"]));
        assert_eq!(info["compacted"], compacted, "{info}");
        assert_eq!(
            info["parts"]["history"]["nodes"], stats["history_nodes"],
            "{info}"
        );
    }
    let line = one_line_ok(&["build", p, "--no-compaction"]);
    assert!(line.contains(", uncompacted)"), "{line}");
    fails(
        &["build", p, "--method", "sweep", "--no-compaction"],
        &["--no-compaction"],
    );
}
