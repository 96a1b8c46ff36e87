//! # vcx — exact 2D visibility with the visibility complex
//!
//! vcx implements Cho & Forsyth, *Interactive ray tracing with the visibility complex*
//! (Computers & Graphics 1999) for scenes of pairwise-disjoint convex polygons.
//!
//! The crate is `no_std` and free of `unsafe`. Every decision is an integer predicate on a
//! fixed-point grid ([`geom`]); floating point is only used to print results for people.
//!
//! Modules follow the data, and depend on each other in this order only:
//! [`geom`] → [`scene`] → (later: `line_space` → `partition` → `history` → `build` →
//! `walk` → `format`). See `ARCHITECTURE.md` in the repository.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

#[cfg(feature = "alloc")]
extern crate alloc;

#[cfg(feature = "format")]
pub mod format;
pub mod geom;
mod ids;
pub mod line_space;
pub mod partition;
pub mod render;
pub mod scene;
pub mod walk;

pub use geom::{Point, QueryPoint, Sign};
pub use scene::{Eta, Material, Object, ObjectId, SceneError, SceneRef};
#[cfg(feature = "alloc")]
pub use scene::{Scene, SubScene};
