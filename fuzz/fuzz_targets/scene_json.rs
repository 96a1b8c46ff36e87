//! Arbitrary text into the JSON scene loader: an error, or a scene that an exact oracle
//! accepts, that is unchanged when written and read back, and (up to 12 objects) whose
//! complex builds and validates. Never a panic. See `vcx_tests::generators`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|text: &str| {
    if let Err(e) = vcx_tests::generators::check_scene_json(text) {
        panic!("{e}\ninput: {text:?}");
    }
});
