//! Helpers shared by the CLI tests (`mod common;`): the built binary, temporary paths,
//! example scenes, and the two outcomes every command has (success with a clean stderr,
//! or exit status 2 with one `error: ` line). Each test crate uses a subset.
#![allow(dead_code)]

use core::sync::atomic::{AtomicUsize, Ordering};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub const VCX: &str = env!("CARGO_BIN_EXE_vcx");

/// A fresh path in a per-process temporary directory.
pub fn temp_path(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!("vcx-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    dir.join(format!("{n}-{name}"))
}

/// The example scene `std-demo/scenes/NAME.json`.
pub fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.json"))
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

pub fn vcx(args: &[&str]) -> Output {
    Command::new(VCX).args(args).output().unwrap()
}

/// Requires exit 0 and empty stderr; returns stdout.
pub fn ok(args: &[&str]) -> String {
    let out = vcx(args);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
    assert!(stderr.is_empty(), "{args:?}: {stderr}");
    String::from_utf8(out.stdout).unwrap()
}

/// Requires exit 2, empty stdout and one `error: ` line containing every string of
/// `expect`; returns the whole stderr.
pub fn fails(args: &[&str], expect: &[&str]) -> String {
    let out = vcx(args);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(out.stdout.is_empty(), "{args:?}: stdout not empty");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
    assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    for e in expect {
        assert!(stderr.contains(e), "{args:?}: {e:?} not in {stderr}");
    }
    stderr
}
