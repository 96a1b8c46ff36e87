//! Puts the memory layout — `memory-device.x` (an nRF52840-class Cortex-M4F) for thumbv7em,
//! `memory-rp2040.x` for thumbv6m, `memory-qemu.x` with the feature `qemu` — as `memory.x`
//! where the linker script of cortex-m-rt finds it. (No `memory.x` in this directory: the
//! linker would find that one first.)
use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let target = env::var("TARGET").unwrap_or_default();
    let memory = if env::var_os("CARGO_FEATURE_QEMU").is_some() {
        "memory-qemu.x"
    } else if target.starts_with("thumbv6m") {
        "memory-rp2040.x"
    } else {
        "memory-device.x"
    };
    fs::copy(memory, out.join("memory.x")).expect("memory files are next to build.rs");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=memory-device.x");
    println!("cargo:rerun-if-changed=memory-rp2040.x");
    println!("cargo:rerun-if-changed=memory-qemu.x");
}
