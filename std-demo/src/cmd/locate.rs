//! `vcx locate SCENE.json --at X,Y --dir DX,DY [--json]`: what a ray sees ahead and behind.
//!
//! Locates the ray from `(X, Y)` in direction `(DX, DY)` through the construction history
//! (the paper's §4.2): the live cylinder that contains it, reported by its history node id.
//! The history is the one stored in a `.vcx` file (`vcx build --history`), used as is;
//! otherwise it is built by randomized incremental construction (as `vcx build` does, with
//! the seed a `.vcx` file records, else seed 0; validated; a failure is internal, exit
//! status 3). Its ceiling is the first object the ray hits (**forward**), its floor
//! the first object hit looking the opposite way (**backward**); `null` / "nothing" means
//! the ray escapes to infinity. Object ids are indices in the scene file's `objects`.
//!
//! * `--at X,Y`: two decimal numbers, rounded to the nearest point of the query grid
//!   (2⁻³²); `|X|, |Y| ≤ 2²⁰ = 1048576`. A point that lies on a free bitangent or on the
//!   extension of an edge is decided by the symbolic perturbation (it moves by `(ε, ε²)`).
//! * `--dir DX,DY`: two decimal numbers, not both zero. Only the direction matters. The two
//!   `f64` values are converted **exactly** to an integer vector with the same direction
//!   (both are dyadic rationals: they are multiplied by the same power of two, then divided
//!   by their gcd), e.g. `0.5,0.75` becomes `(2, 3)`. If a component still exceeds 2⁵² —
//!   values whose binary exponents are far apart, such as `1,1e-30` — both are divided by
//!   the same power of two and rounded to the nearest integer, which gives the nearest
//!   direction the predicates can represent (the angular error is below 2⁻⁵¹ radian; a tiny
//!   component may become 0). The summary line then says so.
//! * Negative values may be written directly: `--at -1,0` or `--at=-1,0`.
//!
//! Output, one line on stdout: with `--json` exactly
//! `{"forward": id|null, "backward": id|null, "cylinder": id}`, otherwise a sentence.
//!
//! Errors (exit status 2, one `error: ` line): a value that is not a number, not finite or
//! out of range; a zero direction; a point inside an object or on its boundary, which the
//! line names (`error: SCENE: point (x, y) is inside object 3`, `… is on the boundary of
//! object 3`).

use std::path::PathBuf;

use serde_json::{json, Value};
use vcx::geom::point::{QUERY_FRAC_BITS, QUERY_MAX_ABS_RAW};
use vcx::geom::predicates::Direction;
use vcx::partition::{point_in_scene, Location};
use vcx::{ObjectId, QueryPoint};
use vcx_demo::SceneFile;

use super::build::{build_with, Method, EXIT_INTERNAL};
use super::{write_stdout, Failure};
use vcx::partition::BuildOptions;

/// Arguments of `vcx locate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The scene file (JSON, or a binary complex file `.vcx`: its stored history is used;
    /// without one the history is rebuilt from the file's scene).
    pub scene: PathBuf,
    /// The ray's origin, `X,Y` in scene units.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub at: String,
    /// The ray's direction, `DX,DY` (not both zero; only the direction matters).
    #[arg(long, value_name = "DX,DY", allow_hyphen_values = true)]
    pub dir: String,
    /// Print `{"forward": …, "backward": …, "cylinder": …}` instead of a sentence.
    #[arg(long)]
    pub json: bool,
}

/// Largest `|X|`, `|Y|` of `--at`, in scene units (2²⁰).
const MAX_ABS_AT: f64 = (QUERY_MAX_ABS_RAW >> QUERY_FRAC_BITS) as f64;

