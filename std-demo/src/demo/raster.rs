//! A braille dot canvas: every terminal cell holds 2 × 4 dots and one colour. Layers are
//! drawn with a priority; a cell takes the colour of the highest-priority dot in it.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;

/// Dot bits of a braille cell, by column and row within the cell (Unicode order).
const BITS: [[u8; 4]; 2] = [[0x01, 0x02, 0x04, 0x40], [0x08, 0x10, 0x20, 0x80]];

#[derive(Clone, Copy, Debug, PartialEq)]
struct Cell {
    mask: u8,
    color: Color,
    priority: u8,
}

/// A canvas of `width × height` cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Braille {
    width: u16,
    height: u16,
    cells: Vec<Cell>,
    /// Text drawn over the dots: (cell x, cell y, text, colour).
    labels: Vec<(u16, u16, String, Color)>,
}

impl Braille {
    /// An empty canvas.
    pub fn new(width: u16, height: u16) -> Braille {
        Braille {
            width,
            height,
            cells: vec![
                Cell {
                    mask: 0,
                    color: Color::Reset,
                    priority: 0
                };
                usize::from(width) * usize::from(height)
            ],
            labels: Vec::new(),
        }
    }

    /// Width in dots.
    pub fn dots_x(&self) -> f64 {
        f64::from(self.width) * 2.0
    }

    /// Height in dots.
    pub fn dots_y(&self) -> f64 {
        f64::from(self.height) * 4.0
    }

    /// Sets the dot at `(x, y)` (dots, y down); outside the canvas nothing happens.
    pub fn dot(&mut self, x: f64, y: f64, color: Color, priority: u8) {
        if !(x >= 0.0 && y >= 0.0 && x < self.dots_x() && y < self.dots_y()) {
            return;
        }
        let (xi, yi) = (x as usize, y as usize);
        let idx = (yi / 4) * usize::from(self.width) + xi / 2;
        if let Some(c) = self.cells.get_mut(idx) {
            c.mask |= BITS[xi % 2][yi % 4];
            if priority >= c.priority {
                c.color = color;
                c.priority = priority;
            }
        }
    }

    /// A line between two dot positions (clipped to the canvas).
    pub fn line(&mut self, a: (f64, f64), b: (f64, f64), color: Color, priority: u8) {
        let (w, h) = (self.dots_x(), self.dots_y());
        let outside = |p: (f64, f64), q: (f64, f64)| {
            (p.0 < 0.0 && q.0 < 0.0)
                || (p.1 < 0.0 && q.1 < 0.0)
                || (p.0 >= w && q.0 >= w)
                || (p.1 >= h && q.1 >= h)
        };
        if !a.0.is_finite() || !a.1.is_finite() || !b.0.is_finite() || !b.1.is_finite() {
            return;
        }
        if outside(a, b) {
            return;
        }
        let steps = (b.0 - a.0)
            .abs()
            .max((b.1 - a.1).abs())
            .ceil()
            .clamp(1.0, 4096.0);
        let n = steps as usize;
        for i in 0..=n {
            let t = i as f64 / steps;
            self.dot(
                a.0 + (b.0 - a.0) * t,
                a.1 + (b.1 - a.1) * t,
                color,
                priority,
            );
        }
    }

    /// Text at a cell, drawn over the dots.
    pub fn label(&mut self, x: u16, y: u16, text: impl Into<String>, color: Color) {
        if x < self.width && y < self.height {
            self.labels.push((x, y, text.into(), color));
        }
    }

    /// Draws the canvas into `area` of `buf` (its top-left corner; clipped to the area).
    pub fn render(&self, area: Rect, buf: &mut Buffer) {
        for y in 0..self.height.min(area.height) {
            for x in 0..self.width.min(area.width) {
                let c = self.cells[usize::from(y) * usize::from(self.width) + usize::from(x)];
                if c.mask == 0 {
                    continue;
                }
                let ch = char::from_u32(0x2800 + u32::from(c.mask)).unwrap_or(' ');
                if let Some(cell) = buf.cell_mut((area.x + x, area.y + y)) {
                    cell.set_char(ch).set_fg(c.color);
                }
            }
        }
        for (x, y, text, color) in &self.labels {
            if *y >= area.height {
                continue;
            }
            for (k, ch) in text.chars().enumerate() {
                let cx = x.saturating_add(k as u16);
                if cx >= area.width {
                    break;
                }
                if let Some(cell) = buf.cell_mut((area.x + cx, area.y + y)) {
                    cell.set_char(ch).set_fg(*color);
                }
            }
        }
    }
}

/// Maps a rectangle of the plane onto the dots of a canvas (y up in the plane, down on
/// the screen).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Left edge of the plane rectangle.
    pub x0: f64,
    /// Bottom edge.
    pub y0: f64,
    /// Width of the plane rectangle.
    pub w: f64,
    /// Height.
    pub h: f64,
    /// Canvas width in dots.
    pub dots_x: f64,
    /// Canvas height in dots.
    pub dots_y: f64,
}

impl Transform {
    /// The dot position of a plane point.
    pub fn dot(&self, x: f64, y: f64) -> (f64, f64) {
        (
            (x - self.x0) / self.w * self.dots_x,
            (1.0 - (y - self.y0) / self.h) * self.dots_y,
        )
    }

    /// The plane point at the centre of a dot.
    pub fn point(&self, dx: f64, dy: f64) -> (f64, f64) {
        (
            self.x0 + (dx + 0.5) / self.dots_x * self.w,
            self.y0 + (1.0 - (dy + 0.5) / self.dots_y) * self.h,
        )
    }

    /// A transform showing at least the rectangle `(x0, y0)..(x1, y1)` with square dots
    /// (braille dots are about square on a terminal whose cells are twice as high as wide).
    pub fn fit(bbox: (f64, f64, f64, f64), canvas: &Braille) -> Transform {
        let (x0, y0, x1, y1) = bbox;
        let (dx, dy) = (canvas.dots_x().max(1.0), canvas.dots_y().max(1.0));
        let (mut w, mut h) = ((x1 - x0).max(1e-9), (y1 - y0).max(1e-9));
        if w / h > dx / dy {
            h = w * dy / dx;
        } else {
            w = h * dx / dy;
        }
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        Transform {
            x0: cx - w / 2.0,
            y0: cy - h / 2.0,
            w,
            h,
            dots_x: dx,
            dots_y: dy,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dots_and_priorities() {
        let mut b = Braille::new(2, 1);
        b.dot(0.0, 0.0, Color::Red, 1);
        b.dot(1.0, 3.0, Color::Blue, 0);
        b.dot(3.0, 3.0, Color::Green, 2);
        b.dot(-1.0, 0.0, Color::Green, 9);
        b.dot(4.0, 0.0, Color::Green, 9);
        let mut buf = Buffer::empty(Rect::new(0, 0, 2, 1));
        b.render(Rect::new(0, 0, 2, 1), &mut buf);
        assert_eq!(buf[(0, 0)].symbol(), "\u{2881}");
        assert_eq!(buf[(0, 0)].fg, Color::Red);
        assert_eq!(buf[(1, 0)].symbol(), "\u{2880}");
    }

    #[test]
    fn fit_keeps_square_dots() {
        let b = Braille::new(40, 10); // 80 × 40 dots
        let t = Transform::fit((0.0, 0.0, 10.0, 10.0), &b);
        assert!((t.w / t.h - 2.0).abs() < 1e-12);
        let (x, y) = t.dot(5.0, 5.0);
        assert!((x - 40.0).abs() < 1e-9 && (y - 20.0).abs() < 1e-9);
    }
}
