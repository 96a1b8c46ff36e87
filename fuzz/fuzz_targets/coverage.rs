//! The coverage table (runs of whole columns placed by image coordinate) against the
//! column-by-column pieces of `render::coverage`, on cameras down to columns narrower than
//! the rounding of their edges and starts on and next to column edges. See
//! `vcx_tests::generators::check_coverage`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use vcx_tests::generators::{check_coverage, CoverageInput};

fuzz_target!(|input: CoverageInput| {
    if let Err(e) = check_coverage(&input) {
        panic!("{e}\ninput: {input:?}");
    }
});
