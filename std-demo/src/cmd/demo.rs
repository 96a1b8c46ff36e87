//! `vcx demo [SCENE]`: walk a scene in the terminal — the first-person view, the map and
//! the visibility complex in dual space (the paper's Fig. 20). Without SCENE, the
//! built-in grid example (`vcx gen grid 64 --seed 1`).
//!
//! Keys: ↑/↓ or W/S move, ←/→ or A/D turn, +/- ray-tree depth (0 to 5), t screens in or
//! out of the complex, 1/2/3 show or hide the View, Map and Dual space panes, [ ] field of
//! view, o load another scene, space pause a playback, q (or Control-C) quit.
//!
//! * `--trajectory FILE` replays `x,y,heading_deg` lines, `--circuit` the built-in circuit
//!   (an ellipse around the middle of the scene); a key that moves takes over.
//! * `--depth D` starts at ray-tree depth D (0 to 5). At depth 0 the View shows what is
//!   seen directly ([`vcx::walk::view`] over the complex without screens, unless `t` or
//!   `--screens`); at D > 0 it shows the ray tree ([`vcx::walk::ray_tree`] over the complex
//!   of the whole scene, screens included, built once when first needed): each column in
//!   the colour of what the ray finally hits, darker per bounce, framed by the colour of
//!   the first mirror or refractive object; the Map draws the rays of a few columns
//!   through their reflections.
//! * `--frames N` stops after N frames. With `--headless`, nothing is shown: N frames of
//!   the trajectory (default: the circuit) are computed and drawn into an off-screen
//!   buffer of `--size WxH`, and the statistics are printed as one JSON object:
//!   `frames`, `view_us_mean`/`view_us_median`/`view_us_max` (time in
//!   `vcx::walk::view`, or `vcx::walk::ray_tree` at depth > 0), `render_us_mean`
//!   (drawing), `events_per_frame_mean`/`_max` (walk steps of the primary trace over the
//!   complex shown, at every depth), `active_cylinders_mean` (distinct cylinders entered per
//!   frame), `cylinders_touched` (distinct over all frames), `cylinders`, `objects`,
//!   `depth`, `screens_in_complex`, `trajectory`; with `--per-frame` also `per_frame`:
//!   each frame's viewpoint (raw query-grid coordinates `x_raw`, `y_raw` and `x`, `y`),
//!   `heading_deg`, `events`, `active_cylinders` and its view intervals
//!   (`start` in radians, `object` — the last object of the branch —, `branch` — the
//!   objects along the ray, primary first, screens left out, as `path` of `vcx view
//!   --depth D --json` —, `start_vertex` as a global index and `vertex` as
//!   `[object, vertex]` written in the scene file, as in `vcx view`).
//!
//! Errors before the terminal is taken (a scene or trajectory that does not load or
//! validate, a viewpoint inside an object, no terminal) are one `error: ` line, exit
//! status 2. The terminal is restored on every exit, a panic included (the hook restores
//! it, then prints the usual one line).

use core::time::Duration;
use std::io::{self, IsTerminal, Write};
use std::path::PathBuf;
use std::time::Instant;

use crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
use crossterm::terminal::{self, EnterAlternateScreen, LeaveAlternateScreen};
use ratatui::backend::{CrosstermBackend, TestBackend};
use ratatui::Terminal;
use serde_json::{json, Value};
use vcx::{ObjectId, SceneRef};
use vcx_demo::demo::app::{App, Key};
use vcx_demo::demo::trajectory::{self, Pose};
use vcx_demo::demo::{ui, World, MAX_DEPTH};

use super::build::EXIT_INTERNAL;
use super::{write_stdout, Failure};

