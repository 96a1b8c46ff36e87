//! Degenerate scenes through validation and construction: the written scene's validation
//! agrees with an exact oracle (an error names an invalid polygon, or a touching or
//! overlapping pair), and the repaired scene's complex builds, validates, matches the
//! brute-force cross-section along axes, diagonals and edge directions, and has the
//! reference's number of free bitangents. See `vcx_tests::generators`.
//! (The issue calls this target `build`; cargo reserves that name for binaries.)
#![no_main]

use libfuzzer_sys::fuzz_target;
use vcx_tests::generators::{check_build, BuildInput};

fuzz_target!(|input: BuildInput| {
    if let Err(e) = check_build(&input) {
        panic!("{e}\ninput: {input:?}");
    }
});
