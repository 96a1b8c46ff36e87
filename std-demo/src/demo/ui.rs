//! Drawing a demo session into a ratatui buffer: the View, Map and Dual space panes (as
//! in the paper's Fig. 20: the view on the right, the map above the complex on the left)
//! and a three-line status at the bottom.
//!
//! * **View**: each terminal cell is split into 2 × 2 sub-pixels — two half-columns (whose
//!   pieces and exact coverage come from [`columns`]) by two half-rows. A sub-pixel's
//!   colour is the coverage-weighted mix of its pieces, each piece either its wall (height
//!   ∝ 1/distance, shaded by distance, edge orientation and material) or floor/ceiling;
//!   vertical coverage of the wall's top and bottom edges is fractional too. The cell then
//!   shows the quadrant glyph (▘▝▀▖▌▞▛ …) with the two colours that fit its four
//!   sub-pixels best. At depth > 0 a piece shows the last object of its branch (what the
//!   ray finally hits) at the unfolded length of the ray, darker by a factor per bounce;
//!   when the ray went on from a mirror or a refractive object, that first object's wall
//!   is drawn as a frame — a band of its colour along its top and bottom, a light tint of
//!   it inside — and what is seen through it is clipped to it.
//! * **Map**: the scene from above in braille dots, the viewpoint `@`, the field of view
//!   and the rays from the viewpoint to the vertices that cause the view's boundaries
//!   (bright inside the field of view, dim outside). At depth > 0 also the rays of a few
//!   sample columns through their reflections (polylines in `f64`, one colour per
//!   generation; refraction drawn straight through, see [`super::trace_branch`]).
//! * **Dual space**: the `(θ, u)` plane, θ in `[0, 2π)` across, `u = cross(d(θ), p)` up:
//!   u measured from the middle of the scene (a shift of origin keeps the trace small).
//!   The window spans the field of view and a quarter of it on each side in θ, and the
//!   trace's u-range there plus a margin (keys z/x) in u. Every cylinder crossing the
//!   window is drawn by its bottom and top chains (sampled at a few θ per cylinder); the
//!   cylinders the trace entered this frame are outlined whole (chains and walls) and
//!   brighter; the trace `u_q(θ)` is red, the field of view two vertical lines, and the
//!   view's boundaries white ticks above and below the trace.

use core::f64::consts::TAU;

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Paragraph, Widget, Wrap};
use vcx::geom::sos::Angle;
use vcx::line_space::{tangent_vertex, Chain};
use vcx::partition::Wall;
use vcx::{Material, ObjectId};

use super::app::{depth_note, App};
use super::columns::{columns, direction_angle, interval_at, Column};
use super::raster::{Braille, Transform};

/// Smallest terminal the panes are drawn in.
pub const MIN_WIDTH: u16 = 40;
/// Smallest terminal height.
pub const MIN_HEIGHT: u16 = 12;

/// Drawings kept between frames: the sampled outlines of the cylinders and the raster of
/// all of them, rebuilt when the complex or the pane size changes.
#[derive(Debug, Default)]
pub struct Cache {
    outlines: Option<(u64, Outlines)>,
}

/// Cylinder outlines in `(θ, u)`, indexed like the complex's cylinders.
#[derive(Debug)]
struct Outlines {
    cylinders: Vec<Outline>,
}

#[derive(Debug)]
struct Outline {
    left: f64,
    right: f64,
    bottom: Option<Vec<(f64, f64)>>,
    top: Option<Vec<(f64, f64)>>,
    /// Lowest u of the bottom chain (−∞ if unbounded).
    lo: f64,
    /// Highest u of the top chain (+∞ if unbounded).
    hi: f64,
}