/// Arguments of `vcx demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (JSON); default: the built-in grid example.
    pub scene: Option<PathBuf>,
    /// Replay a path: one viewpoint per line, `x,y,heading_deg`.
    #[arg(long, value_name = "FILE", conflicts_with = "circuit")]
    pub trajectory: Option<PathBuf>,
    /// Replay the built-in circuit (an ellipse around the middle of the scene).
    #[arg(long)]
    pub circuit: bool,
    /// Stop after N frames.
    #[arg(long, value_name = "N")]
    pub frames: Option<u64>,
    /// No terminal: render N frames (--frames) off-screen and print statistics as JSON.
    #[arg(long, requires = "frames")]
    pub headless: bool,
    /// With --headless: also print every frame's viewpoint and view.
    #[arg(long, requires = "headless")]
    pub per_frame: bool,
    /// Size of the off-screen terminal of --headless, WxH.
    #[arg(long, value_name = "WxH", default_value = "120x40")]
    pub size: String,
    /// Field of view in degrees (20 to 180).
    #[arg(long, value_name = "DEG", default_value_t = 90.0)]
    pub fov: f64,
    /// Ray-tree depth to start at (0 to 5; keys +/- change it).
    #[arg(long, value_name = "D", default_value_t = 0)]
    pub depth: usize,
    /// Start with the screens in the complex.
    #[arg(long)]
    pub screens: bool,
    /// Most frames per second drawn in the terminal.
    #[arg(long, value_name = "FPS", default_value_t = 30.0)]
    pub max_fps: f64,
    /// For tests: panic after this many frames (the terminal must still be restored).
    #[arg(long, value_name = "N", hide = true)]
    pub panic_at_frame: Option<u64>,
}

/// Viewpoints of the built-in circuit.
const CIRCUIT_POSES: usize = 360;

/// Runs the demo.
pub fn run(args: &Args) -> Result<(), Failure> {
    if !(20.0..=180.0).contains(&args.fov) {
        return Err(Failure::bad_input(format!(
            "--fov {}: the field of view must be between 20 and 180 degrees",
            args.fov
        )));
    }
    if !(args.max_fps.is_finite() && args.max_fps > 0.0) {
        return Err(Failure::bad_input(format!(
            "--max-fps {}: must be a positive number",
            args.max_fps
        )));
    }
    if args.depth > MAX_DEPTH {
        return Err(Failure::bad_input(format!(
            "--depth {}: the demo's ray-tree depth must be from 0 to {MAX_DEPTH}",
            args.depth
        )));
    }
    let world = match &args.scene {
        // JSON or `.vcx` (crate::input); the demo rebuilds the complexes it walks.
        Some(path) => crate::input::load(path)
            .map_err(|f| f.message)
            .and_then(|i| World::new(i.file, path.display().to_string(), args.screens)),
        None => World::builtin().and_then(|mut w| {
            if args.screens {
                w.rebuild(true)?;
            }
            Ok(w)
        }),
    }
    .map_err(Failure::bad_input)?;
    let poses = poses(args, &world)?;
    let mut app = App::new(world);
    app.fov_deg = args.fov;
    if args.depth > 0 {
        app.world.full_complex().map_err(|m| Failure {
            message: m,
            code: EXIT_INTERNAL,
        })?;
        app.depth = args.depth;
        app.compute();
    }
    if let Some((poses, name)) = poses {
        app.play(poses, name);
    }
    if args.headless {
        return headless(args, app);
    }
    if !io::stdout().is_terminal() || !io::stdin().is_terminal() {
        return Err(Failure::bad_input(
            "vcx demo needs a terminal (for statistics without one: --headless --frames N)",
        ));
    }
    interactive(args, app)
}

/// The path to replay: `--trajectory`, `--circuit`, or the circuit for `--headless`.
fn poses(args: &Args, world: &World) -> Result<Option<(Vec<Pose>, String)>, Failure> {
    if let Some(path) = &args.trajectory {
        let poses = trajectory::load(path).map_err(Failure::bad_input)?;
        trajectory::check(world, &poses, &path.display().to_string())
            .map_err(Failure::bad_input)?;
        return Ok(Some((poses, path.display().to_string())));
    }
    if args.circuit || args.headless {
        let poses = trajectory::circuit(world, CIRCUIT_POSES);
        if poses.is_empty() {
            return Err(Failure::bad_input(format!(
                "{}: the built-in circuit finds no free viewpoints in this scene; give --trajectory FILE",
                world.name
            )));
        }
        return Ok(Some((poses, "circuit".to_string())));
    }
    Ok(None)
}

