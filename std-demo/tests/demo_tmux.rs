//! `vcx demo`, driven as a person would: in a detached tmux session of fixed size, keys
//! sent with `send-keys`, the screen read with `capture-pane`. Checked: the three panes and
//! a status line with a non-zero frame rate, the view changing after a turn, `q` leaving a
//! restored terminal (no alternate screen, cursor shown, canonical mode back), a panic
//! also restoring it, a tiny terminal and a resize, a scene that fails to load, `+` going
//! to depth 1 (the status line says so and, in the hall of mirrors, the view changes).
//!
//! The tmux tests SKIP (with a message on stderr) when `tmux` is not installed. The
//! headless tests need no terminal: the JSON statistics, and every frame's view against
//! `vcx::walk::view` (and `vcx view`) at the same viewpoints, and at depth 3 every
//! frame's ray tree against `vcx view --depth 3`.

use core::sync::atomic::{AtomicUsize, Ordering};
use core::time::Duration;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Instant;

use serde_json::Value;
use vcx::{Material, ObjectId, QueryPoint};

const VCX: &str = env!("CARGO_BIN_EXE_vcx");

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.json"))
}

/// A fresh file in a per-process temporary directory.
fn temp_file(name: &str, text: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!("vcx-demo-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let path = dir.join(format!("{n}-{name}"));
    std::fs::write(&path, text).unwrap();
    path
}

fn vcx(args: &[&str]) -> Output {
    Command::new(VCX).args(args).output().unwrap()
}

/// Runs `vcx demo ARGS --headless`, requires success, parses the JSON line.
fn headless(args: &[&str]) -> Value {
    let mut all = vec!["demo"];
    all.extend_from_slice(args);
    all.push("--headless");
    let out = vcx(&all);
    let stdout = String::from_utf8(out.stdout).unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(0), "{all:?}: {stderr}");
    assert!(stderr.is_empty(), "{stderr}");
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    serde_json::from_str(&stdout).unwrap()
}

/// Requires exit 2, nothing on stdout and one `error: ` line containing every `needle`.
fn fails(args: &[&str], needles: &[&str]) {
    let out = vcx(args);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(out.stdout.is_empty());
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "{stderr:?} lacks {n:?}");
    }
}

// ----- headless -----

#[test]
fn headless_statistics() {
    let v = headless(&["--frames", "40"]);
    assert_eq!(v["frames"], 40);
    assert_eq!(v["objects"], 64);
    assert_eq!(v["depth"], 0);
    assert_eq!(v["trajectory"], "circuit");
    assert_eq!(v["screens_in_complex"], false);
    for key in [
        "view_us_mean",
        "view_us_median",
        "view_us_max",
        "render_us_mean",
        "events_per_frame_mean",
        "events_per_frame_max",
        "active_cylinders_mean",
    ] {
        let x = v[key].as_f64().unwrap_or_else(|| panic!("{key}: {v}"));
        assert!(x > 0.0, "{key} = {x}");
    }
    let cylinders = v["cylinders"].as_u64().unwrap();
    let touched = v["cylinders_touched"].as_u64().unwrap();
    assert!(touched > 0 && touched <= cylinders, "{v}");
    assert!(v["view_us_median"].as_f64() <= v["view_us_max"].as_f64());
    assert!(v["active_cylinders_mean"].as_f64() <= v["events_per_frame_mean"].as_f64());
    assert!(v.get("per_frame").is_none());
}

/// The complex over the scene's non-screen objects, as views need it.
struct Reference {
    file: vcx_demo::SceneFile,
    ids: Vec<ObjectId>,
}

impl Reference {
    fn new(path: &Path) -> Reference {
        let file = vcx_demo::load(path).unwrap();
        let ids = file
            .scene
            .as_ref()
            .objects()
            .iter()
            .enumerate()
            .filter(|(_, o)| o.material != Material::Screen)
            .map(|(i, _)| ObjectId(i as u32))
            .collect();
        Reference { file, ids }
    }

    /// The view from `q` as (start radians, object in the whole scene, start vertex).
    fn view(&self, q: QueryPoint) -> Vec<(f64, Option<u64>, Option<u64>)> {
        let sub = vcx::SubScene::new(self.file.scene.as_ref(), self.ids.iter().copied());
        let scene = sub.as_ref();
        let complex = vcx::partition::build_by_sweep(&scene).unwrap();
        vcx::walk::view(&complex, &scene, q)
            .unwrap()
            .iter()
            .map(|i| {
                (
                    i.start.radians(),
                    i.object
                        .and_then(|o| sub.original(o))
                        .map(|o| u64::from(o.0)),
                    i.start_vertex.map(|v| v as u64),
                )
            })
            .collect()
    }
}