/// Draws the whole screen.
pub fn render(app: &App, cache: &mut Cache, area: Rect, buf: &mut Buffer) {
    if area.width < MIN_WIDTH || area.height < MIN_HEIGHT {
        let text = format!(
            "terminal too small: {}×{}, the demo needs at least {MIN_WIDTH}×{MIN_HEIGHT} (q quits)",
            area.width, area.height
        );
        Paragraph::new(text)
            .style(Style::default().fg(Color::Yellow))
            .wrap(Wrap { trim: true })
            .render(area, buf);
        return;
    }
    let [main, status] = Layout::vertical([Constraint::Min(1), Constraint::Length(3)]).areas(area);
    draw_status(app, status, buf);
    let [view_on, map_on, dual_on] = app.panes;
    let left_on = map_on || dual_on;
    let (left, right) = match (view_on, left_on) {
        (true, true) => {
            let [l, r] =
                Layout::horizontal([Constraint::Percentage(40), Constraint::Percentage(60)])
                    .areas(main);
            (Some(l), Some(r))
        }
        (true, false) => (None, Some(main)),
        (false, true) => (Some(main), None),
        (false, false) => {
            Paragraph::new("all panes hidden: press 1 (View), 2 (Map) or 3 (Dual space)")
                .block(Block::bordered())
                .render(main, buf);
            return;
        }
    };
    if let Some(r) = right {
        pane(" View ", r, buf, |inner, buf| draw_view(app, inner, buf));
    }
    if let Some(l) = left {
        let (map, dual) = match (map_on, dual_on) {
            (true, true) => {
                let [a, b] =
                    Layout::vertical([Constraint::Percentage(50), Constraint::Percentage(50)])
                        .areas(l);
                (Some(a), Some(b))
            }
            (true, false) => (Some(l), None),
            _ => (None, Some(l)),
        };
        if let Some(a) = map {
            let legend = Line::from(vec![
                Span::styled(" ■ opaque", Style::default().fg(material_rgb(None, 0))),
                Span::styled(" ■ mirror", Style::default().fg(rgb(MIRROR))),
                Span::styled(" ■ refractive", Style::default().fg(rgb(REFRACTIVE))),
                Span::styled(" ■ screen ", Style::default().fg(rgb(SCREEN))),
            ]);
            let block = Block::bordered().title(" Map ").title_bottom(legend);
            let inner = block.inner(a);
            block.render(a, buf);
            draw_map(app, inner, buf);
        }
        if let Some(b) = dual {
            let inner = Block::bordered().inner(b);
            let shown = if inner.width > 0 && inner.height > 0 {
                draw_dual(app, cache, inner, buf)
            } else {
                String::new()
            };
            let note = format!(" {shown} │ z/x zoom ");
            Block::bordered()
                .title(" Dual space (θ, u) ")
                .title_bottom(Line::from(note).right_aligned())
                .render(b, buf);
        }
    }
}

/// A bordered pane with a title; `f` draws its inside.
fn pane(title: &str, area: Rect, buf: &mut Buffer, f: impl FnOnce(Rect, &mut Buffer)) {
    let block = Block::bordered().title(title.to_string());
    let inner = block.inner(area);
    block.render(area, buf);
    if inner.width > 0 && inner.height > 0 {
        f(inner, buf);
    }
}

fn draw_status(app: &App, area: Rect, buf: &mut Buffer) {
    let (events, active, view_ms) = match &app.frame {
        Ok(f) => (
            f.events.to_string(),
            f.active.len().to_string(),
            format!("{:.2} ms", f.view_micros / 1000.0),
        ),
        Err(_) => ("-".into(), "-".into(), "-".into()),
    };
    let screens = if app.world.screens() == 0 {
        String::new()
    } else if app.world.screens_in_complex {
        " │ screens in complex".into()
    } else {
        " │ screens left out".into()
    };
    let playback = match &app.playback {
        Some(p) => format!(
            " │ {} {}/{}{}",
            p.name,
            p.index + 1,
            p.poses.len(),
            if p.paused { " paused" } else { "" }
        ),
        None => String::new(),
    };
    let first = format!(
        "fps {:.1} │ events/frame {events} │ active cylinders {active} │ depth {} │ viewpoint ({:.2}, {:.2}) heading {:.1}° │ view {view_ms}{screens}{playback}",
        app.fps(),
        app.depth,
        app.x,
        app.y,
        app.heading_deg,
    );
    let second = if let Some(p) = &app.prompt {
        Line::from(vec![
            Span::styled(
                "load scene (Enter loads, Esc cancels): ",
                Style::default().fg(Color::Yellow),
            ),
            Span::raw(format!("{p}_")),
        ])
    } else if let Some(m) = app.message() {
        Line::styled(m.to_string(), Style::default().fg(Color::Yellow))
    } else {
        Line::styled(depth_note(app.depth), Style::default().fg(Color::Gray))
    };
    let third = Line::styled(
        format!(
            "↑↓/WS move ←→/AD turn +/- depth t screens 1/2/3 panes [ ] fov z/x zoom o open space pause q quit │ {} ({} objects, {} cylinders)",
            app.world.name,
            app.world.scene().len(),
            app.world.complex.cylinders().len(),
        ),
        Style::default().fg(Color::DarkGray),
    );
    Paragraph::new(vec![
        Line::styled(first, Style::default().add_modifier(Modifier::BOLD)),
        second,
        third,
    ])
    .style(Style::default().bg(Color::Rgb(20, 20, 28)))
    .render(area, buf);
}