/// Parses the arguments, builds the complex, locates the ray and prints the answer.
pub fn run(args: &Args) -> Result<(), Failure> {
    let (x, y) = parse_pair("--at", &args.at)?;
    let q = query_point("--at", &args.at, x, y)?;
    let (dx, dy) = parse_pair("--dir", &args.dir)?;
    let (d, exact) = direction_from_f64(dx, dy)
        .map_err(|e| Failure::bad_input(format!("--dir {:?}: {}", args.dir, e.message(dx, dy))))?;

    let input = crate::input::load(&args.scene)?;
    let file = &input.file;
    let scene = file.scene.as_ref();
    let at = format!("({}, {})", number(x), number(y));
    // A point in an object needs no complex.
    if let Some(l) = point_in_scene(&scene, q) {
        return Err(in_object(&args.scene, &at, file, l));
    }
    let internal = |what: &str| Failure {
        message: format!("{}: internal: {what}", args.scene.display()),
        code: EXIT_INTERNAL,
    };
    if let Some(l) = vcx::partition::point_in_scene(&scene, q) {
        return Err(in_object(&args.scene, &at, file, l));
    }
    let built;
    let history = match input.history_for(&scene) {
        Some(h) => h,
        None => {
            let options = BuildOptions {
                seed: input
                    .stored
                    .as_ref()
                    .and_then(|s| s.header.seed)
                    .unwrap_or(0),
                ..Default::default()
            };
            built = build_with(&args.scene, &scene, Method::Ric, &options)?;
            built
                .history
                .as_ref()
                .ok_or_else(|| internal("no history"))?
        }
    };
    // Point location through the history of the randomized construction (§4.2).
    let (cylinder, c) = history
        .locate(&scene, q, d)
        .ok_or_else(|| internal(&format!("no cylinder contains the ray from {at}")))?;
    let (forward, backward) = (c.ceiling, c.floor);
    let text = if args.json {
        let id = |o: Option<ObjectId>| o.map_or(Value::Null, |o| json!(o.0));
        json!({
            "forward": id(forward),
            "backward": id(backward),
            "cylinder": cylinder.index(),
        })
        .to_string()
    } else {
        let mut line = format!(
            "{}: from {at} towards ({}, {}): forward {}, backward {} (cylinder {})",
            args.scene.display(),
            number(dx),
            number(dy),
            describe(file, forward),
            describe(file, backward),
            cylinder.index(),
        );
        if !exact {
            line.push_str(&format!(
                "; direction rounded to the integer vector ({}, {})",
                d.x, d.y
            ));
        }
        super::one_line(&line)
    };
    write_stdout(&format!("{text}\n"))
}

/// A number for people: as written by Rust, or in scientific notation if that is long.
pub(crate) fn number(v: f64) -> String {
    let plain = v.to_string();
    if plain.len() > 20 {
        format!("{v:e}")
    } else {
        plain
    }
}

/// `object 3` or `object 3 "name"`, or `nothing` for infinity.
pub(crate) fn describe(file: &SceneFile, object: Option<ObjectId>) -> String {
    match object {
        None => "nothing".to_string(),
        Some(o) => match file.meta.get(o.0 as usize).and_then(|m| m.name()) {
            Some(name) => format!("object {} {name:?}", o.0),
            None => format!("object {}", o.0),
        },
    }
}

/// The failure for a point inside or on an object.
pub(crate) fn in_object(
    path: &std::path::Path,
    at: &str,
    file: &SceneFile,
    l: Location,
) -> Failure {
    let what = match l {
        Location::Inside { object } => format!("is inside {}", describe(file, Some(object))),
        Location::OnBoundary { object } => {
            format!("is on the boundary of {}", describe(file, Some(object)))
        }
        Location::Free { .. } => "is in free space".to_string(),
    };
    Failure::bad_input(format!("{}: point {at} {what}", path.display()))
}

/// Parses `A,B` into two finite `f64`s; the failure names the option.
pub(crate) fn parse_pair(option: &str, text: &str) -> Result<(f64, f64), Failure> {
    let bad = |why: String| Failure::bad_input(format!("{option} {text:?}: {why}"));
    let mut parts = text.split(',');
    let (Some(a), Some(b), None) = (parts.next(), parts.next(), parts.next()) else {
        return Err(bad(
            "expected two numbers separated by a comma, like 1.5,-2".to_string(),
        ));
    };
    let number = |s: &str| -> Result<f64, Failure> {
        let s = s.trim();
        let v: f64 = s
            .parse()
            .map_err(|_| bad(format!("{s:?} is not a number")))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(bad(format!("{s:?} is not finite")))
        }
    };
    Ok((number(a)?, number(b)?))
}

