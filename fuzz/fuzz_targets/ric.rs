//! The randomized incremental construction with history on degenerate scenes: after every
//! insertion the live partition is the rotational sweep's partition of the objects
//! inserted so far, `History::build` gives the canonical partition, and point location
//! through the history agrees with the complex and exact ray shooting. See
//! `vcx_tests::generators`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use vcx_tests::generators::{check_incremental, IncrementalInput};

fuzz_target!(|input: IncrementalInput| {
    if let Err(e) = check_incremental(&input) {
        panic!("{e}\ninput: {input:?}");
    }
});