// ----- colours -----

type Rgb = (f64, f64, f64);

fn rgb(c: Rgb) -> Color {
    let b = |v: f64| v.clamp(0.0, 255.0).round() as u8;
    Color::Rgb(b(c.0), b(c.1), b(c.2))
}

fn mix(a: Rgb, b: Rgb, t: f64) -> Rgb {
    (
        a.0 + (b.0 - a.0) * t,
        a.1 + (b.1 - a.1) * t,
        a.2 + (b.2 - a.2) * t,
    )
}

const MIRROR: Rgb = (150.0, 215.0, 255.0);
const REFRACTIVE: Rgb = (70.0, 235.0, 150.0);
const SCREEN: Rgb = (235.0, 90.0, 235.0);

/// Base colour of a material (object id varies opaque objects a little).
fn base_rgb(material: Option<Material>, id: u32) -> Rgb {
    match material {
        Some(Material::Mirror) => MIRROR,
        Some(Material::Refractive { .. }) => REFRACTIVE,
        Some(Material::Screen) => SCREEN,
        _ => {
            const WARM: [Rgb; 4] = [
                (222.0, 176.0, 112.0),
                (200.0, 150.0, 105.0),
                (215.0, 190.0, 140.0),
                (190.0, 160.0, 125.0),
            ];
            WARM[(id % 4) as usize]
        }
    }
}

fn material_rgb(material: Option<Material>, id: u32) -> Color {
    rgb(base_rgb(material, id))
}

/// Ceiling and floor colour of half-row `r` of `rows`, with the horizon in the middle.
fn background(r: f64, rows: f64) -> Rgb {
    let mid = rows / 2.0;
    if r < mid {
        let t = (r / mid).clamp(0.0, 1.0);
        mix((8.0, 10.0, 26.0), (28.0, 34.0, 70.0), t)
    } else {
        let t = ((r - mid) / mid).clamp(0.0, 1.0);
        mix((38.0, 34.0, 26.0), (96.0, 86.0, 64.0), t)
    }
}

// ----- the view -----

/// One piece of a half-column, ready to draw.
#[derive(Clone, Copy)]
struct Paint {
    fraction: f64,
    /// `None`: nothing seen (floor and ceiling only).
    wall: Option<(Rgb, f64, f64)>,
    /// At depth > 0, the wall of the first mirror or refractive object the ray went on
    /// from: its colour and span; what is seen is clipped to it.
    glass: Option<(Rgb, f64, f64)>,
}

/// Darkening per bounce at depth > 0.
const PER_BOUNCE: f64 = 0.78;