fn parse_size(text: &str) -> Result<(u16, u16), Failure> {
    let bad = || Failure::bad_input(format!("--size {text:?}: expected WxH, like 120x40"));
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u16 = w.trim().parse().map_err(|_| bad())?;
    let h: u16 = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 || w > 1000 || h > 1000 {
        return Err(bad());
    }
    Ok((w, h))
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    match s.len() {
        0 => 0.0,
        n if n % 2 == 1 => s[n / 2],
        n => (s[n / 2 - 1] + s[n / 2]) / 2.0,
    }
}

/// `--headless`: N frames off-screen, statistics as JSON.
fn headless(args: &Args, mut app: App) -> Result<(), Failure> {
    let (w, h) = parse_size(&args.size)?;
    let n = args.frames.unwrap_or(0);
    let internal = |m: String| Failure {
        message: m,
        code: EXIT_INTERNAL,
    };
    let mut terminal = Terminal::new(TestBackend::new(w, h))
        .map_err(|e| internal(format!("off-screen terminal: {e}")))?;
    let mut cache = ui::Cache::default();
    let cylinders = app.world.complex.cylinders().len();
    let mut touched = vec![false; cylinders];
    let (mut view_us, mut render_us, mut events, mut active) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut per_frame = Vec::new();
    for i in 0..n {
        if i > 0 {
            app.advance();
        }
        app.compute();
        let frame = app
            .frame
            .as_ref()
            .map_err(|e| internal(format!("frame {i}: viewpoint ({}, {}): {e}", app.x, app.y)))?;
        view_us.push(frame.view_micros);
        events.push(frame.events as f64);
        active.push(frame.active.len() as f64);
        for c in &frame.active {
            if let Some(t) = touched.get_mut(c.index()) {
                *t = true;
            }
        }
        if args.per_frame {
            let (x, y) = frame.q.to_f64();
            let view: Vec<Value> = frame
                .view
                .iter()
                .map(|s| {
                    json!({
                        "start": s.start_radians,
                        "object": s.object.map(|o| o.0),
                        "branch": s.branch.iter().map(|o| o.0).collect::<Vec<_>>(),
                        "start_vertex": s.start_vertex,
                        "vertex": s.start_vertex
                            .and_then(|k| written_vertex(&app.world.scene(), k))
                            .map(|(o, v)| json!([o.0, v])),
                    })
                })
                .collect();
            per_frame.push(json!({
                "x_raw": frame.q.x(),
                "y_raw": frame.q.y(),
                "x": x,
                "y": y,
                "heading_deg": app.heading_deg,
                "view_us": frame.view_micros,
                "events": frame.events,
                "active_cylinders": frame.active.len(),
                "view": view,
            }));
        }
        let start = Instant::now();
        terminal
            .draw(|f| {
                let area = f.area();
                ui::render(&app, &mut cache, area, f.buffer_mut());
            })
            .map_err(|e| internal(format!("drawing: {e}")))?;
        render_us.push(start.elapsed().as_secs_f64() * 1e6);
        app.frame_drawn(Instant::now());
    }
    let mut out = json!({
        "scene": app.world.name,
        "objects": app.world.scene().len(),
        "cylinders": cylinders,
        "screens_in_complex": app.world.screens_in_complex,
        "depth": app.depth,
        "trajectory": app.playback.as_ref().map(|p| p.name.clone()),
        "size": [w, h],
        "frames": n,
        "view_us_mean": mean(&view_us),
        "view_us_median": median(&view_us),
        "view_us_max": view_us.iter().copied().fold(0.0, f64::max),
        "render_us_mean": mean(&render_us),
        "events_per_frame_mean": mean(&events),
        "events_per_frame_max": events.iter().copied().fold(0.0, f64::max),
        "active_cylinders_mean": mean(&active),
        "cylinders_touched": touched.iter().filter(|t| **t).count(),
    });
    if args.per_frame {
        out["per_frame"] = Value::Array(per_frame);
    }
    write_stdout(&format!("{out}\n"))
}

