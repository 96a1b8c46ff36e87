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
    pub(crate) fn mul_i128(&self, k: i128) -> Option<Wide> {
        let k = (k < 0, k.unsigned_abs());
        let (k0, k1) = (k.1 as u64, (k.1 >> 64) as u64);
        let mut mag = [0u64; LIMBS];
        // Limbs above the highest nonzero one contribute nothing.
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
        Some(Wide::new(self.negative != k.0, mag, used + 2))
    }

    /// `self + o`, `None` past 2¹⁰²⁴.
    pub(crate) fn add(&self, o: &Wide) -> Option<Wide> {
        // Limbs above both operands' highest nonzero ones stay zero (but for a carry).
        let used = usize::from(self.len.max(o.len));
        if self.negative == o.negative {
            let mut mag = [0u64; LIMBS];
            let mut carry = false;
            for ((slot, &a), &b) in mag.iter_mut().zip(&self.mag).zip(&o.mag).take(used) {
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
        let (big, small) = match cmp_mag(self, o) {
            Ordering::Less => (o, self),
            _ => (self, o),
        };
        let mut mag = [0u64; LIMBS];
        let mut borrow = false;
        for ((slot, &a), &b) in mag.iter_mut().zip(&big.mag).zip(&small.mag).take(used) {
            let (d, b1) = a.overflowing_sub(b);
            let (d, b2) = d.overflowing_sub(u64::from(borrow));
            *slot = d;
            borrow = b1 || b2;
        }
        Some(Wide::new(big.negative, mag, used))
    }

    /// `self − o`.
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
        u.0.mul_i128(v.1)?.sub(&u.1.mul_i128(v.0)?)
    }

    /// `u.0 · v.0 + u.1 · v.1`.
    pub(crate) fn dot(u: &(Wide, Wide), v: (i128, i128)) -> Option<Wide> {
        u.0.mul_i128(v.0)?.add(&u.1.mul_i128(v.1)?)
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

/// Order of the magnitudes: the longer is larger, else the first differing limb from the top.
fn cmp_mag(a: &Wide, b: &Wide) -> Ordering {
    a.len
        .cmp(&b.len)
        .then_with(|| a.limbs().iter().rev().cmp(b.limbs().iter().rev()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(v: i128) -> Wide {
        Wide::from_i128(v)
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