fn draw_view(app: &App, area: Rect, buf: &mut Buffer) {
    let frame = match &app.frame {
        Ok(f) => f,
        Err(e) => {
            Paragraph::new(format!("no view: {e}"))
                .style(Style::default().fg(Color::Red))
                .wrap(Wrap { trim: true })
                .render(area, buf);
            return;
        }
    };
    let (w, h) = (usize::from(area.width), usize::from(area.height));
    let half_cols = columns(&app.world, frame, app.heading(), app.fov(), 2 * w);
    let rows = 2.0 * h as f64;
    let paints: Vec<Vec<Paint>> = half_cols
        .iter()
        .map(|c| paint_column(app, c, w, rows))
        .collect();
    let sub = |j: usize, r: usize| -> Rgb {
        let (r0, r1) = (r as f64, r as f64 + 1.0);
        let bg = background(r as f64 + 0.5, rows);
        let mut acc = (0.0, 0.0, 0.0);
        for p in &paints[j] {
            let cover = |top: f64, bottom: f64| (r1.min(bottom) - r0.max(top)).clamp(0.0, 1.0);
            let mut c = match p.wall {
                Some((colour, top, bottom)) => mix(bg, colour, cover(top, bottom)),
                None => bg,
            };
            if let Some((g, top, bottom)) = p.glass {
                let band = (bottom - top).min(2.0) * 0.35;
                let edge = (cover(top, top + band) + cover(bottom - band, bottom)).min(1.0);
                let framed = mix(mix(c, g, 0.12), g, edge);
                c = mix(bg, framed, cover(top, bottom));
            }
            acc = (
                acc.0 + c.0 * p.fraction,
                acc.1 + c.1 * p.fraction,
                acc.2 + c.2 * p.fraction,
            );
        }
        acc
    };
    for cy in 0..h {
        for cx in 0..w {
            let quad = [
                sub(2 * cx, 2 * cy),
                sub(2 * cx + 1, 2 * cy),
                sub(2 * cx, 2 * cy + 1),
                sub(2 * cx + 1, 2 * cy + 1),
            ];
            let (glyph, fg, bg) = quadrant(quad);
            if let Some(cell) = buf.cell_mut((area.x + cx as u16, area.y + cy as u16)) {
                cell.set_char(glyph).set_fg(rgb(fg)).set_bg(rgb(bg));
            }
        }
    }
}

/// The pieces of a half-column with their colours and wall spans in half-rows.
fn paint_column(app: &App, column: &Column, w: usize, rows: f64) -> Vec<Paint> {
    let extent = app.world.extent();
    let wall_height = 0.12 * extent;
    let eye = 0.35 * wall_height;
    // Half-rows per radian: a half-row is about one cell width high, and w cells span
    // the field of view.
    let per_radian = w as f64 / app.fov();
    let horizon = rows / 2.0;
    column
        .pieces
        .iter()
        .map(|p| {
            let span = |d: f64| {
                let d = d.max(1e-6);
                (
                    horizon - (wall_height - eye) / d * per_radian,
                    horizon + eye / d * per_radian,
                )
            };
            let dim = PER_BOUNCE.powi(p.bounces.min(16) as i32);
            let wall = p.object.filter(|_| p.distance.is_finite()).map(|o| {
                let (top, bottom) = span(p.distance);
                let c = shade(app, o, p.distance, p.facing);
                ((c.0 * dim, c.1 * dim, c.2 * dim), top, bottom)
            });
            let glass = p.first.filter(|_| p.first_distance.is_finite()).map(|o| {
                let (top, bottom) = span(p.first_distance);
                (base_rgb(app.world.material(o), o.0), top, bottom)
            });
            Paint {
                fraction: p.fraction,
                wall,
                glass,
            }
        })
        .collect()
}

/// Colour of a wall: material, lit by how squarely it faces the ray, darkened with
/// distance.
fn shade(app: &App, o: ObjectId, distance: f64, facing: f64) -> Rgb {
    let material = app.world.material(o);
    let base = base_rgb(material, o.0);
    let light = 0.45 + 0.55 * facing;
    let fog = (-distance / (0.45 * app.world.extent())).exp();
    let k = light * (0.2 + 0.8 * fog);
    let c = (base.0 * k, base.1 * k, base.2 * k);
    match material {
        // Glassy: lighter and bluer at the top of the range, but never see-through.
        Some(Material::Refractive { .. }) => mix(c, (200.0, 255.0, 230.0), 0.15 * fog),
        _ => c,
    }
}

/// Quadrant glyphs by the mask of sub-pixels in the foreground (TL 1, TR 2, BL 4, BR 8).
const QUADRANTS: [char; 16] = [
    ' ', '▘', '▝', '▀', '▖', '▌', '▞', '▛', '▗', '▚', '▐', '▜', '▄', '▙', '▟', '█',
];