/// A global vertex index as `(object, vertex id as written in the scene file)`.
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

/// Leaves raw mode and the alternate screen and shows the cursor; safe to call twice.
fn restore_terminal() {
    let _ = terminal::disable_raw_mode();
    let _ = crossterm::execute!(io::stdout(), LeaveAlternateScreen, crossterm::cursor::Show);
    let _ = io::stdout().flush();
}

/// Restores the terminal when dropped (every way out of the loop).
struct Restore;

impl Drop for Restore {
    fn drop(&mut self) {
        restore_terminal();
    }
}

fn map_key(k: event::KeyEvent) -> Option<Key> {
    if k.kind == KeyEventKind::Release {
        return None;
    }
    Some(match k.code {
        KeyCode::Char('c') if k.modifiers.contains(KeyModifiers::CONTROL) => Key::CtrlC,
        KeyCode::Char(c) => Key::Char(c),
        KeyCode::Up => Key::Up,
        KeyCode::Down => Key::Down,
        KeyCode::Left => Key::Left,
        KeyCode::Right => Key::Right,
        KeyCode::Enter => Key::Enter,
        KeyCode::Esc => Key::Esc,
        KeyCode::Backspace => Key::Backspace,
        _ => return None,
    })
}

/// The full-screen session.
fn interactive(args: &Args, mut app: App) -> Result<(), Failure> {
    let io_error = |what: &str, e: io::Error| Failure::bad_input(format!("terminal: {what}: {e}"));
    // Restore the terminal before the one-line panic report.
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        restore_terminal();
        previous(info);
    }));
    terminal::enable_raw_mode().map_err(|e| io_error("raw mode", e))?;
    let _restore = Restore;
    crossterm::execute!(io::stdout(), EnterAlternateScreen, crossterm::cursor::Hide)
        .map_err(|e| io_error("alternate screen", e))?;
    let mut terminal =
        Terminal::new(CrosstermBackend::new(io::stdout())).map_err(|e| io_error("setup", e))?;
    terminal.clear().map_err(|e| io_error("clear", e))?;
    let mut cache = ui::Cache::default();
    let period = Duration::from_secs_f64(1.0 / args.max_fps);
    loop {
        let start = Instant::now();
        if app.frames > 0 {
            app.advance();
        }
        app.compute();
        terminal
            .draw(|f| {
                let area = f.area();
                ui::render(&app, &mut cache, area, f.buffer_mut());
            })
            .map_err(|e| io_error("draw", e))?;
        app.frame_drawn(Instant::now());
        if args.panic_at_frame == Some(app.frames) {
            panic!("--panic-at-frame {}: panicking as asked", app.frames);
        }
        if args.frames.is_some_and(|n| app.frames >= n) {
            break;
        }
        // Input until the next frame is due.
        loop {
            let left = period.saturating_sub(start.elapsed());
            if !event::poll(left).map_err(|e| io_error("input", e))? {
                break;
            }
            match event::read().map_err(|e| io_error("input", e))? {
                Event::Key(k) => {
                    if let Some(key) = map_key(k) {
                        app.key(key);
                    }
                }
                Event::Resize(..) => terminal.autoresize().map_err(|e| io_error("resize", e))?,
                _ => {}
            }
            if app.quit || left.is_zero() {
                break;
            }
        }
        if app.quit {
            break;
        }
    }
    Ok(())
}
