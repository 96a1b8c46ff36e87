//! Fixed-width signed integers for the exact tests that outgrow `i128`: a ray-tree
//! boundary direction mapped back through several hops grows by about 102 bits per hop
//! (`walk::tree`). Sign and magnitude, 1024-bit magnitude; every operation is checked and
//! returns `None` instead of wrapping, so a caller can fall back when a budget is exceeded.

use core::cmp::Ordering;

use super::Sign;

const LIMBS: usize = 16;

/// A signed integer of magnitude below 2¹⁰²⁴.
#[derive(Clone, Copy, PartialEq, Eq, Default, Debug)]
pub(crate) struct Wide {
    negative: bool,
    /// The number of limbs up to the highest nonzero one: operations run over these only
    /// (values of a few limbs are the common case).
    len: u8,
    /// Little-endian limbs, zero from `len` on.
    mag: [u64; LIMBS],
}

impl Wide {
    /// The value of `mag`, whose limbs from `bound` on are zero. Zero is never negative
    /// and `len` is minimal, so that `==` is equality of values.
    #[inline]
    fn new(negative: bool, mag: [u64; LIMBS], bound: usize) -> Wide {
        let len = mag.get(..bound.min(LIMBS)).map_or(0, |m| {
            m.len() - m.iter().rev().take_while(|&&l| l == 0).count()
        });
        Wide {
            negative: negative && len > 0,
            len: len as u8,
            mag,
        }
    }

    pub(crate) fn from_i128(v: i128) -> Wide {
        let m = v.unsigned_abs();
        let mut mag = [0; LIMBS];
        mag[0] = m as u64;
        mag[1] = (m >> 64) as u64;
        Wide::new(v < 0, mag, 2)
    }

    fn limbs(&self) -> &[u64] {
        self.mag.get(..usize::from(self.len)).unwrap_or(&self.mag)
    }

    pub(crate) fn sign(&self) -> Sign {
        match (self.len, self.negative) {
            (0, _) => Sign::Zero,
            (_, true) => Sign::Negative,
            (_, false) => Sign::Positive,
        }
    }

    pub(crate) fn neg(self) -> Wide {
        Wide {
            negative: !self.negative && self.len > 0,
            ..self
        }
    }

    /// `self · k`, `None` past 2¹⁰²⁴.
    #[inline]
    pub(crate) fn mul_i128(&self, k: i128) -> Option<Wide> {
        let mut out = Wide::default();
        self.mul_into(k, &mut out)?;
        Some(out)
    }

    /// `self · k + o · ko`, `None` past 2¹⁰²⁴: the products built in place, not moved.
    #[inline]
    pub(crate) fn mul_add(&self, k: i128, o: &Wide, ko: i128) -> Option<Wide> {
        let (mut p, mut q) = (Wide::default(), Wide::default());
        self.mul_into(k, &mut p)?;
        o.mul_into(ko, &mut q)?;
        p.add(&q)
    }

    /// `self · k` into `out`, which is zero.
    #[inline]
    fn mul_into(&self, k: i128, out: &mut Wide) -> Option<()> {
        let neg = self.negative != (k < 0);
        let k = k.unsigned_abs();
        let (k0, k1) = (k as u64, (k >> 64) as u64);
        // Limbs above the highest nonzero one contribute nothing.
        let used = usize::from(self.len);
        if used + 2 > LIMBS {
            *out = self.mul_near_limit(neg, k0, k1)?;
            return Some(());
        }
        // The product has at most `used + 2` limbs: no overflow, no checks. Row by row, each
        // limb product plus the limb below it and a carry fits in `u128`.
        let mag = &mut out.mag;
        let src = self.limbs();
        let mut carry = 0u64;
        for (slot, &l) in mag.iter_mut().zip(src) {
            let acc = u128::from(l) * u128::from(k0) + u128::from(carry);
            *slot = acc as u64;
            carry = (acc >> 64) as u64;
        }
        if let Some(slot) = mag.get_mut(used) {
            *slot = carry;
        }
        if k1 != 0 {
            let mut carry = 0u64;
            for (slot, &l) in mag.iter_mut().skip(1).zip(src) {
                let acc = u128::from(l) * u128::from(k1) + u128::from(*slot) + u128::from(carry);
                *slot = acc as u64;
                carry = (acc >> 64) as u64;
            }
            if let Some(slot) = mag.get_mut(used + 1) {
                *slot = carry;
            }
        }
        let len = mag.get(..used + 2).map_or(0, |m| {
            m.len() - m.iter().rev().take_while(|&&l| l == 0).count()
        });
        out.negative = neg && len > 0;
        out.len = len as u8;
        Some(())
    }

