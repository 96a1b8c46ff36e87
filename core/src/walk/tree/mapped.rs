//! The exact directions of range ends mapped through hops, made on demand.
//!
//! A range end mapped through a hop ([`Tree::map_end`](super::Tree)) is placed by a
//! rounded `f64` direction, but an event exactly on it must still be classified exactly
//! (a vertex exactly on a mapped range end is a frequent degeneracy of grid scenes). Its
//! exact direction through the hop `prev → edge a b → next` is
//!
//! `x' = sign(den)·(den·pn + num·x)`, `den = cross(x, e)`, `pn = prev − next`,
//! `num = cross(a − prev, e)` (`e = b − a`, or its unit vector along an axis),
//!
//! or, through an axis-parallel mirror edge, `x` with one coordinate negated
//! ([`reflect_axis`]). It grows by about 110 bits per hop: 1024-bit [`Wide`]s, 272 bytes
//! each. An end does not keep it. It keeps a [`Mapped`] of 48 bytes: what the direction is
//! made of — the exact direction it started from and the hops it went through, which stay
//! on the stack as long as the end — and a certified enclosure in `f64` (midpoint and
//! radius). A test against the end ([`Mapped::turn`]) is decided by the enclosure where it
//! excludes zero; otherwise (an event exactly on the end, or an enclosure too wide) the
//! exact direction is rebuilt through the hops ([`Mapped::exact`]).
//!
//! **Enclosure.** `(m, r)` with `|x_c · 2⁻ˢ − m_c| ≤ r` for both coordinates and some
//! power of two `2ˢ` (directions are kept up to positive scale, and the midpoint is scaled
//! to `[1, 2)` after every hop). Every `f64` operation rounds to nearest with a relative
//! error of at most `u = 2⁻⁵³`; the radii below charge `U = 2⁻⁵⁰ ≥ 8u` per rounded
//! expression (each has at most three roundings, and its inputs' conversions to `f64` add
//! two), and a radius, itself rounded, is multiplied by `1 + U` (its own few roundings stay
//! below `4u`). A radius that is not finite means "no enclosure": every test is exact.
//!
//! **Budget.** Whether the exact direction fits in a `Wide` is decided when the end is
//! mapped, from a bound on its bit length (`bits`): a rebuilt direction then never
//! overflows. The bound adds two bits per hop to the true growth, so a tree past about
//! eight general hops (far beyond the depth-5 trees' usual hops) loses its exact ends
//! at most one hop earlier than a direction kept in full would.

// Only mirrors and refraction map range ends; screens alone keep the stack empty.
#![cfg_attr(
    not(any(feature = "mirrors", feature = "refraction")),
    allow(dead_code)
)]

use super::{cross, diff, diff64, eye_before, Hop};
use crate::geom::wide::{i128_to_f64 as to_f64, Wide};
use crate::geom::{Point, QueryPoint, Sign};

/// `2⁻⁵⁰`: the relative error charged per rounded expression (see the module documentation).
const U: f64 = 1.0 / (1u64 << 50) as f64;

/// Bit length of a `Wide`'s largest magnitude.
const WIDE_BITS: u32 = 1024;

/// Longest chain of hops a [`Mapped`] records (its `axis` mask).
const MAX_CHAIN: usize = 32;

/// A mapped range end's exact direction: the enclosure and the recipe (module
/// documentation). 48 bytes.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Mapped {
    /// Midpoint of the enclosure, scaled to `[1, 2)` in its larger coordinate.
    m: (f64, f64),
    /// Radius of the enclosure in both coordinates; not finite: none.
    r: f64,
    /// The exact direction the chain starts from, from the eye before hop `first`.
    origin: (i64, i64),
    /// Bit i set: hop `first + i` is an axis-parallel mirror edge mapped by [`reflect_axis`].
    axis: u32,
    /// At least the bit length of the exact direction's larger coordinate.
    bits: u16,
    /// The hops, indices in the stack of hops, `first..end`.
    first: u8,
    end: u8,
}

/// What a hop contributes to the map of a direction: `pn = prev − next`, the edge vector
/// `e1` (its unit vector along an axis: a positive scale of the result) and
/// `num1 = cross(a − prev, e1)`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Terms {
    pub pn: (i64, i64),
    pub e1: (i128, i128),
    pub num1: i128,
}

