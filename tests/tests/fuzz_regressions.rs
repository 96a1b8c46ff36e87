//! Replays the committed fuzz regressions on stable, without libFuzzer: every file under
//! `fuzz/regressions/<target>/` other than `*.md` and `*.rs` holds raw fuzzer bytes, decoded
//! exactly as the cargo-fuzz target decodes its input (`arbitrary_take_rest`, or UTF-8 text
//! for `scene_json`) and run through the same check (`vcx_tests::generators`); every `*.rs`
//! file is an input written as a Rust expression (hand-minimized), compiled in below with
//! `include!`. See `FUZZING.md`.
//!
//! A regression of a bug that is not fixed yet is an `#[ignore]`d test naming the bug, so
//! `cargo test -- --ignored` shows what is still open; drop the `ignore` with the fix.

use std::path::{Path, PathBuf};

use vcx_tests::generators::{
    check_build, check_coverage, check_incremental, check_locate, check_ray_tree, check_scene_json,
    check_walk, decode, BuildInput, CoverageInput, IncrementalInput, LocateInput, RayTreeInput,
    WalkInput,
};

/// The targets with a directory under `fuzz/regressions/`.
const TARGETS: &[&str] = &[
    "build_complex",
    "locate",
    "walk",
    "ray_tree",
    "ric",
    "scene_json",
    "scene",
    "coverage",
];

/// `(target, file)` of the Rust-expression regressions compiled in below.
const RUST_INPUTS: &[(&str, &str)] = &[
    ("ray_tree", "no_start_on_edge_extension.rs"),
    ("ray_tree", "no_start_on_edge_extension_mirror.rs"),
    ("ray_tree", "thin_refracted_piece.rs"),
    ("ray_tree", "deep_boundary_angle_near_vertex.rs"),
    ("ray_tree", "screen_range_corrupt.rs"),
    ("ray_tree", "boundary_vertex_touching.rs"),
    ("ray_tree", "no_start_grazing_mirror.rs"),
    ("ray_tree", "no_start_far_eye_depth2.rs"),
    ("ray_tree", "boundary_vertex_mirror_corner.rs"),
    ("ray_tree", "thin_interval_below_2pi.rs"),
    ("ray_tree", "spurious_sliver_diagonal.rs"),
    ("ray_tree", "no_start_refracted_end_off_edge.rs"),
    ("ray_tree", "far_eye_range_across_zero.rs"),
    ("ray_tree", "no_start_range_near_glass_vertex.rs"),
    ("ray_tree", "far_eye_extra_piece_at_range_end.rs"),
];

fn dir(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/regressions")
        .join(target)
}

/// Runs `check` on one committed input.
fn run(target: &str, bytes: &[u8]) -> Result<(), String> {
    match target {
        "build_complex" => decode::<BuildInput>(bytes).map_or(Ok(()), |i| check_build(&i)),
        "locate" => decode::<LocateInput>(bytes).map_or(Ok(()), |i| check_locate(&i).map(drop)),
        "walk" => decode::<WalkInput>(bytes).map_or(Ok(()), |i| check_walk(&i).map(drop)),
        "ray_tree" => {
            decode::<RayTreeInput>(bytes).map_or(Ok(()), |i| check_ray_tree(&i).map(drop))
        }
        "ric" => {
            decode::<IncrementalInput>(bytes).map_or(Ok(()), |i| check_incremental(&i).map(drop))
        }
        "scene_json" => core::str::from_utf8(bytes).map_or(Ok(()), check_scene_json),
        "scene" => Ok(()),
        "coverage" => decode::<CoverageInput>(bytes).map_or(Ok(()), |i| check_coverage(&i)),
        _ => Err(format!("unknown target {target}")),
    }
}