    /// `self · k` for a magnitude of at most four limbs: its sign (−1, 0, 1) and five
    /// little-endian limbs of its magnitude (below 2³²⁰, no overflow), on the stack. One
    /// pass: `|k| ≤ 2⁶³` is one limb.
    #[cfg_attr(
        not(any(feature = "mirrors", feature = "refraction", feature = "screens")),
        allow(dead_code)
    )]
    #[inline]
    fn mul_short(&self, k: i64) -> (i8, [u64; 5]) {
        let mut mag = [0u64; 5];
        let src = self.limbs();
        let km = k.unsigned_abs();
        let mut carry = 0u64;
        for (slot, &l) in mag.iter_mut().zip(src) {
            let acc = u128::from(l) * u128::from(km) + u128::from(carry);
            *slot = acc as u64;
            carry = (acc >> 64) as u64;
        }
        if let Some(slot) = mag.get_mut(src.len()) {
            *slot = carry;
        }
        let sign = if self.len == 0 || k == 0 {
            0
        } else if self.negative != (k < 0) {
            -1
        } else {
            1
        };
        (sign, mag)
    }

    /// [`Wide::mul_i128`] for a magnitude within two limbs of the budget, checked per limb.
    fn mul_near_limit(&self, neg: bool, k0: u64, k1: u64) -> Option<Wide> {
        let mut mag = [0u64; LIMBS];
        let used = usize::from(self.len);
        for (shift, kl) in [(0, k0), (1, k1)] {
            if kl == 0 {
                continue;
            }
            let mut carry: u128 = 0;
            for (i, &l) in self.limbs().iter().enumerate() {
                let acc = u128::from(l) * u128::from(kl) + carry;
                match mag.get_mut(i + shift) {
                    Some(slot) => {
                        let sum = u128::from(*slot) + (acc & u128::from(u64::MAX));
                        *slot = sum as u64;
                        carry = (acc >> 64) + (sum >> 64);
                    }
                    None if acc != 0 => return None,
                    None => carry = 0,
                }
            }
            // The carry goes into the next limb, if there is one.
            match mag.get_mut(used + shift) {
                Some(slot) if carry != 0 => {
                    let sum = u128::from(*slot) + carry;
                    *slot = sum as u64;
                    if sum >> 64 != 0 {
                        return None;
                    }
                }
                None if carry != 0 => return None,
                _ => {}
            }
        }
        Some(Wide::new(neg, mag, used + 2))
    }

    /// `self + o`, `None` past 2¹⁰²⁴.
    #[inline]
    pub(crate) fn add(&self, o: &Wide) -> Option<Wide> {
        // Limbs above both operands' highest nonzero ones stay zero (but for a carry).
        let used = usize::from(self.len.max(o.len));
        let (a, b) = (
            self.mag.get(..used).unwrap_or(&self.mag),
            o.mag.get(..used).unwrap_or(&o.mag),
        );
        if self.negative == o.negative {
            let mut mag = [0u64; LIMBS];
            let mut carry = false;
            for ((slot, &a), &b) in mag.iter_mut().zip(a).zip(b) {
                let (s, c1) = a.overflowing_add(b);
                let (s, c2) = s.overflowing_add(u64::from(carry));
                *slot = s;
                carry = c1 || c2;
            }
            if carry {
                *mag.get_mut(used)? = 1;
            }
            return Some(Wide::new(self.negative, mag, used + 1));
        }
        // Opposite signs: the larger magnitude minus the smaller, with the larger's sign.
        let (big, small, negative) = match cmp_mag(self, o) {
            Ordering::Less => (b, a, o.negative),
            _ => (a, b, self.negative),
        };
        let mut mag = [0u64; LIMBS];
        let mut borrow = false;
        for ((slot, &a), &b) in mag.iter_mut().zip(big).zip(small) {
            let (d, b1) = a.overflowing_sub(b);
            let (d, b2) = d.overflowing_sub(u64::from(borrow));
            *slot = d;
            borrow = b1 || b2;
        }
        Some(Wide::new(negative, mag, used))
    }

    /// `self − o`.
    #[cfg(test)]
    pub(crate) fn sub(&self, o: &Wide) -> Option<Wide> {
        self.add(&o.neg())
    }

    /// `self mod P` for the prime `P = 2⁶¹ − 1`, in `[0, P)`, to test the modular
    /// arithmetic of callers (`walk::tree` maps directions modulo P) against `Wide`'s.
    #[cfg(test)]
    pub(crate) fn residue(&self) -> u64 {
        // 2⁶⁴ ≡ 2³ (mod 2⁶¹ − 1): Horner from the top limb.
        let r = self
            .limbs()
            .iter()
            .rev()
            .fold(0u64, |r, &l| mod_p((u128::from(r) << 64) + u128::from(l)));
        if self.negative && r != 0 {
            P - r
        } else {
            r
        }
    }

    /// `u.0 · v.1 − u.1 · v.0`.
    pub(crate) fn cross(u: &(Wide, Wide), v: (i128, i128)) -> Option<Wide> {
        let (mut p, mut q) = (Wide::default(), Wide::default());
        u.0.mul_into(v.1, &mut p)?;
        u.1.mul_into(v.0, &mut q)?;
        q.negative = !q.negative && q.len > 0;
        p.add(&q)
    }

    /// The sign of [`Wide::cross`] (`None` exactly where it is): the two products compared,
    /// without forming their difference.
    #[cfg_attr(
        not(any(feature = "mirrors", feature = "refraction", feature = "screens")),
        allow(dead_code)
    )]
    pub(crate) fn cross_sign(u: &(Wide, Wide), v: (i128, i128)) -> Option<Sign> {
        // The common case (a range end mapped through one hop, against a query difference,
        // an `i64` widened): both products within five limbs, compared without forming
        // `Wide`s.
        let short = match (i64::try_from(v.0), i64::try_from(v.1)) {
            (Ok(v0), Ok(v1)) if u.0.len <= 4 && u.1.len <= 4 => Some((v0, v1)),
            _ => None,
        };
        if let Some((v0, v1)) = short {
            let (p, q) = (u.0.mul_short(v1), u.1.mul_short(v0));
            return Some(match p.0.cmp(&q.0) {
                Ordering::Greater => Sign::Positive,
                Ordering::Less => Sign::Negative,
                Ordering::Equal if p.0 == 0 => Sign::Zero,
                // Equal signs: the magnitudes decide, reversed for negative products.
                Ordering::Equal => {
                    let by_mag = p.1.iter().rev().cmp(q.1.iter().rev());
                    let by_mag = if p.0 < 0 { by_mag.reverse() } else { by_mag };
                    match by_mag {
                        Ordering::Greater => Sign::Positive,
                        Ordering::Equal => Sign::Zero,
                        Ordering::Less => Sign::Negative,
                    }
                }
            });
        }
        let (mut p, mut q) = (Wide::default(), Wide::default());
        u.0.mul_into(v.1, &mut p)?;
        u.1.mul_into(v.0, &mut q)?;
        // Opposite signs add the magnitudes, which may pass the budget.
        if p.negative != q.negative && usize::from(p.len.max(q.len)) == LIMBS {
            return Some(p.add(&q.neg())?.sign());
        }
        Some(match p.cmp(&q) {
            Ordering::Greater => Sign::Positive,
            Ordering::Equal => Sign::Zero,
            Ordering::Less => Sign::Negative,
        })
    }

    /// `u.0 · v.0 + u.1 · v.1`.
    pub(crate) fn dot(u: &(Wide, Wide), v: (i128, i128)) -> Option<Wide> {
        u.0.mul_add(v.0, &u.1, v.1)
    }
}

