//! Test support for vcx: the **exact brute-force reference** every capability of the core
//! is judged against (DESIGN.md §8).
//!
//! The reference is deliberately simple and independent of the core's algorithms: it reads
//! only the validated scene data ([`vcx::SceneRef`]) and decides everything with big
//! rationals ([`num_rational::BigRational`]). Floats appear only in printed angles.
//!
//! * [`reference::view`] — the view from a point over the full circle;
//! * [`reference::ray_tree`] / [`reference::trace_ray`] — ray trees through mirrors and
//!   refractive objects (DESIGN.md §6 optics), screens transparent;
//! * [`reference::shoot`] / [`reference::shoot_perturbed`] — forward and backward object
//!   of a ray, exact and under the core's Simulation of Simplicity;
//! * [`reference::free_bitangents`] — free bitangents of the perturbed scene;
//! * [`reference::sos_orient`] — the perturbed orientation predicate, by symbolic expansion.

pub mod generators;
pub mod reference;

pub use reference::*;