/// The glyph and the two colours that best show four sub-pixels (TL, TR, BL, BR).
fn quadrant(q: [Rgb; 4]) -> (char, Rgb, Rgb) {
    let dist = |a: Rgb, b: Rgb| (a.0 - b.0).powi(2) + (a.1 - b.1).powi(2) + (a.2 - b.2).powi(2);
    let mean = |mask: usize, inside: bool| -> Rgb {
        let mut s = (0.0, 0.0, 0.0);
        let mut n = 0.0;
        for (k, c) in q.iter().enumerate() {
            if ((mask >> k) & 1 == 1) == inside {
                s = (s.0 + c.0, s.1 + c.1, s.2 + c.2);
                n += 1.0;
            }
        }
        if n > 0.0 {
            (s.0 / n, s.1 / n, s.2 / n)
        } else {
            s
        }
    };
    let all = mean(0, false);
    let mut best = (q.iter().map(|c| dist(*c, all)).sum::<f64>(), 0usize);
    for mask in 1..8 {
        let (fg, bg) = (mean(mask, true), mean(mask, false));
        let err: f64 = q
            .iter()
            .enumerate()
            .map(|(k, c)| dist(*c, if (mask >> k) & 1 == 1 { fg } else { bg }))
            .sum();
        if err + 1e-9 < best.0 {
            best = (err, mask);
        }
    }
    match best.1 {
        0 => (' ', all, all),
        m => (QUADRANTS[m], mean(m, true), mean(m, false)),
    }
}

// ----- the map -----