fn read(target: &str, name: &str) -> Vec<u8> {
    let path = dir(target).join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Replays every committed regression of `target`; returns how many.
fn replay(target: &str) -> usize {
    let Ok(entries) = std::fs::read_dir(dir(target)) else {
        return 0;
    };
    let mut names: Vec<String> = entries
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.ends_with(".md") && !n.ends_with(".rs") && !n.starts_with('.'))
        .collect();
    names.sort();
    let mut failures = Vec::new();
    let mut count = 0;
    for name in names {
        count += 1;
        if let Err(e) = run(target, &read(target, &name)) {
            failures.push(format!("{target}/{name}: {e}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    count
}

#[test]
fn build_complex() {
    println!("{} replayed", replay("build_complex"));
}

#[test]
fn locate() {
    println!("{} replayed", replay("locate"));
}

#[test]
fn walk() {
    println!("{} replayed", replay("walk"));
}

#[test]
fn ray_tree() {
    println!("{} replayed", replay("ray_tree"));
}

#[test]
fn ric() {
    println!("{} replayed", replay("ric"));
}

#[test]
fn scene_json() {
    println!("{} replayed", replay("scene_json"));
}

#[test]
fn coverage() {
    println!("{} replayed", replay("coverage"));
}

/// Every directory under `fuzz/regressions/` is a target replayed above, and every `*.rs`
/// input there is compiled in below.
#[test]
fn every_regression_is_replayed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/regressions");
    let Ok(entries) = std::fs::read_dir(&root) else {
        return;
    };
    for e in entries {
        let e = e.unwrap();
        if !e.file_type().unwrap().is_dir() {
            continue;
        }
        let t = e.file_name().to_string_lossy().into_owned();
        assert!(
            TARGETS.contains(&t.as_str()),
            "fuzz/regressions/{t}: no replay for this target"
        );
        for f in std::fs::read_dir(e.path()).unwrap() {
            let f = f.unwrap().file_name().to_string_lossy().into_owned();
            if f.ends_with(".rs") {
                assert!(
                    RUST_INPUTS.contains(&(t.as_str(), f.as_str())),
                    "fuzz/regressions/{t}/{f} is not compiled into a test"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Rust-expression regressions (fuzz/regressions/<target>/*.rs).

use vcx_tests::generators::{
    Dir8::*, DirSpec::*, Gap::*, Mat::*, Obj, Place::*, PointSpec::*, RaySpec, SceneSpec, Shape::*,
    StartSpec::*,
};

#[test]
fn ray_tree_no_start_on_edge_extension() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/no_start_on_edge_extension.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_no_start_on_edge_extension_mirror() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/no_start_on_edge_extension_mirror.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_thin_refracted_piece() {
    let input: RayTreeInput = include!("../../fuzz/regressions/ray_tree/thin_refracted_piece.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_deep_boundary_angle_near_vertex() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/deep_boundary_angle_near_vertex.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_screen_range_corrupt() {
    let input: RayTreeInput = include!("../../fuzz/regressions/ray_tree/screen_range_corrupt.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_boundary_vertex_touching() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/boundary_vertex_touching.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_no_start_grazing_mirror() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/no_start_grazing_mirror.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_no_start_far_eye_depth2() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/no_start_far_eye_depth2.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_boundary_vertex_mirror_corner() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/boundary_vertex_mirror_corner.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_thin_interval_below_2pi() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/thin_interval_below_2pi.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_spurious_sliver_diagonal() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/spurious_sliver_diagonal.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_no_start_refracted_end_off_edge() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/no_start_refracted_end_off_edge.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

/// Printed inputs are Rust code: `{:?}` of an input is, up to whitespace and trailing
/// commas, the expression that builds it.
#[test]
fn printed_inputs_are_rust() {
    macro_rules! round_trip {
        ($e:expr) => {{
            // Whitespace and trailing commas (rustfmt's) aside.
            let strip = |s: &str| {
                s.split_whitespace()
                    .collect::<String>()
                    .replace(",}", "}")
                    .replace(",]", "]")
                    .replace(",)", ")")
            };
            assert_eq!(strip(&format!("{:?}", $e)), strip(stringify!($e)));
        }};
    }
    round_trip!(SceneSpec {
        step: 16,
        place: Corner {
            east: true,
            north: false,
        },
        objects: vec![
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Rect {
                    x: -3,
                    y: 0,
                    w: 2,
                    h: 16,
                },
            },
            Obj {
                material: Screen,
                reversed: true,
                rotate: 1,
                shape: Translated {
                    of: 0,
                    dir: NE,
                    gap: Unit,
                },
            },
            Obj {
                material: Glass,
                reversed: false,
                rotate: 0,
                shape: Hull {
                    points: vec![(0, 0), (4, -1), (2, 2)],
                },
            },
            Obj {
                material: Mirror,
                reversed: false,
                rotate: 0,
                shape: Reflected {
                    of: 2,
                    dir: S,
                    gap: Touch,
                },
            },
        ],
    });
    round_trip!(BuildInput {
        scene: SceneSpec {
            step: 3,
            place: Origin,
            objects: vec![Obj {
                material: Opaque,
                reversed: false,
                rotate: 2,
                shape: Written {
                    points: vec![(1, 1), (1, 1)],
                },
            }],
        },
        directions: vec![(1, -1)],
    });
    round_trip!(LocateInput {
        scene: SceneSpec {
            step: 0,
            place: Origin,
            objects: vec![Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Sliver {
                    a: (0, 0),
                    b: (5, 1),
                    left: true,
                },
            }],
        },
        rays: vec![
            RaySpec {
                from: OnLine { a: 0, b: 1, t: -3 },
                dir: Towards { v: 2 },
            },
            RaySpec {
                from: NearVertex {
                    v: 1,
                    dx: -1,
                    dy: 0,
                    shift: 16,
                },
                dir: Along { a: 0, b: 1 },
            },
            RaySpec {
                from: GridPoint { x: 1, y: 1 },
                dir: Axis(SW),
            },
            RaySpec {
                from: GridPoint { x: 1, y: 1 },
                dir: Free { x: 3, y: -7 },
            },
        ],
    });
    round_trip!(WalkInput {
        scene: SceneSpec {
            step: 20,
            place: Origin,
            objects: vec![Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Tiny { at: (0, 0) },
            }],
        },
        viewpoints: vec![GridPoint { x: 1, y: 1 }],
    });
    round_trip!(RayTreeInput {
        scene: SceneSpec {
            step: 16,
            place: Origin,
            objects: vec![],
        },
        depth: 2,
        viewpoints: vec![Raw {
            x: -1,
            y: 1099511627776
        }],
    });
    round_trip!(IncrementalInput {
        scene: SceneSpec {
            step: 20,
            place: Origin,
            objects: vec![],
        },
        order_seed: 7,
        screens_first: true,
        budget: Some((40, 200)),
        rays: vec![],
    });
    round_trip!(CoverageInput {
        heading: 3,
        fov: (65535, 41),
        width: 799,
        count: 8,
        starts: [
            (Edge(4), true, 1),
            (Near(5, -1, 2), false, 0),
            (Any(-7, 300), true, 3),
            (Edge(0), false, 2),
            (Edge(1), true, 0),
            (Edge(2), true, 0),
            (Edge(3), true, 0),
            (Edge(5), true, 0),
        ],
    });
}

#[test]
fn ray_tree_far_eye_range_across_zero() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/far_eye_range_across_zero.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_no_start_range_near_glass_vertex() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/no_start_range_near_glass_vertex.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}

#[test]
fn ray_tree_far_eye_extra_piece_at_range_end() {
    let input: RayTreeInput =
        include!("../../fuzz/regressions/ray_tree/far_eye_extra_piece_at_range_end.rs");
    assert_eq!(check_ray_tree(&input), Ok(1), "{input:?}");
}
