//! `vcx build --region X0,Y0,X1,Y1`, run as the built binary: the pruned file (version 4)
//! keeps fewer cylinders and is the whole replayed file plus a bit per cylinder, with
//! `--explicit-cylinders` (version 2) smaller than the whole complex stored the same way,
//! `vcx inspect` shows its region and what it keeps, `vcx view` from inside the box prints exactly what the
//! full file prints, from outside it fails with one `error:` line and exit status 2, as do
//! every refused combination (history, a malformed or empty box); ray trees through the
//! mirrors, refractive objects and screens of the mixed example from inside the box equal
//! the full file's; `vcx bench views` draws its viewpoints in the region.

use std::path::{Path, PathBuf};

use serde_json::Value;

mod common;
use common::{example, fails, ok, s, temp_path, vcx};

fn json(text: &str) -> Value {
    serde_json::from_str(text.trim()).unwrap()
}

/// The grid example scene (64 opaque triangles in 0..80 × 0..80), full and pruned to a
/// box of about a sixteenth of its area.
fn files() -> (PathBuf, PathBuf) {
    let scene = example("grid");
    let (full, reg) = (temp_path("full.vcx"), temp_path("region.vcx"));
    ok(&["build", s(&scene), "--method", "sweep", "-o", s(&full)]);
    let line = ok(&["build", s(&scene), "--region", "30,30,50,50", "-o", s(&reg)]);
    assert!(line.contains("region 30,30,50,50: kept"), "{line}");
    (full, reg)
}

#[test]
fn region_file_is_smaller_and_inspect_shows_it() {
    let (full, v4) = files();
    // The default (version 4): the whole complex replayed, as version 3 stores it, plus
    // the region, a vertex count and a bit per cylinder.
    let v3 = temp_path("whole-v3.vcx");
    ok(&["build", s(&example("grid")), "-o", s(&v3)]);
    let (a, b) = (
        std::fs::metadata(&v3).unwrap().len(),
        std::fs::metadata(&v4).unwrap().len(),
    );
    let replayed = json(&ok(&["inspect", s(&v4), "--json"]))["parts"]["complex"]
        ["replayed_cylinders"]
        .as_u64()
        .unwrap();
    assert!(
        b > a + replayed / 8 && b < a + replayed / 8 + 24,
        "{b}, {a}"
    );
    let text = ok(&["inspect", s(&v4)]);
    assert!(text.contains("format version 4"), "{text}");
    assert!(text.contains("cylinders kept"), "{text}");
    assert!(
        text.contains("region   viewpoints in 30,30,50,50 only"),
        "{text}"
    );
    // `vcx check` loads it.
    ok(&["check", s(&v4)]);
    let reg = temp_path("region-v2.vcx");
    ok(&[
        "build",
        s(&example("grid")),
        "--region",
        "30,30,50,50",
        "--explicit-cylinders",
        "-o",
        s(&reg),
    ]);
    assert_eq!(
        json(&ok(&["inspect", s(&v4), "--json"]))["parts"]["complex"]["cylinders"],
        json(&ok(&["inspect", s(&reg), "--json"]))["parts"]["complex"]["cylinders"],
    );
    // Version 2 against the whole complex with every cylinder stored, as it stores its
    // own.
    let explicit = temp_path("explicit.vcx");
    ok(&[
        "build",
        s(&example("grid")),
        "--explicit-cylinders",
        "-o",
        s(&explicit),
    ]);
    let (a, b) = (
        std::fs::metadata(&explicit).unwrap().len(),
        std::fs::metadata(&reg).unwrap().len(),
    );
    assert!(b < a / 2, "{b} bytes pruned, {a} full");
    let cylinders = |p: &PathBuf| {
        json(&ok(&["inspect", s(p), "--json"]))["parts"]["complex"]["cylinders"]
            .as_u64()
            .unwrap()
    };
    assert!(cylinders(&reg) < cylinders(&full) / 2);
    let text = ok(&["inspect", s(&reg)]);
    assert!(text.contains("format version 2"), "{text}");
    assert!(
        text.contains("region   viewpoints in 30,30,50,50 only"),
        "{text}"
    );
    assert!(text.contains("history  absent"), "{text}");
    let v = json(&ok(&["inspect", s(&reg), "--json"]));
    assert_eq!(v["version"], 2);
    assert_eq!(v["region"], serde_json::json!([30.0, 30.0, 50.0, 50.0]));
    let v = json(&ok(&["inspect", s(&full), "--json"]));
    assert_eq!(v["version"], 3);
    let v = json(&ok(&["inspect", s(&explicit), "--json"]));
    assert_eq!(v["version"], 1);
    assert_eq!(v["region"], Value::Null);
    // --stats-json reports both counts.
    let stats = json(&ok(&[
        "build",
        s(&example("grid")),
        "--region",
        "30,30,50,50",
        "--stats-json",
    ]));
    assert!(stats["cylinders"].as_u64().unwrap() < stats["full_cylinders"].as_u64().unwrap());
    assert_eq!(stats["region"], serde_json::json!([30.0, 30.0, 50.0, 50.0]));
}