/// The query point of `--at` (or of another `option` label), or a failure naming the
/// coordinate out of range.
pub(crate) fn query_point(option: &str, text: &str, x: f64, y: f64) -> Result<QueryPoint, Failure> {
    for (name, v) in [("X", x), ("Y", y)] {
        if QueryPoint::from_f64(v, 0.0).is_err() {
            return Err(Failure::bad_input(format!(
                "{option} {text:?}: {name} = {v} is out of range (|{name}| <= {MAX_ABS_AT})"
            )));
        }
    }
    QueryPoint::from_f64(x, y)
        .map_err(|_| Failure::bad_input(format!("{option} {text:?}: out of range")))
}

/// Why `--dir` has no direction.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum DirectionError {
    /// Both components are zero.
    Zero,
    /// A component is NaN or infinite.
    NotFinite,
}

impl DirectionError {
    fn message(self, dx: f64, dy: f64) -> String {
        match self {
            DirectionError::Zero => "the zero vector has no direction".to_string(),
            DirectionError::NotFinite => format!("({dx}, {dy}) is not finite"),
        }
    }
}

/// A non-zero finite `f64` as `(negative, odd, exponent)`: `±odd · 2^exponent`, exactly.
fn decompose(v: f64) -> Option<(bool, u64, i32)> {
    let bits = v.to_bits();
    let exp_bits = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1u64 << 52) - 1);
    let (mantissa, exponent) = if exp_bits == 0 {
        (frac, -1074)
    } else {
        (frac | (1u64 << 52), exp_bits - 1075)
    };
    if mantissa == 0 {
        return None;
    }
    let tz = mantissa.trailing_zeros();
    Some((v.is_sign_negative(), mantissa >> tz, exponent + tz as i32))
}

fn gcd(mut a: u128, mut b: u128) -> u128 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// `m · 2^k` rounded to the nearest integer (ties away from zero), for `m < 2⁵³`.
fn shift_round(m: u64, k: i64) -> u128 {
    if k >= 0 {
        // The caller keeps k small enough that this stays below 2⁶⁴.
        u128::from(m) << k.min(64)
    } else if k < -64 {
        0
    } else {
        let n = (-k) as u32;
        (u128::from(m) + (1u128 << (n - 1))) >> n
    }
}