impl Terms {
    /// The terms of `hop`, which leaves the eye `prev`, whose edge's vertices are
    /// `points[hop.a()]`, `points[hop.b()]`.
    pub fn of((prev, hop): (QueryPoint, &Hop), points: &[Point]) -> Terms {
        let q = |i: usize| points.get(i).copied().unwrap_or_default().to_query();
        let a = q(hop.a());
        let e = diff(q(hop.b()), a);
        let axis = e.0 == 0 || e.1 == 0;
        let e1 = if axis {
            (e.0.signum(), e.1.signum())
        } else {
            e
        };
        Terms {
            pn: diff64(prev, hop.next),
            e1,
            num1: cross(diff(a, prev), e1),
        }
    }
}

/// The stack of hops the ends were mapped through, the eye its first hop leaves (the
/// primary eye), and the scene's vertices.
#[derive(Clone, Copy)]
pub(super) struct HopChain<'e> {
    pub eye: QueryPoint,
    pub hops: &'e [Hop],
    pub points: &'e [Point],
}

impl HopChain<'_> {
    /// The eye hop `i` leaves.
    pub fn prev(&self, i: usize) -> QueryPoint {
        eye_before(self.eye, self.hops, i)
    }
}

/// Bit length of `|v|`.
fn bits(v: i128) -> u32 {
    128 - v.unsigned_abs().leading_zeros()
}

/// `|v|`.
fn abs(v: f64) -> f64 {
    libm::fabs(v)
}

/// `cross(m, v)` and its error bound for an enclosure `(m, r)` of `x` (scaled): the exact
/// `cross(x, v)` scaled lies within the bound of the value.
fn cross_ball(m: (f64, f64), r: f64, v: (i128, i128)) -> (f64, f64) {
    let (vx, vy) = (to_f64(v.0), to_f64(v.1));
    let (p, q) = (m.0 * vy, m.1 * vx);
    let c = p - q;
    let rc = ((r * (abs(vx) + abs(vy))) * (1.0 + U) + (abs(p) + abs(q)) * U) * (1.0 + U);
    (c, rc)
}

/// The sign of an enclosed value, if the enclosure excludes zero (`false` for `NaN`).
fn certain(c: f64, rc: f64) -> Option<Sign> {
    if abs(c) > rc {
        Some(if c > 0.0 {
            Sign::Positive
        } else {
            Sign::Negative
        })
    } else {
        None
    }
}

impl Mapped {
    /// The exact direction `d` (from the eye the hop leaves) mapped through the hop at index `at` of
    /// the stack of hops, whose `den = cross(d, e1)` is not zero.
    pub fn start(d: (i64, i64), t: &Terms, at: u8) -> Option<Mapped> {
        Mapped::exactly(d, at).general(t, at, || {
            Some(Sign::of_i128(cross((d.0.into(), d.1.into()), t.e1)))
        })
    }

    /// The exact direction `d` itself, from the eye before the hop at index `at`.
    pub fn exactly(d: (i64, i64), at: u8) -> Mapped {
        let m = (d.0 as f64, d.1 as f64);
        Mapped {
            m,
            // The conversions' rounding.
            r: (abs(m.0) + abs(m.1)) * U,
            origin: d,
            axis: 0,
            bits: bits(i128::from(d.0)).max(bits(i128::from(d.1))) as u16,
            first: at,
            end: at,
        }
    }

    /// This direction (from the eye the hop leaves) mapped through the hop at index `at` of the stack
    /// of hops, right above the hops it went through: by [`reflect_axis`] if `reflect`.
    /// `None` where the exact map gives none (`den = 0`, [`reflect_axis`]'s `t = 0`, past
    /// `Wide`'s budget or past [`MAX_CHAIN`] hops).
    pub fn through(&self, c: HopChain<'_>, t: &Terms, at: u8, reflect: bool) -> Option<Mapped> {
        let chain = usize::from(at.checked_sub(self.first)?);
        if chain >= MAX_CHAIN || at != self.end {
            return None;
        }
        if !reflect {
            return self.general(t, at, || {
                Wide::cross(&self.exact(c)?, t.e1).map(|d| d.sign())
            });
        }
        // As `reflect_axis`: `cross(x, e1)` is one coordinate of `x` up to sign.
        let (first, e) = if t.e1.0 == 0 {
            (true, t.e1.1)
        } else {
            (false, -t.e1.0)
        };
        let xc = match certain(if first { self.m.0 } else { self.m.1 }, self.r) {
            Some(s) => s,
            None => {
                let x = self.exact(c)?;
                if first {
                    x.0.sign()
                } else {
                    x.1.sign()
                }
            }
        };
        let tt = xc.times(Sign::of_i128(e)).times(Sign::of_i128(t.num1));
        if tt == Sign::Zero {
            return None;
        }
        // Negated: the coordinate across the edge, or the other one where `t < 0`.
        let mut m = self.m;
        if first == (tt == Sign::Positive) {
            m.0 = -m.0;
        } else {
            m.1 = -m.1;
        }
        Some(Mapped {
            m,
            axis: self.axis | 1 << chain,
            end: at.checked_add(1)?,
            ..*self
        })
    }

