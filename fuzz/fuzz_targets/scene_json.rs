//! Arbitrary text into the JSON scene loader: an error or a valid scene, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|text: &str| {
    if let Ok(file) = vcx_demo::scene_file::parse(text) {
        let scene = file.scene.as_ref();
        assert!(scene.objects().iter().all(|o| o.len() >= 3));
    }
});
