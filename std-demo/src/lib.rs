//! # vcx-demo — the `vcx` command line and its library
//!
//! The library half holds what the binary and the integration tests share:
//!
//! * [`scene_file`]: the JSON scene interchange format — parsing with errors that name
//!   the object and vertex at fault, and writing a scene back with its extra fields.
//! * [`generate`](mod@generate): deterministic test scenes after the paper's Figs. 20–22 (grid of
//!   triangles, hall of mirrors, mixed materials).
//!
//! The binary (`src/main.rs`, one module per subcommand under `src/cmd/`) only parses
//! arguments, calls these, and turns errors into one line on stderr.

pub mod demo;
pub mod generate;
pub mod scene_file;
pub mod stress;

pub use generate::{generate, GenerateError, SceneKind};
pub use scene_file::{load, parse, to_json, ObjectMeta, ObjectSpec, SceneFile, SceneFileError};