    /// The general map through the hop at `at`; `exact_den`: the sign of `den` exactly, if
    /// the enclosure does not decide it (`None` past the budget). `None` for `den = 0` or
    /// past the budget.
    fn general(
        &self,
        t: &Terms,
        at: u8,
        exact_den: impl FnOnce() -> Option<Sign>,
    ) -> Option<Mapped> {
        let b = u32::from(self.bits);
        let e_bits = bits(t.e1.0).max(bits(t.e1.1));
        let pn_bits = bits(t.pn.0.into()).max(bits(t.pn.1.into()));
        // `den = cross(x, e1)` times `pn`, `num·x`, and their sum.
        let next = (b + e_bits + 1 + pn_bits).max(bits(t.num1) + b) + 1;
        if next > WIDE_BITS {
            return None;
        }
        let (d, rd) = cross_ball(self.m, self.r, t.e1);
        let s = match certain(d, rd).or_else(exact_den)? {
            Sign::Zero => return None,
            Sign::Positive => 1.0,
            Sign::Negative => -1.0,
        };
        let (n, r) = (to_f64(t.num1), self.r);
        let coord = |p: i64, m: f64| {
            let p = p as f64;
            let (dp, nm) = (d * p, n * m);
            let rv = (rd * abs(p) + abs(n) * (1.0 + U) * r + (abs(dp) + abs(nm)) * U) * (1.0 + U);
            (s * (dp + nm), rv)
        };
        let ((mx, rx), (my, ry)) = (coord(t.pn.0, self.m.0), coord(t.pn.1, self.m.1));
        let (ax, ay) = (abs(mx), abs(my));
        let big = if ax < ay { ay } else { ax };
        let r = if rx < ry { ry } else { rx };
        let exp = ((big.to_bits() >> 52) & 0x7ff) as i32 - 0x3ff;
        // A normal `big` far from the ends of the range (always: it is below 2¹²⁰).
        let (m, r) = if r.is_finite() && (-1000..1000).contains(&exp) {
            // Scaled by a power of two (exactly): the larger coordinate in [1, 2).
            let scale = f64::from_bits(((0x3ff - exp) as u64) << 52);
            ((mx * scale, my * scale), r * scale)
        } else {
            ((1.0, 0.0), f64::INFINITY)
        };
        Some(Mapped {
            m,
            r,
            bits: next as u16,
            end: at.checked_add(1)?,
            ..*self
        })
    }

    /// The sign of `cross(x, v)` for this end's exact direction `x`: by the enclosure if it
    /// decides, else exactly; `None` past `Wide`'s budget.
    #[inline]
    pub fn turn(&self, c: HopChain<'_>, v: (i128, i128)) -> Option<Sign> {
        let (x, rx) = cross_ball(self.m, self.r, v);
        certain(x, rx).or_else(|| self.turn_exact(c, v))
    }

    /// [`Mapped::turn`] on the exact direction, rebuilt (out of line: its `Wide`s take
    /// about 2 KiB of stack).
    #[inline(never)]
    fn turn_exact(&self, c: HopChain<'_>, v: (i128, i128)) -> Option<Sign> {
        Wide::cross_sign(&self.exact(c)?, v)
    }