/// Checks every frame of a `--per-frame` run against `vcx::walk::view`.
fn frames_agree(scene: &Path, v: &Value) -> Vec<(f64, f64)> {
    let reference = Reference::new(scene);
    let frames = v["per_frame"].as_array().unwrap();
    assert_eq!(frames.len() as u64, v["frames"].as_u64().unwrap());
    let mut points = Vec::new();
    for f in frames {
        let q = QueryPoint::from_raw(f["x_raw"].as_i64().unwrap(), f["y_raw"].as_i64().unwrap())
            .unwrap();
        let (x, y) = q.to_f64();
        assert!((f["x"].as_f64().unwrap() - x).abs() < 1e-9, "{f}");
        assert!((f["y"].as_f64().unwrap() - y).abs() < 1e-9, "{f}");
        let got: Vec<(f64, Option<u64>, Option<u64>)> = f["view"]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| {
                (
                    i["start"].as_f64().unwrap(),
                    i["object"].as_u64(),
                    i["start_vertex"].as_u64(),
                )
            })
            .collect();
        assert!(!got.is_empty());
        let want = reference.view(q);
        assert_eq!(
            got.len(),
            want.len(),
            "frame at ({x}, {y}): {got:?} vs {want:?}"
        );
        for (g, w) in got.iter().zip(&want) {
            // JSON's decimal floats may come back one ulp off; objects and vertices exactly.
            assert!(
                (g.0 - w.0).abs() < 1e-12,
                "frame at ({x}, {y}): {g:?} vs {w:?}"
            );
            assert_eq!((g.1, g.2), (w.1, w.2), "frame at ({x}, {y})");
        }
        assert!(f["events"].as_u64().unwrap() >= got.len() as u64);
        points.push((x, y));
    }
    points
}

#[test]
fn headless_views_agree_with_the_walk() {
    // The built-in grid along the circuit, and the mixed scene (screens left out).
    let v = headless(&["--frames", "24", "--per-frame"]);
    frames_agree(&example("grid"), &v);
    let mixed = example("mixed");
    let v = headless(&[mixed.to_str().unwrap(), "--frames", "24", "--per-frame"]);
    assert_eq!(v["objects"], 30);
    let points = frames_agree(&mixed, &v);
    // Distinct viewpoints: the circuit moves.
    assert!(points.windows(2).all(|w| w[0] != w[1]));
}

#[test]
fn headless_views_agree_with_vcx_view() {
    let scene = example("hall");
    let v = headless(&[scene.to_str().unwrap(), "--frames", "6", "--per-frame"]);
    for f in v["per_frame"].as_array().unwrap() {
        let at = format!("{},{}", f["x"].as_f64().unwrap(), f["y"].as_f64().unwrap());
        let out = vcx(&["view", scene.to_str().unwrap(), "--at", &at, "--json"]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let view: Value = serde_json::from_slice(&out.stdout).unwrap();
        let theirs: Vec<(f64, Option<u64>)> = view["intervals"]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| (i["start"].as_f64().unwrap(), i["path"][0].as_u64()))
            .collect();
        let ours: Vec<(f64, Option<u64>)> = f["view"]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| (i["start"].as_f64().unwrap(), i["object"].as_u64()))
            .collect();
        assert_eq!(ours.len(), theirs.len(), "at {at}: {ours:?} vs {theirs:?}");
        for (o, t) in ours.iter().zip(&theirs) {
            assert!(
                (o.0 - t.0).abs() < 1e-12 && o.1 == t.1,
                "at {at}: {o:?} vs {t:?}"
            );
        }
    }
}

