//! The exact predicates fail on no stress family (issue 6, item 4): every family of
//! near-degenerate scenes of `vcx bench stability` (`vcx_demo::stress`), at every scale from
//! the finest grid unit to the top of the coordinate range, at a small size: the scene
//! validates, the sweep's complex passes `validate`, `validate_at` along the axes,
//! diagonals and edge directions and has the reference's free bitangents
//! ([`check_complex`]), and every view equals the big-rational reference's view
//! ([`compare_view`]: same intervals, objects, boundary directions and boundary vertices).
//!
//! The naive `f64` variant is not tested here (it is expected to fail near the top of the
//! range); `vcx bench stability --compare` measures it against the exact build.

use vcx::{ObjectId, SubScene};
use vcx_demo::stress::{generate, Family, SCALES};
use vcx_tests::generators::{check_complex, compare_view};

/// Objects and viewpoints per instance, and instances per scale.
const OBJECTS: usize = 8;
const VIEWS: usize = 6;
const INSTANCES: u64 = 2;

fn check_family(f: Family) {
    let mut failures: Vec<String> = Vec::new();
    let mut compared = 0;
    for e in SCALES {
        for instance in 0..INSTANCES {
            let s = generate(f, e, OBJECTS, VIEWS, 1, instance).expect("scales are in range");
            let at = format!("{} scale {e} instance {instance}", f.name());
            let scene = match s.scene() {
                Ok(scene) => scene,
                Err(err) => {
                    failures.push(format!("{at}: scene rejected: {err}"));
                    continue;
                }
            };
            let sr = scene.as_ref();
            let complex = match check_complex(&sr, &[]) {
                Ok(c) => c,
                Err(m) => {
                    failures.push(format!("{at}: {m}"));
                    continue;
                }
            };
            let sub = SubScene::new(sr, (0..sr.len() as u32).map(ObjectId));
            for &q in &s.viewpoints {
                match compare_view(&sr, &sub, &complex, q) {
                    Ok(true) => compared += 1,
                    Ok(false) => failures.push(format!("{at}: viewpoint {q:?} is not free")),
                    Err(m) => failures.push(format!("{at}: {m}")),
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures, first:\n{}",
        failures.len(),
        failures.first().map_or("", String::as_str)
    );
    // Every scale contributed views (the generators found free viewpoints).
    let want = SCALES.len() * INSTANCES as usize * VIEWS / 2;
    assert!(
        compared >= want,
        "{}: only {compared} views compared",
        f.name()
    );
}

#[test]
fn collinear_lattices() {
    check_family(Family::Collinear);
}

#[test]
fn pairs_one_grid_unit_apart() {
    check_family(Family::UnitGap);
}

#[test]
fn long_thin_slivers() {
    check_family(Family::Sliver);
}

#[test]
fn nearly_parallel_edges() {
    check_family(Family::Parallel);
}

#[test]
fn viewpoints_on_bitangents() {
    check_family(Family::Bitangent);
}

#[test]
fn viewpoints_on_edge_extensions() {
    check_family(Family::EdgeExtension);
}
