//! The state of a demo session and what the keys do. No terminal here: the binary maps
//! terminal events to [`Key`]s, and tests drive [`App`] directly.

use core::time::Duration;
use std::collections::VecDeque;
use std::path::Path;
use std::time::Instant;

use vcx::QueryPoint;

use super::trajectory::Pose;
use super::{compute_frame, FrameData, World, MAX_DEPTH};

/// A key, as far as the demo cares.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// A character key.
    Char(char),
    /// Arrow up.
    Up,
    /// Arrow down.
    Down,
    /// Arrow left.
    Left,
    /// Arrow right.
    Right,
    /// Enter.
    Enter,
    /// Escape.
    Esc,
    /// Backspace.
    Backspace,
    /// Control-C.
    CtrlC,
}

/// The panes, in the order of their toggle keys 1, 2, 3.
pub const PANE_NAMES: [&str; 3] = ["View", "Map", "Dual space"];

/// How long a message stays in the status line.
const MESSAGE_TIME: Duration = Duration::from_secs(5);

/// The note shown when there is no message, by depth.
pub fn depth_note(depth: usize) -> &'static str {
    if depth == 0 {
        "depth 0: what is seen directly; mirrors and refractive objects are drawn as surfaces \
         of their own colour (+ follows reflections and refractions)"
    } else {
        "ray tree: each column shows what the ray finally hits, darker per bounce, inside a \
         band of the colour of the first mirror or refractive object; the map draws a few rays"
    }
}

/// A path being replayed.
#[derive(Clone, Debug)]
pub struct Playback {
    /// The viewpoints.
    pub poses: Vec<Pose>,
    /// The current one.
    pub index: usize,
    /// Whether playback is paused (space).
    pub paused: bool,
    /// Where the path came from.
    pub name: String,
}

/// One demo session.
#[derive(Debug)]
pub struct App {
    /// The scene and its complex.
    pub world: World,
    /// Viewpoint x (scene units).
    pub x: f64,
    /// Viewpoint y.
    pub y: f64,
    /// Heading in degrees, counter-clockwise from +x.
    pub heading_deg: f64,
    /// Field of view in degrees.
    pub fov_deg: f64,
    /// Ray-tree depth, 0 to [`MAX_DEPTH`] (keys +/-).
    pub depth: usize,
    /// Which panes are shown: View, Map, Dual space.
    pub panes: [bool; 3],
    /// Margin of the dual pane's u-range around the trace, as a fraction of the scene's
    /// size (keys z and x).
    pub dual_zoom: f64,
    /// The path being replayed, if any.
    pub playback: Option<Playback>,
    /// The text typed at the "load scene" prompt, while it is open.
    pub prompt: Option<String>,
    /// Set by `q` or Control-C.
    pub quit: bool,
    /// The last frame computed, or why there is none.
    pub frame: Result<FrameData, String>,
    /// Frames drawn so far.
    pub frames: u64,
    message: Option<(String, Instant)>,
    frame_times: VecDeque<Instant>,
}

impl App {
    /// A session in `world`, at its start viewpoint.
    pub fn new(world: World) -> App {
        let (x, y, heading_deg) = world.start_viewpoint();
        let mut app = App {
            world,
            x,
            y,
            heading_deg,
            fov_deg: 90.0,
            depth: 0,
            panes: [true; 3],
            dual_zoom: 0.04,
            playback: None,
            prompt: None,
            quit: false,
            frame: Err("no frame yet".to_string()),
            frames: 0,
            message: None,
            frame_times: VecDeque::new(),
        };
        app.compute();
        app
    }

    /// Replays `poses` (a trajectory or the circuit), starting with the first.
    pub fn play(&mut self, poses: Vec<Pose>, name: String) {
        if let Some(p) = poses.first() {
            self.set_pose(*p);
        }
        self.playback = Some(Playback {
            poses,
            index: 0,
            paused: false,
            name,
        });
        self.compute();
    }

    /// Puts the viewpoint at a pose.
    pub fn set_pose(&mut self, p: Pose) {
        self.x = p.x;
        self.y = p.y;
        self.heading_deg = p.heading_deg.rem_euclid(360.0);
    }