/// The integer direction of the vector `(dx, dy)`: exact when every component of the
/// reduced vector fits in 2⁵² (the flag is `true`), otherwise the nearest representable
/// direction, obtained by dividing both components by the same power of two and rounding.
pub fn direction_from_f64(dx: f64, dy: f64) -> Result<(Direction, bool), DirectionError> {
    if !dx.is_finite() || !dy.is_finite() {
        return Err(DirectionError::NotFinite);
    }
    let max = vcx::geom::point::MAX_ABS_DIRECTION as u128;
    let sign = |neg: bool, v: u128| -> i64 {
        // v ≤ 2⁵² here.
        let v = v as i64;
        if neg {
            -v
        } else {
            v
        }
    };
    let (x, y) = match (decompose(dx), decompose(dy)) {
        (None, None) => return Err(DirectionError::Zero),
        (Some((neg, ..)), None) => (sign(neg, 1), 0),
        (None, Some((neg, ..))) => (0, sign(neg, 1)),
        (Some((nx, ox, ex)), Some((ny, oy, ey))) => {
            // Both odd parts share no factor of two, so this is the whole gcd.
            let g = gcd(u128::from(ox), u128::from(oy)) as u64;
            let (ox, oy) = (ox / g, oy / g);
            let low = ex.min(ey);
            let (ex, ey) = (i64::from(ex - low), i64::from(ey - low));
            let fits = |o: u64, e: i64| e < 64 && (u128::from(o) << e) <= max;
            if fits(ox, ex) && fits(oy, ey) {
                let (x, y) = (u128::from(ox) << ex, u128::from(oy) << ey);
                (sign(nx, x), sign(ny, y))
            } else {
                // Bit length of the larger component; divide by 2^s with s from just
                // below the point where it fits.
                let bits = |o: u64, e: i64| i64::from(64 - o.leading_zeros()) + e;
                let top = bits(ox, ex).max(bits(oy, ey));
                let mut s = (top - 53).max(1);
                loop {
                    let (rx, ry) = (shift_round(ox, ex - s), shift_round(oy, ey - s));
                    if rx <= max && ry <= max {
                        let g = gcd(rx, ry).max(1);
                        let d = Direction::new(sign(nx, rx / g), sign(ny, ry / g))
                            .ok_or(DirectionError::Zero)?;
                        return Ok((d, false));
                    }
                    s += 1;
                }
            }
        }
    };
    Direction::new(x, y)
        .map(|d| (d, true))
        .ok_or(DirectionError::Zero)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(dx: f64, dy: f64) -> (i64, i64, bool) {
        let (d, exact) = direction_from_f64(dx, dy).unwrap();
        (d.x, d.y, exact)
    }

    #[test]
    fn exact_directions() {
        assert_eq!(dir(1.0, 0.0), (1, 0, true));
        assert_eq!(dir(-3.0, 0.0), (-1, 0, true));
        assert_eq!(dir(0.0, -0.25), (0, -1, true));
        assert_eq!(dir(0.5, 0.75), (2, 3, true));
        assert_eq!(dir(-6.0, 4.0), (-3, 2, true));
        assert_eq!(dir(1e-300, 1e-300), (1, 1, true));
        assert_eq!(dir(3.0, -1e10), (3, -10_000_000_000, true));
        // 0.1 and 0.2 are dyadic: 0.2 is exactly twice 0.1 in binary.
        assert_eq!(dir(0.1, 0.2), (1, 2, true));
        // Exactly 2^52 fits.
        assert_eq!(dir(4_503_599_627_370_496.0, 1.0), (1 << 52, 1, true));
        // 0.1 = m / 2^56 with odd m < 2^53; 0.1 against 1 needs 2^56: rounded.
        let (x, y, exact) = dir(1.0, 0.1);
        assert!(!exact);
        assert!((1 << 51..=1 << 52).contains(&x));
        let ratio = y as f64 / x as f64;
        assert!((ratio - 0.1).abs() < 1e-15, "{ratio}");
    }

    #[test]
    fn rounded_directions() {
        // Exponents far apart: the small component vanishes.
        assert_eq!(dir(1.0, 1e-300), (1, 0, false));
        assert_eq!(dir(-1e300, 1.0), (-1, 0, false));
        // (2^52 + 1) · 2 against 3: coprime, and too large.
        let (x, y, exact) = dir(9_007_199_254_740_994.0, 3.0);
        assert!(!exact);
        assert!(x.unsigned_abs() <= 1 << 52 && y.unsigned_abs() <= 1 << 52);
        assert!(x > 0 && y > 0);
        // Huge equal-exponent values reduce exactly.
        assert_eq!(dir(1e300, -1e300), (1, -1, true));
        assert_eq!(dir(f64::MAX, f64::MIN_POSITIVE), (1, 0, false));
        assert_eq!(dir(f64::MIN_POSITIVE, -f64::MAX), (0, -1, false));
    }

    #[test]
    fn errors() {
        assert_eq!(direction_from_f64(0.0, -0.0), Err(DirectionError::Zero));
        assert_eq!(
            direction_from_f64(f64::NAN, 1.0),
            Err(DirectionError::NotFinite)
        );
        assert_eq!(
            direction_from_f64(1.0, f64::INFINITY),
            Err(DirectionError::NotFinite)
        );
    }
}
