//! Point location against exact ray shooting (forward and backward object, under the same
//! perturbation) on degenerate scenes, from points on grid points, on lines through two
//! vertices (edge extensions, bitangents) and next to vertices, towards vertices and along
//! edges. See `vcx_tests::generators`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use vcx_tests::generators::{check_locate, LocateInput};

fuzz_target!(|input: LocateInput| {
    if let Err(e) = check_locate(&input) {
        panic!("{e}\ninput: {input:?}");
    }
});
