//! Simulation of Simplicity (Edelsbrunner–Mücke), implemented by literal symbolic expansion.
//!
//! A point of rank `r` has its x perturbed by `ε^(2^(2r))` and its y by `ε^(2^(2r+1))`:
//! variable `2r` and `2r + 1`. Scene vertex `i` of [`vcx::SceneRef::vertices`] has rank
//! `i + 1`; a query point has rank 0. `orient(p, q, r)` with every coordinate `c + ε_var` is
//! expanded into a multilinear polynomial whose monomials are sets of variables. A
//! monomial's exponent is the sum of `2^var` over its variables, so of two monomials the one
//! *not* containing the largest variable of their symmetric difference has the smaller
//! exponent and is more significant. The sign is that of the most significant non-zero
//! coefficient; the constant term (the exact determinant) comes first.

use core::cmp::Ordering;
use std::collections::{BTreeMap, BTreeSet};

use num_rational::BigRational;
use num_traits::{One, Signed, Zero};
use vcx::{SceneRef, Sign};

use super::Vec2;

/// A product of distinct perturbation variables.
#[derive(Clone, PartialEq, Eq, Debug)]
struct Monomial(BTreeSet<u64>);

impl Ord for Monomial {
    /// `Less` = more significant.
    fn cmp(&self, other: &Self) -> Ordering {
        match self.0.symmetric_difference(&other.0).max() {
            None => Ordering::Equal,
            Some(v) if self.0.contains(v) => Ordering::Greater,
            Some(_) => Ordering::Less,
        }
    }
}

impl PartialOrd for Monomial {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// A polynomial in the perturbation variables, terms ordered most significant first.
type Poly = BTreeMap<Monomial, BigRational>;

/// `c + ε_var`.
fn coordinate(c: &BigRational, var: u64) -> Poly {
    let mut p = Poly::new();
    p.insert(Monomial(BTreeSet::new()), c.clone());
    p.insert(Monomial([var].into()), BigRational::one());
    p
}

fn add(mut a: Poly, b: &Poly, sign: i32) -> Poly {
    for (m, c) in b {
        let e = a.entry(m.clone()).or_insert_with(BigRational::zero);
        *e += if sign < 0 { -c.clone() } else { c.clone() };
    }
    a
}

fn mul(a: &Poly, b: &Poly) -> Poly {
    let mut p = Poly::new();
    for (ma, ca) in a {
        for (mb, cb) in b {
            assert!(
                ma.0.is_disjoint(&mb.0),
                "sos_orient needs three points of distinct ranks"
            );
            let m = Monomial(ma.0.union(&mb.0).copied().collect());
            *p.entry(m).or_insert_with(BigRational::zero) += ca * cb;
        }
    }
    p
}

/// Perturbed orientation of `r` with respect to the directed line `p → q`: `Positive` if
/// `r` is to the left. Each argument is `(rank, point)`; the ranks must be distinct
/// (panics otherwise — a misuse, not a legitimate input). For three distinct ranks the
/// result is never `Zero`.
pub fn sos_orient(p: (u64, &Vec2), q: (u64, &Vec2), r: (u64, &Vec2)) -> Sign {
    let exact = q.1.sub(p.1).cross(&r.1.sub(p.1));
    if !exact.is_zero() {
        // The constant term is the most significant monomial.
        return if exact.is_positive() {
            Sign::Positive
        } else {
            Sign::Negative
        };
    }
    let x = |(rank, v): (u64, &Vec2)| coordinate(&v.x, 2 * rank);
    let y = |(rank, v): (u64, &Vec2)| coordinate(&v.y, 2 * rank + 1);
    let (ux, uy) = (add(x(q), &x(p), -1), add(y(q), &y(p), -1));
    let (vx, vy) = (add(x(r), &x(p), -1), add(y(r), &y(p), -1));
    let det = add(mul(&ux, &vy), &mul(&uy, &vx), -1);
    match det.values().find(|c| !c.is_zero()) {
        Some(c) if c.is_positive() => Sign::Positive,
        Some(_) => Sign::Negative,
        None => Sign::Zero,
    }
}

/// [`sos_orient`] of three scene vertices given by their global indices in
/// [`SceneRef::vertices`] (rank = index + 1). Panics if an index is out of range or repeated.
pub fn scene_orient(scene: SceneRef<'_>, i: usize, j: usize, k: usize) -> Sign {
    let v = |i: usize| Vec2::from_point(scene.vertices()[i]);
    let (a, b, c) = (v(i), v(j), v(k));
    sos_orient((i as u64 + 1, &a), (j as u64 + 1, &b), (k as u64 + 1, &c))
}