    /// The viewpoint on the query grid.
    pub fn query_point(&self) -> Option<QueryPoint> {
        QueryPoint::from_f64(self.x, self.y).ok()
    }

    /// Heading in radians.
    pub fn heading(&self) -> f64 {
        self.heading_deg.to_radians()
    }

    /// Field of view in radians.
    pub fn fov(&self) -> f64 {
        self.fov_deg.to_radians()
    }

    /// Recomputes the view from the current viewpoint.
    pub fn compute(&mut self) {
        self.frame = match self.query_point() {
            None => Err(format!(
                "viewpoint ({}, {}) is out of range",
                self.x, self.y
            )),
            Some(q) => compute_frame(&self.world, q, self.depth),
        };
    }

    /// Next pose of the playback, if playing.
    pub fn advance(&mut self) {
        let next = match &mut self.playback {
            Some(p) if !p.paused && !p.poses.is_empty() => {
                p.index = (p.index + 1) % p.poses.len();
                p.poses.get(p.index).copied()
            }
            _ => None,
        };
        if let Some(pose) = next {
            self.set_pose(pose);
        }
    }

    /// Notes that a frame was drawn now (for the frame rate).
    pub fn frame_drawn(&mut self, now: Instant) {
        self.frames += 1;
        self.frame_times.push_back(now);
        while self
            .frame_times
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(2))
        {
            self.frame_times.pop_front();
        }
    }

    /// Frames per second over the last two seconds (0 before the second frame).
    pub fn fps(&self) -> f64 {
        match (self.frame_times.front(), self.frame_times.back()) {
            (Some(a), Some(b)) if self.frame_times.len() >= 2 => {
                let s = b.duration_since(*a).as_secs_f64();
                if s > 0.0 {
                    (self.frame_times.len() - 1) as f64 / s
                } else {
                    0.0
                }
            }
            _ => 0.0,
        }
    }

    /// Shows a message in the status line for a few seconds.
    pub fn say(&mut self, text: impl Into<String>) {
        self.message = Some((super::one_line(&text.into()), Instant::now()));
    }

    /// The current message, if still fresh.
    pub fn message(&self) -> Option<&str> {
        self.message
            .as_ref()
            .filter(|(_, t)| t.elapsed() < MESSAGE_TIME)
            .map(|(m, _)| m.as_str())
    }

    /// Handles one key.
    pub fn key(&mut self, key: Key) {
        if let Some(text) = &mut self.prompt {
            match key {
                Key::Char(c) => text.push(c),
                Key::Backspace => {
                    text.pop();
                }
                Key::Esc => {
                    self.prompt = None;
                    self.say("load cancelled");
                }
                Key::Enter => {
                    let path = text.trim().to_string();
                    self.prompt = None;
                    if !path.is_empty() {
                        self.load(Path::new(&path));
                    }
                }
                Key::CtrlC => self.quit = true,
                _ => {}
            }
            return;
        }
        let step = 0.01 * self.world.extent();
        match key {
            Key::Char('q') | Key::Char('Q') | Key::CtrlC => self.quit = true,
            Key::Up | Key::Char('w') | Key::Char('W') => self.walk(step),
            Key::Down | Key::Char('s') | Key::Char('S') => self.walk(-step),
            Key::Left | Key::Char('a') | Key::Char('A') => self.turn(5.0),
            Key::Right | Key::Char('d') | Key::Char('D') => self.turn(-5.0),
            Key::Char('+') | Key::Char('=') => self.set_depth(self.depth + 1),
            Key::Char('-') | Key::Char('_') => self.set_depth(self.depth.saturating_sub(1)),
            Key::Char('t') | Key::Char('T') => self.toggle_screens(),
            Key::Char(c @ '1'..='3') => {
                let k = usize::from(c as u8 - b'1');
                self.panes[k] = !self.panes[k];
                let state = if self.panes[k] { "shown" } else { "hidden" };
                self.say(format!("{} pane {state}", PANE_NAMES[k]));
            }
            Key::Char('o') | Key::Char('O') => self.prompt = Some(String::new()),
            Key::Char(' ') => match &mut self.playback {
                Some(p) => {
                    p.paused = !p.paused;
                    let what = if p.paused { "paused" } else { "resumed" };
                    self.say(format!("playback {what}"));
                }
                None => self.say("no playback (start with --trajectory FILE or --circuit)"),
            },
            Key::Char('z') | Key::Char('Z') => self.dual_zoom = (self.dual_zoom * 0.7).max(0.002),
            Key::Char('x') | Key::Char('X') => self.dual_zoom = (self.dual_zoom / 0.7).min(2.0),
            Key::Char('[') => self.set_fov(self.fov_deg - 10.0),
            Key::Char(']') => self.set_fov(self.fov_deg + 10.0),
            _ => {}
        }
    }

    /// Sets the ray-tree depth (clamped to 0 to [`MAX_DEPTH`]) and recomputes.
    pub fn set_depth(&mut self, depth: usize) {
        let depth = depth.min(MAX_DEPTH);
        if depth == self.depth {
            self.say(if depth == 0 {
                "depth is 0 already (primary rays only)".to_string()
            } else {
                format!("depth {MAX_DEPTH} is the deepest the demo shows")
            });
            return;
        }
        if depth > 0 {
            if let Err(e) = self.world.full_complex() {
                self.say(e);
                return;
            }
        }
        self.depth = depth;
        self.compute();
        self.say(match depth {
            0 => "depth 0: primary rays only".to_string(),
            d => format!(
                "depth {d}: up to {d} reflection{} or refraction{} (the complex with screens: {} cylinders)",
                if d == 1 { "" } else { "s" },
                if d == 1 { "" } else { "s" },
                self.world.full_complex().map_or(0, |c| c.cylinders().len())
            ),
        });
    }

    fn set_fov(&mut self, deg: f64) {
        self.fov_deg = deg.clamp(20.0, 180.0);
        self.say(format!("field of view {:.0}°", self.fov_deg));
    }

    /// Manual control ends a playback.
    fn take_control(&mut self) {
        if self.playback.take().is_some() {
            self.say("playback stopped: manual control");
        }
    }

    fn turn(&mut self, deg: f64) {
        self.take_control();
        self.heading_deg = (self.heading_deg + deg).rem_euclid(360.0);
        self.compute();
    }

    /// Moves along the heading by `dist` (backwards if negative), unless an object is in
    /// the way: then the viewpoint stays where it is, as at a wall.
    pub fn walk(&mut self, dist: f64) {
        self.take_control();
        let h = self.heading();
        let (dx, dy) = (h.cos() * dist.signum(), h.sin() * dist.signum());
        let len = dist.abs();
        let margin = 0.003 * self.world.extent();
        let from = (self.x, self.y);
        let (nx, ny) = (self.x + dx * len, self.y + dy * len);
        let probe = (self.x + dx * (len + margin), self.y + dy * (len + margin));
        if let Some((o, _)) = self.world.segment_hit(from, probe) {
            self.say(format!("blocked by {}", self.world.describe(o)));
            return;
        }
        let Ok(q) = QueryPoint::from_f64(nx, ny) else {
            self.say("blocked: the edge of the coordinate range");
            return;
        };
        if let Some(o) = self.world.blocked_at(q) {
            self.say(format!("blocked by {}", self.world.describe(o)));
            return;
        }
        // Ray trees need the viewpoint outside the screens too.
        if self.depth > 0 {
            if let Some(o) = self.world.blocked_in_scene(q) {
                self.say(format!(
                    "blocked by {} (at depth > 0)",
                    self.world.describe(o)
                ));
                return;
            }
        }
        self.x = nx;
        self.y = ny;
        self.compute();
    }

    fn toggle_screens(&mut self) {
        let screens = self.world.screens();
        if screens == 0 {
            self.say("this scene has no screens");
            return;
        }
        let on = !self.world.screens_in_complex;
        if let Err(e) = self.world.rebuild(on) {
            self.say(e);
            return;
        }
        if on {
            if let Some(o) = self.query_point().and_then(|q| self.world.blocked_at(q)) {
                let _ = self.world.rebuild(false);
                self.say(format!(
                    "screens not included: the viewpoint is in {}",
                    self.world.describe(o)
                ));
                return;
            }
            let note = if self.depth == 0 {
                "the depth-0 view stops at them (ray trees, +, see through)"
            } else {
                "the ray tree sees through them all the same"
            };
            self.say(format!(
                "{screens} screens in the complex ({} cylinders): {note}",
                self.world.complex.cylinders().len()
            ));
        } else {
            self.say(format!(
                "screens left out of the complex ({} cylinders): the view sees through them",
                self.world.complex.cylinders().len()
            ));
        }
        self.compute();
    }

    /// Loads another scene; on failure the current one stays and the status says why.
    pub fn load(&mut self, path: &Path) {
        match World::load(path, false) {
            Ok(world) => {
                let n = world.scene().len();
                let (x, y, h) = world.start_viewpoint();
                self.world = world;
                self.x = x;
                self.y = y;
                self.heading_deg = h;
                self.playback = None;
                self.compute();
                self.say(format!("loaded {} ({n} objects)", path.display()));
            }
            Err(e) => self.say(format!("error: {e}")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn app() -> App {
        App::new(World::builtin().unwrap())
    }

    #[test]
    fn starts_free_and_turns() {
        let mut a = app();
        let f = a.frame.as_ref().unwrap();
        assert!(f.events > 0 && !f.view.is_empty());
        let h = a.heading_deg;
        a.key(Key::Left);
        assert!((a.heading_deg - (h + 5.0).rem_euclid(360.0)).abs() < 1e-9);
        a.key(Key::Char('d'));
        assert!((a.heading_deg - h).abs() < 1e-9);
    }

    #[test]
    fn walking_into_an_object_is_blocked() {
        let mut a = app();
        // Face the middle of the first object seen, then walk forward until blocked; the
        // viewpoint always stays free.
        let view = a.frame.as_ref().unwrap().view.clone();
        let k = view.iter().position(|s| s.object.is_some()).unwrap();
        let end = view
            .get(k + 1)
            .map_or(core::f64::consts::TAU, |s| s.start_radians);
        a.heading_deg = ((view[k].start_radians + end) / 2.0).to_degrees();
        let mut blocked = false;
        for _ in 0..2000 {
            let before = (a.x, a.y);
            a.key(Key::Up);
            assert!(a.frame.is_ok(), "{:?}", a.frame);
            if (a.x, a.y) == before {
                blocked = true;
                break;
            }
        }
        assert!(blocked);
        assert!(
            a.message().unwrap().starts_with("blocked"),
            "{:?}",
            a.message()
        );
    }

    #[test]
    fn keys_for_depth_panes_prompt_and_quit() {
        let mut a = app();
        a.key(Key::Char('+'));
        assert_eq!(a.depth, 1);
        assert!(
            a.message().unwrap().starts_with("depth 1"),
            "{:?}",
            a.message()
        );
        assert!(a.frame.as_ref().unwrap().depth == 1);
        for _ in 0..10 {
            a.key(Key::Char('+'));
        }
        assert_eq!(a.depth, MAX_DEPTH);
        for _ in 0..10 {
            a.key(Key::Char('-'));
        }
        assert_eq!(a.depth, 0);
        assert_eq!(a.frame.as_ref().unwrap().depth, 0);
        a.key(Key::Char('2'));
        assert_eq!(a.panes, [true, false, true]);
        a.key(Key::Char('t'));
        assert_eq!(a.message(), Some("this scene has no screens"));
        a.key(Key::Char('o'));
        for c in "/no/such/scene.json".chars() {
            a.key(Key::Char(c));
        }
        a.key(Key::Enter);
        assert!(a.prompt.is_none());
        assert!(
            a.message().unwrap().starts_with("error: cannot read"),
            "{:?}",
            a.message()
        );
        assert!(a.frame.is_ok());
        assert!(!a.quit);
        a.key(Key::Char('q'));
        assert!(a.quit);
    }
}