#[test]
fn headless_ray_trees_agree_with_vcx_view() {
    // Depth 3 in the hall of mirrors: every frame's ray tree is `vcx view --depth 3`'s at
    // the same viewpoint — branches and boundary vertices exactly, angles within 1e-9.
    let scene = example("hall");
    let v = headless(&[
        scene.to_str().unwrap(),
        "--frames",
        "6",
        "--depth",
        "3",
        "--per-frame",
    ]);
    assert_eq!(v["depth"], 3);
    for key in ["view_us_mean", "render_us_mean", "events_per_frame_mean"] {
        assert!(v[key].as_f64().unwrap() > 0.0, "{key}: {v}");
    }
    let frames = v["per_frame"].as_array().unwrap();
    assert_eq!(frames.len(), 6);
    let at: String = frames
        .iter()
        .map(|f| {
            format!(
                "{},{}\n",
                f["x"].as_f64().unwrap(),
                f["y"].as_f64().unwrap()
            )
        })
        .collect();
    let at_file = temp_file("hall-points.txt", &at);
    let out = vcx(&[
        "view",
        scene.to_str().unwrap(),
        "--at-file",
        at_file.to_str().unwrap(),
        "--depth",
        "3",
        "--json",
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), frames.len());
    let mut deep = 0;
    for (f, line) in frames.iter().zip(&lines) {
        let view: Value = serde_json::from_str(line).unwrap();
        let theirs = view["intervals"].as_array().unwrap();
        let ours = f["view"].as_array().unwrap();
        let at = format!("{},{}", f["x"], f["y"]);
        assert_eq!(ours.len(), theirs.len(), "at {at}");
        for (o, t) in ours.iter().zip(theirs) {
            let (a, b) = (o["start"].as_f64().unwrap(), t["start"].as_f64().unwrap());
            assert!((a - b).abs() < 1e-9, "at {at}: {o} vs {t}");
            assert_eq!(o["branch"], t["path"], "at {at}: {o} vs {t}");
            assert_eq!(o["vertex"], t["vertex"], "at {at}: {o} vs {t}");
            let branch = o["branch"].as_array().unwrap();
            assert!(branch.len() <= 4, "{o}");
            assert_eq!(o["object"], branch.last().cloned().unwrap_or(Value::Null));
            deep += usize::from(branch.len() > 1);
        }
    }
    // The hall of mirrors is seen through its mirrors.
    assert!(deep > 0);
}

#[test]
fn headless_trajectory_file() {
    let path = temp_file("path.txt", "# a path\n40,40,0\n\n40.5, 40, 90\n41,40,180\n");
    let v = headless(&[
        "--trajectory",
        path.to_str().unwrap(),
        "--frames",
        "5",
        "--per-frame",
    ]);
    assert_eq!(v["trajectory"], path.to_str().unwrap());
    let frames = v["per_frame"].as_array().unwrap();
    let expect = [
        (40.0, 0.0),
        (40.5, 90.0),
        (41.0, 180.0),
        (40.0, 0.0),
        (40.5, 90.0),
    ];
    for (f, (x, h)) in frames.iter().zip(expect) {
        let q = QueryPoint::from_f64(x, 40.0).unwrap();
        assert_eq!(f["x_raw"].as_i64(), Some(q.x()));
        assert_eq!(f["y_raw"].as_i64(), Some(q.y()));
        assert_eq!(f["heading_deg"].as_f64(), Some(h));
    }
    frames_agree(&example("grid"), &v);
}

#[test]
fn bad_input_is_one_line() {
    let bad = temp_file(
        "bad.json",
        r#"{"objects": [{"material": "opaque", "vertices": [[0,0],[1,0]]}]}"#,
    );
    fails(
        &["demo", bad.to_str().unwrap(), "--headless", "--frames", "1"],
        &["bad.json", "object 0"],
    );
    fails(&["demo", "/no/such/scene.json"], &["cannot read"]);
    // Triangle 0 of the grid covers (4, 6).
    let inside = temp_file("inside.txt", "40,40,0\n4,6,0\n");
    fails(
        &[
            "demo",
            "--trajectory",
            inside.to_str().unwrap(),
            "--headless",
            "--frames",
            "2",
        ],
        &["viewpoint 2", "object 0"],
    );
    let garbled = temp_file("garbled.txt", "40,40\n");
    fails(
        &[
            "demo",
            "--trajectory",
            garbled.to_str().unwrap(),
            "--headless",
            "--frames",
            "2",
        ],
        &[":1:", "expected x,y,heading_deg"],
    );
    fails(
        &["demo", "--fov", "500", "--headless", "--frames", "1"],
        &["--fov"],
    );
    fails(
        &["demo", "--size", "0x3", "--headless", "--frames", "1"],
        &["--size"],
    );
    // Standard input here is not a terminal.
    fails(&["demo"], &["needs a terminal"]);
}

// ----- tmux -----

/// A tmux server of its own (socket per test) with one session running `sh`; killed on drop.
struct Tmux {
    socket: String,
}