fn draw_map(app: &App, area: Rect, buf: &mut Buffer) {
    if area.width == 0 || area.height == 0 {
        return;
    }
    let world = &app.world;
    let mut canvas = Braille::new(area.width, area.height);
    let (mut x0, mut y0, mut x1, mut y1) = world.bbox;
    x0 = x0.min(app.x);
    x1 = x1.max(app.x);
    y0 = y0.min(app.y);
    y1 = y1.max(app.y);
    let m = 0.04 * (x1 - x0).max(y1 - y0).max(1.0);
    let t = Transform::fit((x0 - m, y0 - m, x1 + m, y1 + m), &canvas);
    let scene = world.scene();
    // Filled objects, then their outlines.
    for (i, poly) in world.polygons.iter().enumerate() {
        let material = scene.objects().get(i).map(|o| o.material);
        let base = base_rgb(material, i as u32);
        let in_complex = world.complex_objects().contains(&ObjectId(i as u32));
        let dim = if in_complex { 0.45 } else { 0.25 };
        let fill = rgb((base.0 * dim, base.1 * dim, base.2 * dim));
        let (mut a, mut b) = (
            (f64::INFINITY, f64::INFINITY),
            (f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for &(x, y) in poly {
            let d = t.dot(x, y);
            a = (a.0.min(d.0), a.1.min(d.1));
            b = (b.0.max(d.0), b.1.max(d.1));
        }
        let (lo_x, hi_x) = (a.0.floor().max(0.0), b.0.ceil().min(canvas.dots_x()));
        let (lo_y, hi_y) = (a.1.floor().max(0.0), b.1.ceil().min(canvas.dots_y()));
        let mut dy = lo_y;
        while dy < hi_y {
            let mut dx = lo_x;
            while dx < hi_x {
                let (px, py) = t.point(dx, dy);
                if super::polygon_distance(poly, px, py) == 0.0 {
                    canvas.dot(dx + 0.5, dy + 0.5, fill, 2);
                }
                dx += 1.0;
            }
            dy += 1.0;
        }
        let outline = rgb(base);
        for k in 0..poly.len() {
            let p = poly[k];
            let q = poly[(k + 1) % poly.len()];
            canvas.line(t.dot(p.0, p.1), t.dot(q.0, q.1), outline, 3);
        }
    }
    let eye = t.dot(app.x, app.y);
    let heading = app.heading();
    let half = app.fov() / 2.0;
    // Rays to the vertices causing the view's boundaries.
    if let Ok(frame) = &app.frame {
        for s in &frame.view {
            let Some(v) = s.start_vertex.and_then(|v| scene.vertices().get(v)) else {
                continue;
            };
            let (vx, vy) = v.to_f64();
            let off = (s.start_radians - heading + TAU / 2.0).rem_euclid(TAU) - TAU / 2.0;
            let (colour, priority) = if off.abs() <= half {
                (Color::Rgb(190, 165, 60), 1)
            } else {
                (Color::Rgb(55, 55, 68), 0)
            };
            canvas.line(eye, t.dot(vx, vy), colour, priority);
        }
    }
    // At depth > 0: the rays of a few sample columns through their reflections.
    if let Ok(frame) = &app.frame {
        if frame.depth > 0 && !frame.view.is_empty() {
            const SAMPLES: usize = 7;
            const GENERATIONS: [Color; 4] = [
                Color::Rgb(255, 235, 120),
                Color::Rgb(120, 230, 255),
                Color::Rgb(255, 140, 220),
                Color::Rgb(150, 255, 150),
            ];
            let q = frame.q.to_f64();
            for k in 0..SAMPLES {
                let a = heading + half - app.fov() * (k as f64 + 0.5) / SAMPLES as f64;
                let i = interval_at(&frame.view, &direction_angle(a));
                let branch = &frame.view[i].branch;
                let escaped = super::escapes(world, branch, frame.depth);
                let stages =
                    super::trace_branch(world, q, a, branch, escaped, 0.25 * world.extent());
                for (g, st) in stages.iter().enumerate() {
                    let colour = GENERATIONS[g % GENERATIONS.len()];
                    canvas.line(
                        t.dot(st.from.0, st.from.1),
                        t.dot(st.to.0, st.to.1),
                        colour,
                        4,
                    );
                }
            }
        }
    }
    // Field of view.
    let reach = 0.12 * world.extent();
    for a in [heading - half, heading + half] {
        let end = t.dot(app.x + reach * a.cos(), app.y + reach * a.sin());
        canvas.line(eye, end, Color::Rgb(120, 220, 255), 5);
    }
    let cell = (
        (eye.0 / 2.0).floor().clamp(0.0, f64::from(area.width - 1)) as u16,
        (eye.1 / 4.0).floor().clamp(0.0, f64::from(area.height - 1)) as u16,
    );
    canvas.label(cell.0, cell.1, "@", Color::Rgb(255, 80, 80));
    canvas.render(area, buf);
    if let Some(c) = buf.cell_mut((area.x + cell.0, area.y + cell.1)) {
        c.set_style(Style::default().add_modifier(Modifier::BOLD));
    }
}

// ----- dual space -----

/// Samples the cylinders' outlines in `(θ, u)` (once per complex), u measured from the
/// middle of the scene's bounding box.
fn outlines(app: &App) -> Outlines {
    let world = &app.world;
    let sub = world.sub();
    let scene = sub.as_ref();
    let complex = &world.complex;
    let (cx, cy) = centre(app);
    let wall = |w: Wall, zero: f64| -> f64 {
        complex
            .wall_angle(&scene, w)
            .map_or(zero, |a: Angle| a.radians())
    };
    let chain_at = |c: Chain, theta: f64| -> f64 {
        let v = tangent_vertex(&scene, c.object, &direction_angle(theta), c.bound);
        let (vx, vy) = scene.vertices().get(v).map_or((0.0, 0.0), |p| p.to_f64());
        theta.cos() * (vy - cy) - theta.sin() * (vx - cx)
    };
    let cylinders = complex
        .cylinders()
        .iter()
        .map(|c| {
            let left = wall(c.left, 0.0);
            let mut right = wall(c.right, TAU);
            if right < left {
                right = TAU;
            }
            let span = right - left;
            let k = ((span / TAU * 96.0).ceil() as usize).clamp(1, 12);
            let eps = span * 1e-6;
            let sample = |chain: Option<Chain>| -> Option<Vec<(f64, f64)>> {
                chain.map(|ch| {
                    (0..=k)
                        .map(|i| {
                            let th = left + span * i as f64 / k as f64;
                            (th, chain_at(ch, th.clamp(left + eps, right - eps)))
                        })
                        .collect()
                })
            };
            let (bottom, top) = (sample(c.bottom), sample(c.top));
            let lo = bottom.as_ref().map_or(f64::NEG_INFINITY, |p| {
                p.iter().map(|x| x.1).fold(f64::INFINITY, f64::min)
            });
            let hi = top.as_ref().map_or(f64::INFINITY, |p| {
                p.iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max)
            });
            Outline {
                left,
                right,
                bottom,
                top,
                lo,
                hi,
            }
        })
        .collect();
    Outlines { cylinders }
}

/// The point lines are measured from in the dual pane: the middle of the scene.
fn centre(app: &App) -> (f64, f64) {
    let (x0, y0, x1, y1) = app.world.bbox;
    ((x0 + x1) / 2.0, (y0 + y1) / 2.0)
}

/// The window of the dual pane: θ from `a` to `a + width` (radians, unwrapped) and u from
/// `u0` to `u1`.
#[derive(Clone, Copy, Debug)]
struct Window {
    a: f64,
    width: f64,
    u0: f64,
    u1: f64,
}

/// Draws one cylinder outline — its chains, and with `walls` its vertical walls — shifted
/// by `shift` in θ (for the wrap through 2π).
#[allow(clippy::too_many_arguments)]
fn draw_outline(
    canvas: &mut Braille,
    t: &Transform,
    o: &Outline,
    shift: f64,
    w: &Window,
    walls: bool,
    colour: Color,
    p: u8,
) {
    let mut chain = |pts: &Option<Vec<(f64, f64)>>| {
        if let Some(pts) = pts {
            for s in pts.windows(2) {
                canvas.line(
                    t.dot(s[0].0 + shift, s[0].1),
                    t.dot(s[1].0 + shift, s[1].1),
                    colour,
                    p,
                );
            }
        }
    };
    chain(&o.bottom);
    chain(&o.top);
    if !walls {
        return;
    }
    // Walls from the bottom arc to the top arc (the edge of the window if unbounded).
    let end = |pts: &Option<Vec<(f64, f64)>>, first: bool, default: f64| {
        pts.as_ref()
            .and_then(|p| if first { p.first() } else { p.last() })
            .map_or(default, |p| p.1)
    };
    for (theta, first) in [(o.left, true), (o.right, false)] {
        let lo = end(&o.bottom, first, w.u0 - 1.0);
        let hi = end(&o.top, first, w.u1 + 1.0);
        canvas.line(
            t.dot(theta + shift, lo),
            t.dot(theta + shift, hi),
            colour,
            p,
        );
    }
}

/// The θ shifts (multiples of 2π) that bring `[l, r]` into the window, if any.
fn shifts(l: f64, r: f64, w: &Window) -> impl Iterator<Item = f64> + '_ {
    [-TAU, 0.0, TAU]
        .into_iter()
        .filter(move |s| r + s >= w.a && l + s <= w.a + w.width)
}

