//! `vcx check` and `vcx gen`, run as the built binary: every class of bad input gives exit
//! status 2 and exactly one `error: ` line naming the file and the object (and vertex) at
//! fault; good scenes and generated scenes pass.

use core::sync::atomic::{AtomicUsize, Ordering};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const VCX: &str = env!("CARGO_BIN_EXE_vcx");

/// A fresh file in a per-process temporary directory.
fn temp_path(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!("vcx-cli-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    dir.join(format!("{n}-{name}"))
}

fn temp_file(name: &str, text: &str) -> PathBuf {
    let path = temp_path(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn vcx(args: &[&str]) -> Output {
    Command::new(VCX).args(args).output().unwrap()
}

fn check(path: &Path) -> Output {
    vcx(&["check", path.to_str().unwrap()])
}

/// Runs `vcx check` on `text` and requires exit 2 with one stderr line that names the file
/// and contains every string of `expect`.
fn rejects(name: &str, text: &str, expect: &[&str]) -> String {
    let path = temp_file(&format!("{name}.json"), text);
    let out = check(&path);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
    assert!(out.stdout.is_empty(), "{name}: stdout not empty");
    assert_eq!(stderr.lines().count(), 1, "{name}: {stderr}");
    assert!(stderr.ends_with('\n'), "{name}: {stderr}");
    assert!(stderr.starts_with("error: "), "{name}: {stderr}");
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    assert!(
        stderr.contains(path.to_str().unwrap()),
        "{name}: no file name in {stderr}"
    );
    for e in expect {
        assert!(stderr.contains(e), "{name}: {e:?} not in {stderr}");
    }
    stderr
}

/// A scene file of objects given as `(material fields, vertices)`.
fn scene(objects: &[(&str, &str)]) -> String {
    let list: Vec<String> = objects
        .iter()
        .map(|(m, v)| format!(r#"{{{m}, "vertices": {v}}}"#))
        .collect();
    format!("{{\"objects\": [\n{}\n]}}\n", list.join(",\n"))
}

const OPAQUE: &str = r#""material": "opaque""#;
const FAR_SQUARE: &str = "[[100, 100], [101, 100], [101, 101], [100, 101]]";

/// A valid object 0, then `bad` as object 1.
fn second(material: &str, bad: &str) -> String {
    scene(&[(OPAQUE, FAR_SQUARE), (material, bad)])
}

#[test]
fn invalid_json() {
    rejects("truncated", "{\"objects\": [", &["invalid JSON at line 1"]);
    rejects(
        "syntax-in-vertex",
        "{\"objects\": [\n{\"material\": \"opaque\", \"vertices\": [[0, 0], [1 0], [0, 1]]}]}",
        &["invalid JSON at line 2", "object 0, vertex 1"],
    );
    rejects(
        "nan",
        &second(OPAQUE, "[[0, 0], [NaN, 0], [0, 1]]"),
        &["invalid JSON", "object 1, vertex 1"],
    );
    rejects("empty", "", &["invalid JSON"]);
    let path = temp_path("not-utf8.json");
    std::fs::write(&path, b"{\"objects\": [], \"x\": \"\xff\"}").unwrap();
    let out = check(&path);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&out.stderr).lines().count(), 1);
}

#[test]
fn missing_or_ill_typed_structure() {
    rejects("top-array", "[]", &["top level"]);
    rejects("missing-objects", r#"{"things": []}"#, &["\"objects\""]);
    rejects("objects-not-array", r#"{"objects": 5}"#, &["\"objects\""]);
    rejects("object-not-map", r#"{"objects": [[0, 0]]}"#, &["object 0"]);
    rejects(
        "missing-material",
        &format!(r#"{{"objects": [{{"vertices": {FAR_SQUARE}}}]}}"#),
        &["object 0", "material"],
    );
    rejects(
        "missing-vertices",
        r#"{"objects": [{"material": "opaque"}]}"#,
        &["object 0", "vertices"],
    );
    rejects(
        "vertex-not-pair",
        &second(OPAQUE, "[[0, 0], [1, 0], [1]]"),
        &["object 1, vertex 2"],
    );
    rejects(
        "coordinate-string",
        &second(OPAQUE, r#"[[0, 0], ["1", 0], [1, 1]]"#),
        &["object 1, vertex 1"],
    );
}

#[test]
fn unknown_material() {
    rejects(
        "unknown-material",
        &second(r#""material": "glass""#, "[[0, 0], [1, 0], [0, 1]]"),
        &["object 1", "\"glass\""],
    );
    rejects(
        "material-number",
        &second(r#""material": 3"#, "[[0, 0], [1, 0], [0, 1]]"),
        &["object 1", "material"],
    );
}

#[test]
fn bad_polygons() {
    rejects(
        "two-vertices",
        &second(OPAQUE, "[[0, 0], [1, 0]]"),
        &["object 1"],
    );
    rejects("no-vertices", &second(OPAQUE, "[]"), &["object 1"]);
    rejects(
        "repeated-vertex",
        &second(OPAQUE, "[[0, 0], [1, 0], [1, 0], [0, 1]]"),
        &["object 1, vertex 2"],
    );
    rejects(
        "collinear",
        &second(OPAQUE, "[[0, 0], [1, 0], [2, 0], [2, 2]]"),
        &["object 1, vertex 1"],
    );
    rejects(
        "non-convex",
        &second(OPAQUE, "[[0, 0], [4, 0], [4, 4], [2, 1], [0, 4]]"),
        &["object 1, vertex 3"],
    );
    let pentagon = [
        (0.0, 10.0),
        (9.51, 3.09),
        (5.88, -8.09),
        (-5.88, -8.09),
        (-9.51, 3.09),
    ];
    let star: Vec<String> = [0, 2, 4, 1, 3]
        .iter()
        .map(|&i| format!("[{}, {}]", pentagon[i].0, pentagon[i].1))
        .collect();
    let stderr = rejects(
        "pentagram",
        &second(OPAQUE, &format!("[{}]", star.join(", "))),
        &["object 1"],
    );
    assert!(!stderr.contains("after rounding"), "{stderr}");
}

#[test]
fn bad_coordinates() {
    rejects(
        "overflow",
        &second(OPAQUE, "[[0, 0], [1, 0], [1, 1e999]]"),
        &["object 1, vertex 2", "not finite"],
    );
    rejects(
        "overflow-negative",
        &second(OPAQUE, "[[-1e999, 0], [1, 0], [1, 1]]"),
        &["object 1, vertex 0", "not finite"],
    );
    rejects(
        "out-of-range",
        &second(OPAQUE, "[[0, 0], [20000, 0], [1, 1]]"),
        &["object 1, vertex 1", "20000", "out of range"],
    );
    rejects(
        "out-of-range-y",
        &second(OPAQUE, "[[0, 0], [1, 0], [1, -16384]]"),
        &["object 1, vertex 2", "out of range"],
    );
}

#[test]
fn bad_eta() {
    let tri = "[[0, 0], [1, 0], [0, 1]]";
    rejects(
        "eta-missing",
        &second(r#""material": "refractive""#, tri),
        &["object 1", "eta"],
    );
    for (name, eta) in [
        ("eta-zero", "0"),
        ("eta-negative", "-1.5"),
        ("eta-string", "\"1.5\""),
        ("eta-null", "null"),
        ("eta-huge", "1000"),
        ("eta-tiny", "0.001"),
        ("eta-overflow", "1e999"),
    ] {
        rejects(
            name,
            &second(&format!(r#""material": "refractive", "eta": {eta}"#), tri),
            &["object 1", "eta"],
        );
    }
    rejects(
        "eta-on-mirror",
        &second(r#""material": "mirror", "eta": 1.5"#, tri),
        &["object 1", "eta"],
    );
}

#[test]
fn objects_touch_or_overlap() {
    let square = "[[0, 0], [1, 0], [1, 1], [0, 1]]";
    rejects(
        "touch-edge",
        &scene(&[
            (OPAQUE, square),
            (OPAQUE, "[[1, 0], [2, 0], [2, 1], [1, 1]]"),
        ]),
        &["objects 0 and 1", "touch"],
    );
    rejects(
        "touch-corner",
        &scene(&[
            (OPAQUE, square),
            (OPAQUE, "[[1, 1], [2, 1], [2, 2], [1, 2]]"),
        ]),
        &["objects 0 and 1"],
    );
    rejects(
        "overlap",
        &scene(&[
            (OPAQUE, FAR_SQUARE),
            (OPAQUE, "[[0, 0], [2, 0], [2, 2], [0, 2]]"),
            (OPAQUE, "[[1, 1], [3, 1], [3, 3], [1, 3]]"),
        ]),
        &["objects 1 and 2", "overlap"],
    );
    rejects(
        "nested",
        &scene(&[
            (OPAQUE, "[[0, 0], [10, 0], [10, 10], [0, 10]]"),
            (OPAQUE, "[[4, 4], [5, 4], [5, 5]]"),
        ]),
        &["objects 0 and 1"],
    );
}

#[test]
fn rounding_that_breaks_convexity_is_reported() {
    // Vertex 1 is below the line through its neighbours by 5e-6 < 2^-17: convex as
    // written, collinear on the 2^-16 grid.
    let stderr = rejects(
        "rounding-collinear",
        &second(OPAQUE, "[[0, 0], [1, -0.000005], [2, 0], [1, 1]]"),
        &["object 1, vertex 1", "after rounding", "2^-16"],
    );
    assert!(stderr.contains("object 1"));
    // Apart by 1e-6 as written, touching on the grid.
    rejects(
        "rounding-touch",
        &scene(&[
            (OPAQUE, "[[0, 0], [1, 0], [1, 1], [0, 1]]"),
            (OPAQUE, "[[1.000001, 0], [2, 0], [2, 1], [1.000001, 1]]"),
        ]),
        &["objects 0 and 1", "after rounding"],
    );
    // Rounding a vertex just past its neighbours' line: reflex on the grid.
    rejects(
        "rounding-reflex",
        &second(
            OPAQUE,
            "[[0, 0], [1, -0.000005], [2, -0.0000077], [3, 0], [1, 1]]",
        ),
        &["object 1", "after rounding"],
    );
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn passes(path: &Path) -> String {
    let out = check(path);
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stderr.is_empty());
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    assert!(stdout.contains("grid 2^-16"), "{stdout}");
    stdout
}

#[test]
fn example_scenes_pass() {
    let grid = passes(&scenes_dir().join("grid.json"));
    assert!(
        grid.contains("64 objects (opaque 64, mirror 0, refractive 0, screen 0)"),
        "{grid}"
    );
    assert!(grid.contains("192 vertices"), "{grid}");
    let hall = passes(&scenes_dir().join("hall.json"));
    assert!(hall.contains("16 objects"), "{hall}");
    let mixed = passes(&scenes_dir().join("mixed.json"));
    for m in ["opaque", "mirror", "refractive", "screen"] {
        assert!(!mixed.contains(&format!("{m} 0,")), "{mixed}");
        assert!(!mixed.contains(&format!("{m} 0)")), "{mixed}");
    }
}

#[test]
fn example_scenes_are_what_the_readme_says() {
    let readme = std::fs::read_to_string(scenes_dir().join("README.md")).unwrap();
    for name in ["grid", "hall", "mixed"] {
        let line = readme
            .lines()
            .find(|l| l.contains(&format!("{name}.json")) && l.contains("vcx gen"))
            .unwrap_or_else(|| panic!("README has no command for {name}.json"));
        let start = line.find("vcx gen").unwrap();
        let command = &line[start..];
        let command = command.split('`').next().unwrap();
        let args: Vec<&str> = command
            .split_whitespace()
            .skip(1)
            .take_while(|a| *a != "-o")
            .collect();
        let out = vcx(&args);
        assert_eq!(out.status.code(), Some(0));
        let committed = std::fs::read(scenes_dir().join(format!("{name}.json"))).unwrap();
        assert!(
            out.stdout == committed,
            "{name}.json differs from `{command}`"
        );
    }
}

#[test]
fn generated_scenes_pass() {
    for kind in ["grid", "hall", "mixed"] {
        for n in ["1", "16", "100", "1000"] {
            for seed in ["0", "5"] {
                let path = temp_path(&format!("gen-{kind}-{n}-{seed}.json"));
                let out = vcx(&["gen", kind, n, "--seed", seed, "-o", path.to_str().unwrap()]);
                assert_eq!(out.status.code(), Some(0), "{kind} {n} {seed}");
                assert!(out.stdout.is_empty() && out.stderr.is_empty());
                let summary = passes(&path);
                assert!(!summary.contains("rounded"), "{summary}");
            }
        }
    }
}

#[test]
fn gen_is_deterministic() {
    let a = vcx(&["gen", "mixed", "50", "--seed", "9"]);
    let b = vcx(&["gen", "mixed", "50", "--seed", "9"]);
    let c = vcx(&["gen", "mixed", "50", "--seed", "10"]);
    assert_eq!(a.status.code(), Some(0));
    assert_eq!(a.stdout, b.stdout);
    assert_ne!(a.stdout, c.stdout);
}

#[test]
fn gen_bad_arguments_fail_cleanly() {
    let out = vcx(&["gen", "grid", "10", "-o", "/nonexistent-dir/x/y.json"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: cannot write"), "{stderr}");
    assert_eq!(vcx(&["gen", "grid", "-3"]).status.code(), Some(2));
    assert_eq!(vcx(&["gen", "pyramid", "3"]).status.code(), Some(2));
}

#[test]
fn missing_file() {
    let path = temp_path("does-not-exist.json");
    let out = check(&path);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1);
    assert!(stderr.starts_with("error: cannot read "), "{stderr}");
    assert!(stderr.contains(path.to_str().unwrap()));
}

#[test]
fn round_trip_keeps_coordinates_winding_and_extras() {
    let text = r##"{"title": "round trip", "objects": [
        {"name": "cw box", "color": "#ff0000", "material": "opaque",
         "vertices": [[0, 0], [0, 1.5], [2.1, 1.5], [2, 0]]},
        {"material": "refractive", "eta": 1.45, "vertices": [[5, 0], [6, 0], [5.5, 0.7]],
         "tags": {"glass": true}},
        {"material": "screen", "vertices": [[10, 0], [10, 5], [10.25, 5], [10.25, 0]]}
    ], "camera": [1, 2]}"##;
    let a = vcx_demo::parse(text).unwrap();
    let json = vcx_demo::to_json(&a);
    let b = vcx_demo::parse(&json).unwrap();
    let (sa, sb) = (a.scene.as_ref(), b.scene.as_ref());
    assert_eq!(sa.vertices(), sb.vertices());
    assert_eq!(sa.objects(), sb.objects());
    assert!(sb.objects()[0].was_clockwise());
    assert!(sb.objects()[2].was_clockwise());
    assert!(!sb.objects()[1].was_clockwise());
    assert_eq!(a.top, b.top);
    assert_eq!(b.top["title"], "round trip");
    for (ma, mb) in a.meta.iter().zip(&b.meta) {
        assert_eq!(ma.extra, mb.extra);
    }
    assert_eq!(b.meta[0].extra["color"], "#ff0000");
    // Vertex order as written: the first vertex of each object comes first again.
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(
        v["objects"][0]["vertices"][1],
        serde_json::json!([0.0, 1.5])
    );
    assert_eq!(
        v["objects"][2]["vertices"][1],
        serde_json::json!([10.0, 5.0])
    );
    // The example scenes are written exactly as they are read.
    for name in ["grid", "hall", "mixed"] {
        let text = std::fs::read_to_string(scenes_dir().join(format!("{name}.json"))).unwrap();
        assert_eq!(vcx_demo::to_json(&vcx_demo::parse(&text).unwrap()), text);
    }
}