/// `vcx view --depth D --json` from `at` in files `a` and `b`: the same exit status and,
/// where it succeeds, the same intervals (the file name is in the output); how many.
fn same_views(a: &Path, b: &Path, at: &str, depth: &str) -> usize {
    let run = |f: &Path| vcx(&["view", s(f), "--at", at, "--depth", depth, "--json"]);
    let (a, b) = (run(a), run(b));
    assert_eq!(a.status.code(), b.status.code(), "{at}");
    if a.status.code() != Some(0) {
        return 0;
    }
    let (va, vb) = (
        json(&String::from_utf8(a.stdout).unwrap()),
        json(&String::from_utf8(b.stdout).unwrap()),
    );
    assert_eq!(va["intervals"], vb["intervals"], "{at}");
    let n = va["intervals"].as_array().map_or(0, Vec::len);
    assert!(n > 0, "{at}");
    n
}

#[test]
fn views_inside_equal_the_full_file_and_outside_fail() {
    let (full, reg) = files();
    // Inside, on the edges and at the corners of the box.
    for at in [
        "40.5,40.25",
        "30,30",
        "50,50",
        "30,50",
        "50,30",
        "30,41.125",
        "44.75,50",
        "33.3,47.7",
    ] {
        same_views(&full, &reg, at, "0");
    }
    for at in ["29.99,40", "50.01,40", "40,29.5", "40,60", "0.5,0.5"] {
        fails(
            &["view", s(&reg), "--at", at],
            &["viewpoint", "outside the region 30,30,50,50"],
        );
    }
}

/// The mixed example (mirrors, refractive objects, screens) pruned to a box: depth-5 ray
/// trees from inside print exactly what the JSON scene prints, and the region keeps fewer
/// cylinders; outside, an error.
#[test]
fn ray_trees_inside_equal_the_json_scene() {
    let scene = example("mixed");
    let reg = temp_path("mixed-region.vcx");
    let line = ok(&["build", s(&scene), "--region", "20,20,36,38", "-o", s(&reg)]);
    let kept = line
        .split("kept ")
        .nth(1)
        .and_then(|t| t.split(" cylinders").next())
        .unwrap_or_default()
        .to_string();
    let (k, all) = kept.split_once(" of ").expect(&line);
    assert!(
        k.parse::<u32>().unwrap() < all.parse::<u32>().unwrap(),
        "{line}"
    );
    let mut compared = 0;
    for at in ["20,20", "36,38", "28.5,29.25", "21.75,37.5", "35.9,20.1"] {
        compared += usize::from(same_views(&scene, &reg, at, "5") > 10);
    }
    assert!(compared >= 4, "only {compared} free viewpoints");
    fails(
        &["view", s(&reg), "--at", "19.9,30", "--depth", "5"],
        &["viewpoint", "outside the region 20,20,36,38"],
    );
}

#[test]
fn refused_combinations() {
    let grid = example("grid");
    let out = temp_path("x.vcx");
    fails(
        &[
            "build",
            s(&grid),
            "--region",
            "30,30,50,50",
            "--history",
            "always",
            "-o",
            s(&out),
        ],
        &["--region", "no history"],
    );
    for (bad, why) in [
        ("1,2,3", "3 numbers"),
        ("1,2,3,x", "not four numbers"),
        ("5,0,1,1", "X0 ≤ X1"),
        ("0,0,1,1e9", "outside"),
    ] {
        fails(&["build", s(&grid), "--region", bad], &["--region", why]);
    }
    assert!(!out.exists());
}

#[test]
fn bench_views_draws_points_in_the_region() {
    let (full, reg) = files();
    let a = json(&ok(&[
        "bench",
        "views",
        s(&full),
        "--region",
        "30,30,50,50",
        "--random",
        "20",
        "--repeat",
        "1",
    ]));
    let b = json(&ok(&[
        "bench",
        "views",
        s(&reg),
        "--random",
        "20",
        "--repeat",
        "1",
    ]));
    assert_eq!(a["views"], b["views"]);
    assert_eq!(a["events_per_view"], b["events_per_view"]);
    assert_eq!(a["intervals_per_view"], b["intervals_per_view"]);
    assert!(b["cylinders"].as_u64().unwrap() < a["cylinders"].as_u64().unwrap());
}