fn draw_dual(app: &App, cache: &mut Cache, area: Rect, buf: &mut Buffer) -> String {
    let generation = app.world.generation;
    if cache
        .outlines
        .as_ref()
        .is_none_or(|(g, _)| *g != generation)
    {
        cache.outlines = Some((generation, outlines(app)));
    }
    let Some((_, outlines)) = &cache.outlines else {
        return String::new();
    };
    // θ: the field of view and a quarter of it on each side; u: the trace over that
    // range, and a margin that the zoom keys scale.
    let (cx, cy) = centre(app);
    let (qx, qy) = (app.x - cx, app.y - cy);
    let u = |th: f64| th.cos() * qy - th.sin() * qx;
    let width = (app.fov() * 1.5).min(TAU);
    let a = app.heading() - width / 2.0;
    let samples = 64;
    let (mut u0, mut u1) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..=samples {
        let v = u(a + width * f64::from(i) / f64::from(samples));
        u0 = u0.min(v);
        u1 = u1.max(v);
    }
    let margin = app.dual_zoom * app.world.extent();
    let w = Window {
        a,
        width,
        u0: u0 - margin,
        u1: u1 + margin,
    };
    let mut canvas = Braille::new(area.width, area.height);
    let t = Transform {
        x0: w.a,
        y0: w.u0,
        w: w.width,
        h: w.u1 - w.u0,
        dots_x: canvas.dots_x(),
        dots_y: canvas.dots_y(),
    };
    let active: Vec<bool> = {
        let mut v = vec![false; outlines.cylinders.len()];
        if let Ok(f) = &app.frame {
            for c in &f.active {
                if let Some(x) = v.get_mut(c.index()) {
                    *x = true;
                }
            }
        }
        v
    };
    let mut shown = 0usize;
    for (i, o) in outlines.cylinders.iter().enumerate() {
        if o.hi < w.u0 || o.lo > w.u1 {
            continue;
        }
        let (colour, p) = if active[i] {
            (Color::Rgb(90, 170, 235), 3)
        } else {
            (Color::Rgb(62, 64, 86), 1)
        };
        let mut any = false;
        for s in shifts(o.left, o.right, &w) {
            draw_outline(&mut canvas, &t, o, s, &w, active[i], colour, p);
            any = true;
        }
        shown += usize::from(any);
    }
    // Field of view.
    for th in [
        app.heading() - app.fov() / 2.0,
        app.heading() + app.fov() / 2.0,
    ] {
        canvas.line(
            t.dot(th, w.u0),
            t.dot(th, w.u1),
            Color::Rgb(170, 150, 50),
            2,
        );
    }
    // The trace, and the view's boundaries on it.
    let n = (canvas.dots_x() as usize).max(2);
    let mut prev = t.dot(w.a, u(w.a));
    for i in 1..=n {
        let th = w.a + w.width * i as f64 / n as f64;
        let p = t.dot(th, u(th));
        // Two dots thick, so that it stands out of the outlines.
        canvas.line(prev, p, Color::Rgb(255, 60, 60), 5);
        canvas.line(
            (prev.0, prev.1 + 1.0),
            (p.0, p.1 + 1.0),
            Color::Rgb(255, 60, 60),
            5,
        );
        prev = p;
    }
    // The view's boundaries: white ticks above and below the trace.
    if let Ok(frame) = &app.frame {
        for s in &frame.view {
            for sh in shifts(s.start_radians, s.start_radians, &w) {
                let th = s.start_radians + sh;
                let (x, y) = t.dot(th, u(th));
                for dy in [-4.0, -3.0, 4.0, 5.0] {
                    canvas.dot(x, y + dy, Color::White, 6);
                }
            }
        }
    }
    let deg = |r: f64| r.to_degrees().rem_euclid(360.0);
    let bottom = area.height.saturating_sub(1);
    canvas.label(0, 0, format!("u {:+.1}", w.u1), Color::Gray);
    canvas.label(
        0,
        bottom,
        format!("u {:+.1}  θ {:.0}°", w.u0, deg(w.a)),
        Color::Gray,
    );
    let right = format!("θ {:.0}°", deg(w.a + w.width));
    canvas.label(
        area.width.saturating_sub(right.chars().count() as u16),
        bottom,
        right,
        Color::Gray,
    );
    canvas.render(area, buf);
    format!("{shown}/{} cylinders", outlines.cylinders.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::World;

    fn text(buf: &Buffer) -> String {
        let a = buf.area;
        (0..a.height)
            .map(|y| {
                (0..a.width)
                    .map(|x| buf[(x, y)].symbol())
                    .collect::<String>()
                    + "\n"
            })
            .collect()
    }

    #[test]
    fn renders_panes_status_and_small_terminals() {
        let mut app = App::new(World::builtin().unwrap());
        let mut cache = Cache::default();
        let area = Rect::new(0, 0, 120, 40);
        let mut buf = Buffer::empty(area);
        render(&app, &mut cache, area, &mut buf);
        let t = text(&buf);
        for s in [
            "┌ View",
            "┌ Map",
            "┌ Dual space (θ, u)",
            "fps ",
            "events/frame ",
            "depth 0",
        ] {
            assert!(t.contains(s), "{s}:\n{t}");
        }
        assert!(t.contains("cylinders │ z/x zoom"), "{t}");
        // The view pane is drawn with quadrant glyphs and true colours.
        assert!(t.contains('▀') || t.contains('▄'), "{t}");
        app.key(crate::demo::app::Key::Char('1'));
        let mut buf = Buffer::empty(area);
        render(&app, &mut cache, area, &mut buf);
        assert!(!text(&buf).contains("┌ View"));
        let small = Rect::new(0, 0, 30, 8);
        let mut buf = Buffer::empty(small);
        render(&app, &mut cache, small, &mut buf);
        assert!(text(&buf).contains("too small"), "{}", text(&buf));
    }

    #[test]
    fn quadrant_picks_the_split() {
        let (a, b) = ((0.0, 0.0, 0.0), (255.0, 255.0, 255.0));
        assert_eq!(quadrant([a, a, a, a]).0, ' ');
        let (g, fg, bg) = quadrant([b, b, a, a]);
        assert_eq!((g, fg, bg), ('▀', b, a));
        let (g, fg, bg) = quadrant([a, b, a, b]);
        assert_eq!((g, fg, bg), ('▌', a, b));
        assert_eq!(quadrant([b, a, a, a]).0, '▘');
        // The diagonal: TR and BL in the foreground, the same picture as ▚ inverted.
        assert_eq!(quadrant([b, a, a, b]), ('▞', a, b));
    }
}
