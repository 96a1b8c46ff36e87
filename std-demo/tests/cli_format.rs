//! The binary complex format on the command line, run as the built binary: `vcx build
//! SCENE.json -o FILE.vcx`, `vcx inspect FILE.vcx [--json]`, every scene-taking command
//! (check, view, locate, bench views, demo) on a `.vcx` file giving the same answers as on
//! the JSON scene, and corrupt files — truncated, a bit flipped, an unknown version, not a
//! complex at all — giving exit status 2 and one `error:` line naming the byte offset.

use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::Value;

mod common;
use common::{example, fails, s, temp_path, vcx};

fn stdout(out: &Output) -> String {
    assert!(
        out.status.success(),
        "exit {:?}: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout.clone()).unwrap()
}

/// `vcx build SCENE -o FILE.vcx`; returns the file.
fn build(scene: &Path, extra: &[&str]) -> PathBuf {
    let file = temp_path(&format!(
        "{}.vcx",
        scene.file_stem().unwrap().to_str().unwrap()
    ));
    let mut args = vec!["build", s(scene), "-o", s(&file)];
    args.extend_from_slice(extra);
    let text = stdout(&vcx(&args));
    assert!(text.contains("; wrote "), "{text}");
    assert_eq!(text.lines().count(), 1, "{text}");
    file
}

/// The command must fail with exit 2 and one `error:` line naming the file and containing
/// every string of `expect`.
fn rejects(args: &[&str], file: &Path, expect: &[&str]) {
    let stderr = fails(args, expect);
    assert!(
        stderr.contains(s(file)),
        "{args:?}: no file name in {stderr}"
    );
}

#[test]
fn build_writes_and_inspect_reads() {
    let scene = example("grid");
    let file = build(&scene, &["--seed", "5"]);
    let len = std::fs::metadata(&file).unwrap().len();
    let text = stdout(&vcx(&["inspect", s(&file)]));
    // Without history: version 3, only the cylinders at θ = 0 stored.
    assert!(text.contains("vcx complex format version 3"), "{text}");
    assert!(text.contains("seed 5"), "{text}");
    for part in ["header", "scene", "complex", "history  absent", "checksum"] {
        assert!(text.contains(part), "{part}: {text}");
    }
    let j: Value = serde_json::from_str(&stdout(&vcx(&["inspect", s(&file), "--json"]))).unwrap();
    assert_eq!(j["version"], 3);
    assert_eq!(
        j["parts"]["complex"]["stored_cylinders"].as_u64(),
        Some(3 * 64 + 1)
    );
    assert_eq!(j["bytes"].as_u64(), Some(len));
    assert_eq!(j["seed"], 5);
    assert_eq!(j["parts"]["scene"]["objects"], 64);
    assert!(j["parts"]["history"].is_null());
    let parts = &j["parts"];
    let sum: u64 = ["header", "scene", "complex", "checksum"]
        .iter()
        .map(|p| parts[p]["bytes"].as_u64().unwrap())
        .sum();
    assert_eq!(sum, len);
    // The counts agree with the build's own statistics.
    let stats: Value = serde_json::from_str(&stdout(&vcx(&[
        "build",
        s(&scene),
        "--stats-json",
        "--method",
        "sweep",
    ])))
    .unwrap();
    assert_eq!(parts["complex"]["cylinders"], stats["cylinders"]);
    assert_eq!(parts["complex"]["vertices"], stats["complex_vertices"]);
    // `--stats-json` reports the file size.
    let out = temp_path("grid2.vcx");
    let stats: Value = serde_json::from_str(&stdout(&vcx(&[
        "build",
        s(&scene),
        "--stats-json",
        "-o",
        s(&out),
    ])))
    .unwrap();
    assert_eq!(
        stats["file_bytes"].as_u64(),
        Some(std::fs::metadata(&out).unwrap().len())
    );
}

#[test]
fn check_accepts_vcx() {
    let scene = example("mixed");
    let file = build(&scene, &[]);
    let json = stdout(&vcx(&["check", s(&scene)]));
    let bin = stdout(&vcx(&["check", s(&file)]));
    // Same summary after the file name, plus the complex.
    let tail = |t: &str, p: &Path| t.trim_end().strip_prefix(s(p)).unwrap().to_string();
    let (tj, tb) = (tail(&json, &scene), tail(&bin, &file));
    assert!(tb.starts_with(&tj), "{tj}\n{tb}");
    assert!(tb.contains("cylinders (validated)"), "{tb}");
}

/// `vcx view` (depth 0 and ray trees) and `vcx locate` answer the same from the `.vcx`
/// file as from the JSON scene (JSON output: no file names).
#[test]
fn view_and_locate_agree_with_json() {
    for (name, at, depth) in [
        ("grid", "0.5,0.5", "0"),
        ("hall", "29.5,30.25", "3"),
        ("mixed", "1.5,2.5", "0"),
        ("mixed", "1.5,2.5", "2"),
    ] {
        let scene = example(name);
        let file = build(&scene, &[]);
        let run = |p: &Path| vcx(&["view", s(p), "--at", at, "--depth", depth, "--json"]);
        let (a, b) = (run(&scene), run(&file));
        assert_eq!(a.status.code(), b.status.code(), "{name} {at}");
        assert_eq!(a.stdout, b.stdout, "{name} {at} depth {depth}");
        assert_eq!(
            String::from_utf8_lossy(&a.stderr).replace(s(&scene), "F"),
            String::from_utf8_lossy(&b.stderr).replace(s(&file), "F"),
        );
        for dir in ["1,0", "0.3,-1", "-1,0.2"] {
            let run = |p: &Path| vcx(&["locate", s(p), "--at", at, "--dir", dir, "--json"]);
            let (a, b) = (run(&scene), run(&file));
            assert_eq!(a.status.code(), b.status.code(), "{name} {at} {dir}");
            assert_eq!(a.stdout, b.stdout, "{name} {at} {dir}");
        }
    }
}

#[test]
fn bench_views_and_demo_accept_vcx() {
    let scene = example("hall");
    let file = build(&scene, &[]);
    let bench = |p: &Path| -> Value {
        let args = ["bench", "views", s(p), "--random", "5", "--repeat", "1"];
        serde_json::from_str(&stdout(&vcx(&args))).unwrap()
    };
    let j = bench(&file);
    assert_eq!(j["objects"], 16);
    let cylinders = bench(&scene)["cylinders"].clone();
    assert_eq!(bench(&file)["cylinders"], cylinders);
    let demo = |p: &Path| {
        stdout(&vcx(&[
            "demo",
            s(p),
            "--circuit",
            "--frames",
            "3",
            "--headless",
            "--per-frame",
        ]))
    };
    let (a, b) = (demo(&scene), demo(&file));
    // The same frames; only the scene name and timings may differ.
    let frames = |t: &str| -> Vec<Value> {
        let v: Value = serde_json::from_str(t.trim()).unwrap();
        v["per_frame"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["view"].clone())
            .collect()
    };
    let (fa, fb) = (frames(&a), frames(&b));
    assert_eq!(fa.len(), 3);
    assert!(fa
        .iter()
        .all(|v| v.as_array().is_some_and(|v| !v.is_empty())));
    assert_eq!(fa, fb);
}

/// Every corruption class gives exit 2 and one line naming where, for every command.
#[test]
fn corrupt_files_are_one_line_errors() {
    let scene = example("hall");
    let file = build(&scene, &[]);
    let good = std::fs::read(&file).unwrap();
    let commands = |p: &Path| -> Vec<Vec<String>> {
        let p = s(p).to_string();
        vec![
            vec!["check".into(), p.clone()],
            vec!["inspect".into(), p.clone()],
            vec!["view".into(), p.clone(), "--at".into(), "29.5,30.25".into()],
            vec![
                "locate".into(),
                p.clone(),
                "--at".into(),
                "29.5,30.25".into(),
                "--dir".into(),
                "1,0".into(),
            ],
            vec!["build".into(), p.clone()],
            vec![
                "bench".into(),
                "views".into(),
                p.clone(),
                "--random".into(),
                "2".into(),
            ],
            vec![
                "demo".into(),
                p,
                "--frames".into(),
                "1".into(),
                "--headless".into(),
            ],
        ]
    };
    let write = |name: &str, bytes: &[u8]| {
        let p = temp_path(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    // A bit flipped in the complex part: the checksum names its offset.
    let mut flipped = good.clone();
    flipped[good.len() / 2] ^= 0x10;
    let p = write("flipped.vcx", &flipped);
    for c in commands(&p) {
        let args: Vec<&str> = c.iter().map(String::as_str).collect();
        rejects(
            &args,
            &p,
            &["checksum mismatch", &format!("byte {}", good.len() - 4)],
        );
    }
    // Truncated.
    let p = write("truncated.vcx", &good[..good.len() - 7]);
    rejects(
        &["inspect", s(&p)],
        &p,
        &["truncated", &format!("{} bytes", good.len() - 7)],
    );
    rejects(&["view", s(&p), "--at", "1,1"], &p, &["truncated"]);
    let p = write("short.vcx", &good[..3]);
    rejects(&["check", s(&p)], &p, &["3 bytes"]);
    // An unknown version (2 and 4 are the region formats of `vcx build --region`, 3 the
    // default).
    let mut v5 = good.clone();
    v5[4] = 5;
    let p = write("v5.vcx", &v5);
    rejects(
        &["check", s(&p)],
        &p,
        &["format version 5", "byte 4", "supports versions 1 to 4"],
    );
    // A `.vcx` file that is not one.
    let p = write("json.vcx", b"{\"objects\": []}");
    rejects(&["check", s(&p)], &p, &["bad magic", "byte 0"]);
    // An id out of range with a valid checksum: a neighbour of cylinder 0 inflated.
    // (The structure is the format's: header 56 bytes, scene part, then the complex part
    // with 2 varints per vertex and 8 per cylinder; see docs/format.md.)
    let scene_bytes = u32::from_le_bytes(good[44..48].try_into().unwrap()) as usize;
    let vertices = u32::from_le_bytes(good[20..24].try_into().unwrap()) as usize;
    let mut pos = 56 + scene_bytes;
    let mut skipped = 0;
    while skipped < 2 * vertices + 6 {
        if good[pos] & 0x80 == 0 {
            skipped += 1;
        }
        pos += 1;
    }
    // Field 7 of cylinder 0 (left_neighbour), one byte if small: make it 127 → id 126 or
    // out of range; replace with a 3-byte varint of a huge id and fix lengths and checksum.
    let mut bad = good[..pos].to_vec();
    let mut end = pos;
    while good[end] & 0x80 != 0 {
        end += 1;
    }
    bad.extend_from_slice(&[0xff, 0xff, 0x03]); // 65535 → id 65534
    bad.extend_from_slice(&good[end + 1..good.len() - 4]);
    let grown = bad.len() + 4 - good.len();
    let complex_bytes = u32::from_le_bytes(good[48..52].try_into().unwrap()) + grown as u32;
    bad[48..52].copy_from_slice(&complex_bytes.to_le_bytes());
    let crc = vcx::format::crc32(&bad);
    bad.extend_from_slice(&crc.to_le_bytes());
    let p = write("id.vcx", &bad);
    rejects(
        &["check", s(&p)],
        &p,
        &[
            "cylinder 0: left_neighbour 65534 out of range",
            &format!("(byte {pos})"),
        ],
    );
}

/// `--history`: `always` writes the history part (inspect shows its bytes, nodes, links
/// and depth; locate on the file answers as on the JSON scene, from the stored history);
/// `never` and `auto` on an all-opaque scene write none; `auto` with mirrors writes one;
/// `always` with the sweep is refused.
#[test]
fn build_with_history() {
    let grid = example("grid");
    let file = build(&grid, &["--history", "always"]);
    let j: Value = serde_json::from_str(&stdout(&vcx(&["inspect", s(&file), "--json"]))).unwrap();
    let h = &j["parts"]["history"];
    assert!(h.is_object(), "{j}");
    assert!(h["bytes"].as_u64().unwrap() > 0, "{j}");
    assert!(h["nodes"].as_u64().unwrap() > j["parts"]["complex"]["cylinders"].as_u64().unwrap());
    assert!(h["links"].as_u64().unwrap() >= h["nodes"].as_u64().unwrap() - 1);
    assert!(h["depth"].as_u64().unwrap() > 0, "{j}");
    assert_eq!(j["compacted"], true);
    let sum: u64 = ["header", "scene", "complex", "history", "checksum"]
        .iter()
        .map(|p| j["parts"][p]["bytes"].as_u64().unwrap())
        .sum();
    assert_eq!(sum, std::fs::metadata(&file).unwrap().len());
    let text = stdout(&vcx(&["inspect", s(&file)]));
    assert!(
        text.contains(" nodes, ") && text.contains("depth"),
        "{text}"
    );
    // The history counts agree with the build's own statistics (same seed, 0).
    let stats: Value =
        serde_json::from_str(&stdout(&vcx(&["build", s(&grid), "--stats-json"]))).unwrap();
    assert_eq!(h["nodes"], stats["history_nodes"]);
    assert_eq!(h["links"], stats["history_links"]);
    assert_eq!(h["depth"], stats["history_depth"]);
    for (at, dir) in [
        ("0.5,0.5", "1,0"),
        ("0.5,0.5", "0.3,-1"),
        ("3.25,1.5", "-1,0.2"),
    ] {
        let run = |p: &Path| vcx(&["locate", s(p), "--at", at, "--dir", dir, "--json"]);
        let (a, b) = (run(&grid), run(&file));
        assert_eq!(a.status.code(), b.status.code(), "{at} {dir}");
        assert_eq!(a.stdout, b.stdout, "{at} {dir}");
        let text = |p: &Path| vcx(&["locate", s(p), "--at", at, "--dir", dir]);
        assert_eq!(
            String::from_utf8_lossy(&text(&grid).stdout).replace(s(&grid), "F"),
            String::from_utf8_lossy(&text(&file).stdout).replace(s(&file), "F"),
        );
    }
    // never / auto.
    let history = |f: &Path| -> Value {
        let j: Value = serde_json::from_str(&stdout(&vcx(&["inspect", s(f), "--json"]))).unwrap();
        j["parts"]["history"].clone()
    };
    assert!(history(&build(&grid, &["--history", "never"])).is_null());
    assert!(history(&build(&grid, &[])).is_null(), "grid is all opaque");
    let mixed = example("mixed");
    assert!(
        history(&build(&mixed, &[])).is_object(),
        "mixed has mirrors"
    );
    assert!(history(&build(&mixed, &["--history", "never"])).is_null());
    assert!(history(&build(&mixed, &["--method", "sweep"])).is_null());
    let out = temp_path("refused.vcx");
    let o = vcx(&[
        "build",
        s(&mixed),
        "--method",
        "sweep",
        "--history",
        "always",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--history always"));
    // A corrupt history part is one error line naming the history part.
    let good = std::fs::read(&file).unwrap();
    let h = vcx::format::Header::read(&good).unwrap();
    let at = h.part_range(vcx::format::Part::History).start;
    let mut bad = good.clone();
    // The vertex count prefix made huge (a 5-byte varint in place of the original).
    let mut n = 0;
    while good[at + n] & 0x80 != 0 {
        n += 1;
    }
    bad.splice(at..at + n + 1, [0xff, 0xff, 0xff, 0xff, 0x0f]);
    let hb = h.history_bytes + 4 - n as u32;
    bad[52..56].copy_from_slice(&hb.to_le_bytes());
    let len = bad.len() - 4;
    let crc = vcx::format::crc32(&bad[..len]);
    bad[len..].copy_from_slice(&crc.to_le_bytes());
    let p = temp_path("bad-history.vcx");
    std::fs::write(&p, &bad).unwrap();
    rejects(
        &["locate", s(&p), "--at", "0.5,0.5", "--dir", "1,0"],
        &p,
        &["history part", "history_vertices", &format!("byte {at}")],
    );
}