    /// The exact direction, rebuilt through its hops as [`super::Tree::map_end`] would have
    /// mapped it in full; `None` only if its hops are no longer on the stack.
    #[inline(never)]
    pub fn exact(&self, c: HopChain<'_>) -> Option<(Wide, Wide)> {
        let first = usize::from(self.first);
        let hops = c.hops.get(first..usize::from(self.end))?;
        let mut x = (
            Wide::from_i128(self.origin.0.into()),
            Wide::from_i128(self.origin.1.into()),
        );
        let mut out = x;
        for (i, hop) in hops.iter().enumerate() {
            let t = Terms::of((c.prev(first + i), hop), c.points);
            let pn = (i128::from(t.pn.0), i128::from(t.pn.1));
            let ok = if self.axis >> i & 1 == 1 {
                reflect_axis(&x, t.e1, t.num1, &mut out)
            } else {
                Wide::cross(&x, t.e1).is_some_and(|den| scaled_hit(&x, &den, t.num1, pn, &mut out))
            };
            if !ok {
                return None;
            }
            core::mem::swap(&mut x, &mut out);
        }
        Some(x)
    }
}

/// The exact direction `x` of a range end from the previous eye mapped through an
/// axis-parallel mirror edge of unit vector `e1` (as [`super::reflected`] maps an exact angle),
/// written to `out`: `x` reflected, up to the sign of `t = num / cross(x, e1)` — no
/// products, and no growth from hop to hop. `false` (and `out` untouched) where `t` is zero.
pub(super) fn reflect_axis(
    x: &(Wide, Wide),
    e1: (i128, i128),
    num: i128,
    out: &mut (Wide, Wide),
) -> bool {
    // `cross(x, e1)`: along an axis one coordinate of `x`, up to sign.
    let den = match e1 {
        (0, s) => Sign::of_i128(s).times(x.0.sign()),
        (s, _) => Sign::of_i128(-s).times(x.1.sign()),
    };
    let t = den.times(Sign::of_i128(num));
    if t == Sign::Zero {
        return false;
    }
    *out = *x;
    // Negated: the coordinate across the edge, or the other one where `t < 0`.
    if (e1.0 == 0) == (t == Sign::Positive) {
        out.0 = out.0.neg();
    } else {
        out.1 = out.1.neg();
    }
    true
}

/// The hit point of [`super::Tree::map_end`] relative to the next eye, exactly, scaled by the
/// denominator's magnitude: `(prev − next)·den + num·d` (the direction `d` from `prev`, `num`
/// the numerator of the hit's parameter, `pn = prev − next`), written to `out`; `false` (and
/// `out` untouched) for a zero denominator or past `Wide`'s budget.
fn scaled_hit(
    d: &(Wide, Wide),
    den: &Wide,
    num: i128,
    pn: (i128, i128),
    out: &mut (Wide, Wide),
) -> bool {
    let (Some(x), Some(y)) = (den.mul_add(pn.0, &d.0, num), den.mul_add(pn.1, &d.1, num)) else {
        return false;
    };
    match den.sign() {
        Sign::Negative => *out = (x.neg(), y.neg()),
        Sign::Zero => return false,
        Sign::Positive => *out = (x, y),
    }
    true
}

#[cfg(all(test, feature = "alloc"))]
mod tests {
    use alloc::vec::Vec;

    use super::*;
    use crate::geom::point::MAX_ABS_RAW;
    use crate::geom::{xorshift, QueryPoint};

