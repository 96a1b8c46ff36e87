//! # vcx-baselines — the classical ray casters the visibility complex is compared with
//!
//! Same scene, same optics (mirrors reflect the eye across the hit edge, refraction by the
//! tangent law at the entry and the exit edge, screens transparent and left out of the
//! branch; DESIGN.md §6) and same output (per-column branch coverage,
//! [`vcx::render::CoverageTable`]) as the exact renderer of [`vcx::render`], but by
//! shooting `s` stratified rays per column in `f64`:
//!
//! * [`Quadtree`]: the paper's classical 2D ray tracer (§6): a quadtree whose leaves hold
//!   at most one object, with neighbour links; a ray walks from leaf to leaf.
//! * [`BvhCaster`]: a bounding-volume hierarchy of the objects' boxes built and traversed
//!   by `parry2d` ([`parry2d_f64::partitioning::Bvh`], best-first `find_best`, the
//!   traversal behind its `cast_ray`).
//!
//! Both share the scene data ([`Prepared`]: every edge with its outward unit normal and
//! offset, computed once) and the exact same narrow phase (a ray against one convex
//! polygon, Cyrus–Beck clipping) and optics ([`trace`]); they differ only in how the
//! candidate objects of a ray are found. Nothing allocates per ray: a branch is a
//! fixed-capacity [`vcx::render::Branch`], and a frame reuses its table's buffers.

mod bvh;
mod prepared;
mod quadtree;
mod trace;

pub use bvh::BvhCaster;
pub use prepared::{Kind, Prepared, RayHit};
pub use quadtree::Quadtree;
pub use trace::{render, render_columns, trace, Caster};
