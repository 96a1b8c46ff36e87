//! Views walked in the complex against the exact reference view (intervals, objects,
//! boundary directions and vertices) on degenerate scenes, from viewpoints on grid points,
//! on edge extensions and bitangents, and next to vertices. Screens are left out of the
//! complex and are transparent in the reference. See `vcx_tests::generators`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use vcx_tests::generators::{check_walk, WalkInput};

fuzz_target!(|input: WalkInput| {
    if let Err(e) = check_walk(&input) {
        panic!("{e}\ninput: {input:?}");
    }
});