    /// The enclosure never decides a sign the exact direction does not have, and decides
    /// most: chains of up to six hops, general and axis-parallel, some grazing (the edge
    /// nearly along the direction, where errors grow most), at scene scales from 2⁴ raw
    /// units to the top of the range, against random vectors and vectors within a few units
    /// of the direction. Every kept direction is rebuilt within `Wide`'s budget.
    #[test]
    fn enclosure_decides_only_exact_signs() {
        let mut rnd = xorshift(0x9e37_79b9_7f4a_7c15);
        let mut int = |bits: u32| -> i64 {
            let v = (rnd() >> (64 - bits)) as i64;
            if rnd() & 1 == 0 {
                -v
            } else {
                v
            }
        };
        let (mut tested, mut decided, mut grazing_kept) = (0u64, 0u64, 0u64);
        for case in 0..4000 {
            let bits = [4u32, 12, 20, 30][case % 4];
            let raw = |v: i64| v.clamp(-i64::from(MAX_ABS_RAW), i64::from(MAX_ABS_RAW)) as i32;
            let mut points: Vec<Point> = Vec::new();
            let mut hops: Vec<Hop> = Vec::new();
            let q = |v: i64| v.clamp(-(1 << 52), 1 << 52);
            // Eyes up to the top of the query range, directions up to 2⁶².
            let eb = (bits + 22).min(52);
            let mut eye = QueryPoint::from_raw(q(int(eb)), q(int(eb))).unwrap();
            let d = (int(2 * bits + 2).max(1), int(2 * bits + 2));
            let mut m = Mapped::exactly(d, 0);
            // An exact zero is never decided by the enclosure.
            let start = eye;
            let chain = HopChain {
                eye: start,
                hops: &hops,
                points: &points,
            };
            let along = (i128::from(d.0) * 3, i128::from(d.1) * 3);
            assert_eq!(
                certain(cross_ball(m.m, m.r, along).0, cross_ball(m.m, m.r, along).1),
                None
            );
            assert_eq!(m.turn(chain, along), Some(Sign::Zero));
            for at in 0..(1 + case % 6) as u8 {
                let kind = int(3).unsigned_abs();
                let a = Point::from_raw(raw(int(bits)), raw(int(bits))).unwrap();
                let grazing = kind == 1;
                let e = match kind {
                    0 => (i64::from(raw(int(bits).max(1))), 0),
                    2 => (0, i64::from(raw(int(bits).max(1)))),
                    // Nearly along the direction: its midpoint scaled, plus a unit or two.
                    1 => {
                        let k = libm::ldexp(1.0, bits as i32 - 2);
                        (
                            ((m.m.0 * k) as i64).saturating_add(int(1)),
                            ((m.m.1 * k) as i64).saturating_add(int(1)),
                        )
                    }
                    _ => (int(bits), int(bits)),
                };
                let Some(b) = Point::from_raw(
                    raw(i64::from(a.x()).saturating_add(e.0)),
                    raw(i64::from(a.y()).saturating_add(e.1)),
                ) else {
                    break;
                };
                if a == b {
                    break;
                }
                let next = QueryPoint::from_raw(q(int(eb)), q(int(eb))).unwrap();
                points.extend([a, b]);
                let ends = (points.len() - 2, points.len() - 1);
                let hop = Hop::new(ends, next, 0).unwrap();
                let t = Terms::of((eye, &hop), &points);
                let axis = t.e1.0 == 0 || t.e1.1 == 0;
                let below = HopChain {
                    eye: start,
                    hops: &hops,
                    points: &points,
                };
                let reflect = axis && at > 0 && int(1) > 0;
                let mapped = if at == 0 {
                    let den = cross((d.0.into(), d.1.into()), t.e1);
                    if den == 0 {
                        break;
                    }
                    Mapped::start(d, &t, 0)
                } else {
                    m.through(below, &t, at, reflect)
                };
                hops.push(hop);
                eye = next;
                let Some(mapped) = mapped else { break };
                m = mapped;
                grazing_kept += u64::from(grazing);
                let chain = HopChain {
                    eye: start,
                    hops: &hops,
                    points: &points,
                };
                let exact = m.exact(chain).expect("within the budget");
                // Random vectors and vectors about 2⁻²⁰ rad off the direction first (`far`):
                // the enclosure should decide those.
                let mut vs: Vec<(i128, i128)> =
                    (0..4).map(|_| (int(62).into(), int(62).into())).collect();
                for k in [20, 40, 61] {
                    let s = libm::ldexp(1.0, k);
                    let (x, y) = ((m.m.0 * s) as i64, (m.m.1 * s) as i64);
                    vs.extend((0..3).map(|_| ((x + int(2)).into(), (y + int(2)).into())));
                }
                for (i, v) in vs.into_iter().enumerate() {
                    let truth = Wide::cross_sign(&exact, v);
                    let (c, rc) = cross_ball(m.m, m.r, v);
                    let far = i < 7;
                    tested += u64::from(far);
                    if let Some(s) = certain(c, rc) {
                        decided += u64::from(far);
                        assert_eq!(Some(s), truth, "case {case} hop {at}: {m:?} {v:?}");
                    }
                    assert_eq!(m.turn(chain, v), truth, "case {case} hop {at}");
                }
            }
        }
        assert!(grazing_kept > 100, "{grazing_kept}");
        // The enclosure is tight enough to matter (the rest is decided exactly).
        assert!(decided * 100 > tested * 95, "{decided} of {tested}");
    }
}
