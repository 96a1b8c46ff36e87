//! Paths to replay: trajectory files and the built-in circuit.
//!
//! A trajectory file has one viewpoint per line, `x,y,heading_deg` (scene units; heading
//! in degrees counter-clockwise from +x). Blank lines and lines starting with `#` are
//! skipped; spaces around the numbers are allowed.

use std::path::Path;

use super::World;

/// A viewpoint and a heading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// x in scene units.
    pub x: f64,
    /// y in scene units.
    pub y: f64,
    /// Heading in degrees, counter-clockwise from +x.
    pub heading_deg: f64,
}

/// Parses a trajectory; errors name `name` and the line.
pub fn parse(text: &str, name: &str) -> Result<Vec<Pose>, String> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |why: &str| format!("{name}:{}: {why}: {line:?}", k + 1);
        let parts: Vec<&str> = line.split(',').map(str::trim).collect();
        let [x, y, h] = parts.as_slice() else {
            return Err(bad("expected x,y,heading_deg"));
        };
        let num = |s: &str| -> Result<f64, String> {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(&format!("{s:?} is not a finite number")))
        };
        out.push(Pose {
            x: num(x)?,
            y: num(y)?,
            heading_deg: num(h)?,
        });
    }
    if out.is_empty() {
        return Err(format!("{name}: no viewpoints"));
    }
    Ok(out)
}

/// Reads and parses a trajectory file.
pub fn load(path: &Path) -> Result<Vec<Pose>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    parse(&text, &path.display().to_string())
}

/// Checks that every pose is a free viewpoint of the world; the error names the pose
/// (1-based, in file order without comments) and the object.
pub fn check(world: &World, poses: &[Pose], name: &str) -> Result<(), String> {
    for (k, p) in poses.iter().enumerate() {
        let q = vcx::QueryPoint::from_f64(p.x, p.y).map_err(|_| {
            format!(
                "{name}: viewpoint {} ({}, {}) is out of range",
                k + 1,
                p.x,
                p.y
            )
        })?;
        if let Some(o) = world.blocked_at(q) {
            return Err(format!(
                "{name}: viewpoint {} ({}, {}) is inside or on {}",
                k + 1,
                p.x,
                p.y,
                world.describe(o)
            ));
        }
    }
    Ok(())
}

/// The built-in circuit: `n` viewpoints on an ellipse around the middle of the scene,
/// each pushed along its radius to a free point with some room, heading along the path.
/// Viewpoints that find no room are left out.
pub fn circuit(world: &World, n: usize) -> Vec<Pose> {
    let (x0, y0, x1, y1) = world.bbox;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let (rx, ry) = (0.3 * (x1 - x0).max(1.0), 0.3 * (y1 - y0).max(1.0));
    let room = 0.01 * world.extent();
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let phi = core::f64::consts::TAU * k as f64 / n.max(1) as f64;
        let heading = (ry * phi.cos()).atan2(-rx * phi.sin()).to_degrees();
        let found = (0..40).find_map(|j| {
            // Scales 1, 1.02, 0.98, 1.04, 0.96, …
            let step = f64::from((j + 1) / 2) * 0.02;
            let s = if j % 2 == 1 { 1.0 + step } else { 1.0 - step };
            let (x, y) = (cx + s * rx * phi.cos(), cy + s * ry * phi.sin());
            (world.clearance(x, y) >= room && world.free_f64(x, y)).then_some((x, y))
        });
        if let Some((x, y)) = found {
            out.push(Pose {
                x,
                y,
                heading_deg: heading,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_lines_and_reports_errors() {
        let p = parse("# path\n1,2,90\n\n 3.5 , -4 , 0 \n", "t").unwrap();
        assert_eq!(
            p,
            vec![
                Pose {
                    x: 1.0,
                    y: 2.0,
                    heading_deg: 90.0
                },
                Pose {
                    x: 3.5,
                    y: -4.0,
                    heading_deg: 0.0
                }
            ]
        );
        let e = parse("1,2\n", "t").unwrap_err();
        assert!(e.starts_with("t:1: expected x,y,heading_deg"), "{e}");
        let e = parse("1,2,x\n", "t").unwrap_err();
        assert!(e.contains("t:1:") && e.contains("\"x\""), "{e}");
        let e = parse("1,2,inf\n", "t").unwrap_err();
        assert!(e.contains("not a finite number"), "{e}");
        assert!(parse("# nothing\n", "t").is_err());
    }

    #[test]
    fn circuit_is_free() {
        let world = World::builtin().unwrap();
        let c = circuit(&world, 90);
        assert!(c.len() > 80, "{}", c.len());
        check(&world, &c, "circuit").unwrap();
    }
}
