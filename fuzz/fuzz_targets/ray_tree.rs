//! Ray trees at depth 1–2 (mirrors, refraction by the tangent law, screens) walked in the
//! complex against the exact reference with eyes rounded as the core rounds them, on
//! degenerate scenes and viewpoints. See `vcx_tests::generators`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use vcx_tests::generators::{check_ray_tree, RayTreeInput};

fuzz_target!(|input: RayTreeInput| {
    if let Err(e) = check_ray_tree(&input) {
        panic!("{e}\ninput: {input:?}");
    }
});