impl Ord for Wide {
    fn cmp(&self, o: &Wide) -> Ordering {
        match (self.negative, o.negative) {
            (false, true) => Ordering::Greater,
            (true, false) => Ordering::Less,
            (false, false) => cmp_mag(self, o),
            (true, true) => cmp_mag(o, self),
        }
    }
}

impl PartialOrd for Wide {
    fn partial_cmp(&self, o: &Wide) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// The Mersenne prime 2⁶¹ − 1 of [`Wide::residue`].
pub(crate) const P: u64 = (1 << 61) - 1;

/// `x mod P` for any `x < 2¹²⁸` (folding: `2⁶¹ ≡ 1`).
pub(crate) fn mod_p(x: u128) -> u64 {
    let p = u128::from(P);
    let x = (x & p) + (x >> 61); // < 2⁶¹ + 2⁶⁷
    let x = (x & p) + (x >> 61); // < 2⁶¹ + 2⁷
    let x = x as u64;
    if x >= P {
        x - P
    } else {
        x
    }
}

/// `v mod P` of a signed 128-bit integer, in `[0, P)`.
pub(crate) fn residue_i128(v: i128) -> u64 {
    let r = mod_p(v.unsigned_abs());
    if v < 0 && r != 0 {
        P - r
    } else {
        r
    }
}

/// `v as f64` (nearest, ties to even), bit for bit, without the software `i128` conversion
/// that dominates the `f64` placing of ray-tree range ends: through `i64` when `v` fits,
/// else its 64 leading bits with the rest folded into the lowest one (a sticky bit: the
/// 11 bits `f64` drops decide the rounding, and the folded bit only breaks an exact tie
/// upwards when something below it is nonzero), converted and scaled by a power of two.
pub(crate) fn i128_to_f64(v: i128) -> f64 {
    if let Ok(v) = i64::try_from(v) {
        return v as f64;
    }
    let m = v.unsigned_abs();
    // `m ≥ 2⁶³`: drop `k ≤ 64` bits to keep 64.
    let k = (128 - m.leading_zeros()).saturating_sub(64);
    let sticky = m.trailing_zeros() < k;
    let top = (m >> k) as u64 | u64::from(sticky);
    // `2ᵏ` exactly (`k ≤ 64`), and the product is exact.
    let r = top as f64 * f64::from_bits((1023 + u64::from(k)) << 52);
    if v < 0 {
        -r
    } else {
        r
    }
}

/// Order of the magnitudes: the longer is larger, else the first differing limb from the top.
fn cmp_mag(a: &Wide, b: &Wide) -> Ordering {
    a.len
        .cmp(&b.len)
        .then_with(|| a.limbs().iter().rev().cmp(b.limbs().iter().rev()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::xorshift;

    fn w(v: i128) -> Wide {
        Wide::from_i128(v)
    }

    #[test]
    fn i128_to_f64_is_the_cast() {
        let check = |v: i128| {
            for v in [v, v.wrapping_neg()] {
                assert_eq!(i128_to_f64(v).to_bits(), (v as f64).to_bits(), "{v}");
            }
        };
        for v in [0, 1, i128::MAX, i128::MIN, i128::MIN + 1] {
            check(v);
        }
        // Powers of two, ties and near-ties at the rounding bit of every length.
        for s in 53..127 {
            for d in [-3i128, -1, 0, 1, 3] {
                check((1i128 << s) + d);
                check((3i128 << (s - 1)) + d);
                check((1i128 << s) + (1i128 << (s - 53)) + d);
                check((1i128 << s) + (3i128 << (s - 53)) + d);
            }
        }
        let mut next = xorshift(0x2545_f491_4f6c_dd1du64);
        for _ in 0..50_000 {
            let v = ((u128::from(next()) << 64 | u128::from(next())) >> (next() % 128)) as i128;
            check(v);
            // The same with the bits below the rounding bit cleared: exact ties.
            let k = 128 - v.unsigned_abs().leading_zeros();
            if k > 54 {
                let t = (v >> (k - 54)) << (k - 54);
                check(t);
                check(t + 1);
                check(t - 1);
            }
        }
    }

    /// The unchecked product agrees with the limb-checked one (the original) at every
    /// length, and sums with the difference of the product and its parts.
    #[test]
    fn fast_product_agrees_with_checked_product() {
        let mut next = xorshift(0x9e37_79b9_7f4a_7c15u64);
        for round in 0..4000 {
            let mut x = w(1);
            let steps = round % 14;
            for _ in 0..steps {
                let k = ((u128::from(next()) << 64 | u128::from(next())) >> (next() % 100)) as i128;
                x = x.mul_i128(k | 1).unwrap_or(x);
            }
            let k = ((u128::from(next()) << 64 | u128::from(next())) >> (next() % 128)) as i128;
            for k in [k, -k, 0, 1, -1] {
                let (neg, m) = (x.negative != (k < 0), k.unsigned_abs());
                let slow = x.mul_near_limit(neg, m as u64, (m >> 64) as u64);
                assert_eq!(x.mul_i128(k), slow, "round {round}");
                let fused = slow.and_then(|p| p.add(&x.mul_i128(3 - k)?));
                assert_eq!(x.mul_add(k, &x, 3 - k), fused, "round {round}");
                if let Some(p) = slow {
                    // p − x·k = 0 and p + (−p) = 0 through `add`'s two paths.
                    assert_eq!(p.add(&p.neg()), Some(w(0)));
                    let twice = p.add(&p);
                    assert_eq!(twice, p.mul_i128(2), "round {round}");
                    if let Some(t) = twice {
                        assert_eq!(t.sub(&p), Some(p), "round {round}");
                        assert_eq!(p.sub(&t), Some(p.neg()), "round {round}");
                    }
                }
            }
        }
    }

    #[test]
    fn cross_sign_is_the_sign_of_cross() {
        let mut next = xorshift(0x1234_5678_9abc_def1u64);
        let mut big = |n: u64| {
            let mut x = w(1);
            for _ in 0..n {
                let k = ((u128::from(next()) << 64 | u128::from(next())) >> (next() % 64)) as i128;
                x = x.mul_i128(k | 1).unwrap_or(x);
            }
            x
        };
        for round in 0..3000u64 {
            let (a, b) = (big(round % 12), big((round / 12) % 12));
            let u = match round % 3 {
                0 => (a, a.neg()),
                1 => (a, a),
                _ => (a, b),
            };
            let v = match round % 5 {
                0 => (7, 7),
                1 => (-(1 << 100), 3),
                _ => (
                    (round as i128) << (round % 90),
                    -((round as i128 + 5) << (round % 70)),
                ),
            };
            let plain = u.0.mul_i128(v.1).and_then(|p| p.sub(&u.1.mul_i128(v.0)?));
            assert_eq!(Wide::cross(&u, v), plain, "round {round}");
            assert_eq!(
                Wide::cross_sign(&u, v),
                plain.map(|c| c.sign()),
                "round {round}"
            );
        }
        // The short path: four-limb magnitudes times `i64` factors up to `i64::MIN`, with
        // products equal in their top limbs (`u.1 = u.0 + d`, `v.0 = v.1`) or carries apart.
        let mut next = xorshift(0x0fed_cba9_8765_4321u64);
        let mut wide = |bits: u64| {
            let r = |x: u64| ((u128::from(x) << 64 | u128::from(x.rotate_left(17))) >> 1) as i128;
            let (a, b) = (r(next()) >> (bits % 127), r(next()));
            let sign = if next().is_multiple_of(2) { 1 } else { -1 };
            w(a).mul_i128(b * sign).unwrap_or(w(a))
        };
        let ends = [i64::MIN, i64::MIN + 1, -1, 0, 1, i64::MAX];
        for round in 0..4000u64 {
            let a = wide(round);
            let k = ends
                .get(round as usize % 8)
                .copied()
                .unwrap_or(round.wrapping_mul(0x9e37_79b9_7f4a_7c15) as i64);
            let (u, v) = match round % 4 {
                0 => ((a, a.add(&w(i128::from(round as i8))).unwrap_or(a)), (k, k)),
                1 => ((a, wide(round / 3)), (k, k / 3)),
                2 => ((a.neg(), a), (k, -k.wrapping_add(1))),
                _ => ((wide(round + 1), a), (k, i64::MAX)),
            };
            let v = (i128::from(v.0), i128::from(v.1));
            let plain = u.0.mul_i128(v.1).and_then(|p| p.sub(&u.1.mul_i128(v.0)?));
            assert_eq!(
                Wide::cross_sign(&u, v),
                plain.map(|c| c.sign()),
                "round {round}"
            );
        }
        // Zero products in the short path, and factors past 64 bits.
        let h = 1i128 << 100;
        for (u, v) in [
            ((w(0), w(5)), (3, 0)),
            ((w(0), w(-5)), (3, 2)),
            ((w(4), w(0)), (0, -2)),
            ((w(0), w(0)), (1, 1)),
            ((w(3), w(5)), (0, 0)),
            ((w(-h), w(h)), (-h, -h)),
            ((w(h), w(h + 1)), (h, h)),
        ] {
            let plain = u.0.mul_i128(v.1).and_then(|p| p.sub(&u.1.mul_i128(v.0)?));
            assert_eq!(
                Wide::cross_sign(&u, v),
                plain.map(|c| c.sign()),
                "{u:?} {v:?}"
            );
        }
    }

    #[test]
    fn small_values_agree_with_i128() {
        let vals = [
            0i128,
            1,
            -1,
            7,
            -13,
            i64::MAX as i128,
            i64::MIN as i128,
            1 << 62,
            -(1 << 62) + 3,
        ];
        for &a in &vals {
            for &b in &vals {
                assert_eq!(w(a).add(&w(b)), Some(w(a + b)), "{a} + {b}");
                assert_eq!(w(a).sub(&w(b)), Some(w(a - b)), "{a} - {b}");
                assert_eq!(w(a).mul_i128(b), Some(w(a * b)), "{a} * {b}");
                assert_eq!(w(a).cmp(&w(b)), a.cmp(&b));
            }
        }
    }

    /// Products of several limbs agree with the laws of arithmetic (pseudo-random factors
    /// up to 2¹²⁷, so that carries cross limbs and the top limbs move).
    #[test]
    fn multi_limb_arithmetic_is_consistent() {
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let hi = i128::from(x >> 1) << 63;
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (hi | i128::from(x >> 1)) * if x & 1 == 0 { 1 } else { -1 }
        };
        for _ in 0..200 {
            let (a, b, c, k1, k2) = (next(), next(), next(), next() >> 1, next() >> 1);
            let ab = w(a).mul_i128(b).unwrap().mul_i128(c).unwrap();
            let l = ab.mul_i128(k1).unwrap().mul_i128(k2).unwrap();
            let r = ab.mul_i128(k2).unwrap().mul_i128(k1).unwrap();
            assert_eq!(l, r);
            let sum = ab.mul_i128(k1).unwrap().add(&ab.mul_i128(k2).unwrap());
            assert_eq!(sum, ab.mul_i128(k1 + k2));
            assert_eq!(
                ab.mul_i128(k1).unwrap().sub(&ab.mul_i128(k1).unwrap()),
                Some(w(0))
            );
            assert_eq!(ab.neg().mul_i128(-k1), ab.mul_i128(k1));
        }
    }

    /// Residues modulo 2⁶¹ − 1 agree with `i128` arithmetic and with products far beyond it
    /// (`(a·b)·c mod P = a·b·c mod P`), signs included, and at the edges of the fold.
    #[test]
    fn residues_agree_with_arithmetic() {
        let m = |a: u64, b: u64| mod_p(u128::from(a) * u128::from(b));
        let p = P as i128;
        for v in [
            0i128,
            1,
            -1,
            p - 1,
            p,
            p + 1,
            -p,
            i128::MAX,
            i128::MIN + 1,
            1 << 100,
        ] {
            assert_eq!(w(v).residue(), v.rem_euclid(p) as u64, "{v}");
            assert_eq!(residue_i128(v), v.rem_euclid(p) as u64, "{v}");
        }
        assert_eq!(mod_p(u128::MAX), (u128::MAX % u128::from(P)) as u64);
        let (a, b, c) = (i128::MAX - 5, -(1i128 << 90) + 7, (1i128 << 126) + 3);
        let abc = w(a).mul_i128(b).unwrap().mul_i128(c).unwrap();
        let r = m(m(residue_i128(a), residue_i128(b)), residue_i128(c));
        assert_eq!(abc.residue(), r);
        assert_eq!(abc.neg().residue(), (P - r) % P);
        // The full-width all-ones magnitude: 2¹⁰²⁴ − 1 ≡ 2⁴⁸ − 1 (1024 = 16·61 + 48 and
        // 2⁶¹ ≡ 1).
        let ones = Wide::new(false, [u64::MAX; LIMBS], LIMBS);
        assert_eq!(ones.residue(), (1 << 48) - 1);
    }

    /// The extremes: (2¹²⁷ − 1)⁸ < 2¹⁰¹⁶ fits, one more factor overflows; carries run
    /// through every limb; cancellation to zero at full width.
    #[test]
    fn extremes() {
        let m = i128::MAX;
        let mut p = w(m);
        for _ in 0..7 {
            p = p.mul_i128(m).unwrap();
        }
        assert_eq!(p.sign(), Sign::Positive);
        assert!(p.mul_i128(m).is_none());
        assert!(p.mul_i128(i128::MIN).is_none());
        assert_eq!(p.mul_i128(-1).unwrap().sign(), Sign::Negative);
        assert_eq!(p.sub(&p).unwrap().sign(), Sign::Zero);
        // (2¹²⁷ − 1)⁸ · 2⁸ < 2¹⁰²⁴, and adding it to itself overflows.
        let top = p.mul_i128(1 << 8).unwrap();
        assert!(top.add(&top).is_none());
        assert_eq!(top.sub(&top.neg()), None);
        // All-ones magnitude plus one carries out.
        let ones = Wide::new(false, [u64::MAX; LIMBS], LIMBS);
        assert!(ones.add(&w(1)).is_none());
        // A carry out of both operands' top limbs lands in the next limb.
        assert_eq!(w(u64::MAX as i128).add(&w(1)), Some(w(1 << 64)));
        let all = w(i128::MAX).mul_i128(2).unwrap().add(&w(1)).unwrap(); // 2¹²⁸ − 1
        assert_eq!(all.add(&w(1)), w(1 << 64).mul_i128(1 << 64));
        assert_eq!(all.neg().add(&w(-1)), w(-(1 << 64)).mul_i128(1 << 64));
        assert_eq!(ones.sub(&w(1)).unwrap().add(&w(1)), Some(ones));
        assert_eq!(ones.cmp(&ones.sub(&w(1)).unwrap()), Ordering::Greater);
        assert_eq!(ones.neg().cmp(&ones), Ordering::Less);
        assert_eq!(w(0).neg(), w(0));
        // x² − (x − 2)(x + 2) = 4 far beyond i128: x = 2³⁰⁰.
        let x = w(1 << 100)
            .mul_i128(1 << 100)
            .unwrap()
            .mul_i128(1 << 100)
            .unwrap();
        let a = x.sub(&w(2)).unwrap();
        let b = x.add(&w(2)).unwrap();
        let xx = Wide::cross(&(x, a), (2, 1)).unwrap(); // x − 2a = −x + 4
        assert_eq!(xx.add(&x).unwrap(), w(4));
        assert_eq!(Wide::dot(&(a, b), (1, -1)).unwrap(), w(-4));
    }
}