impl Tmux {
    /// `None` (and a SKIP message) when tmux is missing.
    fn start(test: &str, width: u16, height: u16) -> Option<Tmux> {
        let ok = Command::new("tmux")
            .arg("-V")
            .output()
            .is_ok_and(|o| o.status.success());
        if !ok {
            eprintln!("SKIP {test}: tmux is not installed (apt-get install -y tmux)");
            return None;
        }
        let t = Tmux {
            socket: format!("vcx-demo-{}-{test}", std::process::id()),
        };
        let out = t.run(&[
            "new-session",
            "-d",
            "-s",
            "main",
            "-x",
            &width.to_string(),
            "-y",
            &height.to_string(),
            "env",
            "PS1=$ ",
            "sh",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        // Type only once the shell is listening.
        t.wait("the shell's prompt", |s| s.starts_with('$'));
        Some(t)
    }

    fn run(&self, args: &[&str]) -> Output {
        Command::new("tmux")
            .args(["-L", &self.socket, "-f", "/dev/null"])
            .args(args)
            .output()
            .unwrap()
    }

    /// Types `text` and presses Enter.
    fn line(&self, text: &str) {
        self.keys(&["-l", text]);
        self.keys(&["Enter"]);
    }

    fn keys(&self, keys: &[&str]) {
        let mut args = vec!["send-keys", "-t", "main"];
        args.extend_from_slice(keys);
        assert!(self.run(&args).status.success());
    }

    /// The screen as text (`colours`: with escape sequences).
    fn screen(&self, colours: bool) -> String {
        let mut args = vec!["capture-pane", "-p", "-t", "main"];
        if colours {
            args.push("-e");
        }
        String::from_utf8_lossy(&self.run(&args).stdout).into_owned()
    }

    fn display(&self, format: &str) -> String {
        let out = self.run(&["display-message", "-p", "-t", "main", format]);
        String::from_utf8_lossy(&out.stdout).trim().to_string()
    }

    /// Waits (up to 15 s) until the screen satisfies `ok`; returns it.
    fn wait(&self, what: &str, ok: impl Fn(&str) -> bool) -> String {
        let start = Instant::now();
        loop {
            let s = self.screen(false);
            if ok(&s) {
                return s;
            }
            assert!(
                start.elapsed() < Duration::from_secs(15),
                "timed out waiting for {what}; screen:\n{s}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// After the demo exited: the shell's prompt is back on the normal screen, the cursor
    /// is shown and the terminal is in canonical mode again.
    fn assert_restored(&self, status: i32) {
        let marker = format!("EXIT={status}");
        let screen = self.wait(&marker, |s| s.contains(&marker));
        assert_eq!(self.display("#{alternate_on}"), "0", "{screen}");
        assert_eq!(self.display("#{cursor_flag}"), "1", "{screen}");
        self.line("stty -a | tr ' ;' '\\n\\n' | grep -x -e -icanon -e icanon -e -echo -e echo");
        // `stty -a` lists icanon before echo: wait for both (or their negations).
        let line = |s: &str, want: &str| s.lines().any(|l| l.trim() == want);
        let screen = self.wait("stty", |s| {
            (line(s, "icanon") || line(s, "-icanon")) && (line(s, "echo") || line(s, "-echo"))
        });
        assert!(
            line(&screen, "icanon") && !line(&screen, "-icanon"),
            "{screen}"
        );
        assert!(line(&screen, "echo") && !line(&screen, "-echo"), "{screen}");
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.run(&["kill-server"]);
    }
}

/// The frame rate shown in the status line.
fn fps(screen: &str) -> Option<f64> {
    let rest = screen.split("fps ").nth(1)?;
    rest.split_whitespace().next()?.parse().ok()
}

/// The rows of the View pane (with colours): on each line, what lies between the last
/// two vertical borders.
fn view_rows(screen: &str) -> Vec<String> {
    screen
        .lines()
        .filter_map(|l| {
            let parts: Vec<&str> = l.split('│').collect();
            (parts.len() >= 3).then(|| parts[parts.len() - 2].to_string())
        })
        .collect()
}

fn demo_command(args: &str) -> String {
    format!("{VCX} demo {args}; echo EXIT=$?")
}

#[test]
fn tmux_panes_status_turn_and_quit() {
    let Some(t) = Tmux::start("panes", 150, 45) else {
        return;
    };
    t.line(&demo_command(""));
    let screen = t.wait("a non-zero frame rate", |s| fps(s).is_some_and(|f| f > 0.0));
    for title in ["View", "Map", "Dual space (θ, u)"] {
        assert!(screen.contains(title), "{title}:\n{screen}");
    }
    for part in [
        "events/frame ",
        "active cylinders ",
        "depth 0",
        "viewpoint (",
        "heading 90.0°",
    ] {
        assert!(screen.contains(part), "{part}:\n{screen}");
    }
    assert!(
        screen.contains("depth 0: what is seen directly"),
        "{screen}"
    );
    assert_eq!(t.display("#{alternate_on}"), "1");

    // Turning left changes the heading and the view.
    let before = view_rows(&t.screen(true));
    t.keys(&["Left"]);
    t.wait("heading 95.0°", |s| s.contains("heading 95.0°"));
    std::thread::sleep(Duration::from_millis(200));
    let after = view_rows(&t.screen(true));
    assert!(before.len() > 20, "{before:?}");
    assert_ne!(before, after, "the view did not change after a turn");

    // Depth, pane toggles.
    t.keys(&["+"]);
    t.wait("depth 1 in the status line", |s| {
        s.contains("│ depth 1 │") && s.contains("depth 1: up to 1 reflection")
    });
    t.keys(&["-"]);
    t.wait("depth 0 again", |s| s.contains("│ depth 0 │"));
    t.keys(&["2"]);
    let s = t.wait("the map hidden", |s| !s.contains("┌ Map"));
    assert!(s.contains("┌ View") && s.contains("Dual space"), "{s}");
    t.keys(&["2"]);
    t.wait("the map back", |s| s.contains("┌ Map"));

    t.keys(&["q"]);
    t.assert_restored(0);
}

#[test]
fn tmux_depth_changes_the_view() {
    // In the hall of mirrors, `+` goes to depth 1: the status line says so and the view
    // shows what the mirrors reflect.
    let Some(t) = Tmux::start("depth", 150, 45) else {
        return;
    };
    let hall = example("hall");
    t.line(&demo_command(hall.to_str().unwrap()));
    t.wait("a non-zero frame rate", |s| fps(s).is_some_and(|f| f > 0.0));
    t.wait("depth 0", |s| s.contains("│ depth 0 │"));
    let before = view_rows(&t.screen(true));
    assert!(before.len() > 20, "{before:?}");
    t.keys(&["+"]);
    t.wait("depth 1 in the status line", |s| s.contains("│ depth 1 │"));
    std::thread::sleep(Duration::from_millis(300));
    let after = view_rows(&t.screen(true));
    assert_ne!(before, after, "the view did not change at depth 1");
    t.keys(&["q"]);
    t.assert_restored(0);
}

#[test]
fn tmux_tiny_terminal_and_resize() {
    let Some(t) = Tmux::start("tiny", 30, 9) else {
        return;
    };
    t.line(&demo_command(""));
    t.wait("the too-small message", |s| s.contains("too small"));
    assert!(t
        .run(&["resize-window", "-t", "main", "-x", "140", "-y", "42"])
        .status
        .success());
    t.wait("the panes", |s| s.contains("┌ View") && s.contains("┌ Map"));
    t.keys(&["q"]);
    t.assert_restored(0);
}

#[test]
fn tmux_bad_scene_at_the_prompt() {
    let Some(t) = Tmux::start("prompt", 140, 42) else {
        return;
    };
    let bad = temp_file("bad-prompt.json", "{\"objects\": [}");
    let hall = example("hall");
    t.line(&demo_command(""));
    t.wait("the panes", |s| s.contains("┌ View"));
    t.keys(&["o"]);
    t.wait("the prompt", |s| s.contains("load scene"));
    t.keys(&["-l", bad.to_str().unwrap()]);
    t.keys(&["Enter"]);
    t.wait("the error", |s| {
        s.contains("error: ") && s.contains("invalid JSON")
    });
    // Still running; now a good one.
    t.keys(&["o"]);
    t.wait("the prompt", |s| s.contains("load scene"));
    t.keys(&["-l", hall.to_str().unwrap()]);
    t.keys(&["Enter"]);
    t.wait("the hall", |s| {
        s.contains("loaded") && s.contains("16 objects")
    });
    t.keys(&["q"]);
    t.assert_restored(0);
}

#[test]
fn tmux_panic_restores_the_terminal() {
    let Some(t) = Tmux::start("panic", 120, 40) else {
        return;
    };
    t.line(&demo_command("--panic-at-frame 3"));
    t.assert_restored(101);
    let screen = t.screen(false);
    let errors: Vec<&str> = screen.lines().filter(|l| l.contains("error: ")).collect();
    assert_eq!(errors.len(), 1, "{screen}");
    assert!(errors[0].contains("internal error"), "{screen}");
}

#[test]
fn tmux_playback_of_the_circuit() {
    let Some(t) = Tmux::start("circuit", 140, 42) else {
        return;
    };
    t.line(&demo_command("--circuit --frames 40"));
    t.wait("the circuit", |s| s.contains("circuit "));
    t.assert_restored(0);
}
