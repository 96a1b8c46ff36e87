//! Puts the memory layout, `memory-device.x` (or, with the feature `qemu`,
//! `memory-qemu.x`), as `memory.x` where the linker script of cortex-m-rt finds it. (No
//! `memory.x` in this directory: the linker would find that one first.)
use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let memory = if env::var_os("CARGO_FEATURE_QEMU").is_some() {
        "memory-qemu.x"
    } else {
        "memory-device.x"
    };
    fs::copy(memory, out.join("memory.x")).expect("memory files are next to build.rs");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=memory-device.x");
    println!("cargo:rerun-if-changed=memory-qemu.x");
}
