//! Property harness over the degenerate scene generators of the fuzz targets
//! (`vcx_tests::generators`): the same inputs, decoded from random bytes the way
//! libFuzzer's targets decode theirs, on stable and in CI.
//!
//! * validation against the exact oracle, construction, `validate`, `validate_at`, free
//!   bitangents against the reference (`build_complex`);
//! * point location against exact ray shooting (`locate`);
//! * walked views and depth-0 ray trees against the reference (`walk`);
//! * ray trees at depth 1–2 against the reference (`ray_tree`);
//! * the randomized incremental construction against the sweep after every insertion, with
//!   memory budgets and rollback (`ric`).
//! * the coverage table's runs of whole columns against the column-by-column pieces
//!   (`coverage`).
//!
//! Case counts are sized for CI: about 10 s with two free cores (20 s on one) with the
//! test profile's opt-level 2. `PROPTEST_CASES=N` sets every property here to `N` cases for
//! long runs, e.g. `PROPTEST_CASES=20000 cargo test --release -p vcx-tests --test degenerate`.
//! A failure prints the input as Rust code and its bytes: commit the bytes under
//! `fuzz/regressions/<target>/` (see `FUZZING.md`).

use proptest::prelude::*;
use proptest::test_runner::Config;
use vcx_tests::generators::{
    check_build, check_coverage, check_incremental, check_locate, check_ray_tree, check_walk,
    decode, BuildInput, CoverageInput, IncrementalInput, LocateInput, RayTreeInput, Shape,
    WalkInput,
};

/// `PROPTEST_CASES` if set, else `default`. (`ProptestConfig::with_cases` ignores the
/// variable; only `ProptestConfig::default()` reads it.)
fn config(default: u32) -> Config {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default);
    Config {
        cases,
        // Failures are committed as fuzz regressions, not proptest's own files.
        failure_persistence: None,
        ..Config::default()
    }
}

/// Random bytes for `arbitrary`: enough for a full scene of 12 objects and its queries.
fn bytes() -> impl Strategy<Value = Vec<u8>> {
    proptest::collection::vec(any::<u8>(), 0..1200)
}

fn fail(target: &str, input: &dyn core::fmt::Debug, bytes: &[u8], e: &str) -> TestCaseError {
    TestCaseError::fail(format!(
        "{e}\n\ninput ({target}): {input:?}\n\nbytes (commit as fuzz/regressions/{target}/<name>): {bytes:?}"
    ))
}

proptest! {
    #![proptest_config(config(4000))]

    #[test]
    fn build_validate_and_cross_sections(b in bytes()) {
        if let Some(input) = decode::<BuildInput>(&b) {
            check_build(&input).map_err(|e| fail("build_complex", &input, &b, &e))?;
        }
    }
}

proptest! {
    #![proptest_config(config(4000))]

    #[test]
    fn locate_matches_ray_shooting(b in bytes()) {
        if let Some(input) = decode::<LocateInput>(&b) {
            check_locate(&input).map_err(|e| fail("locate", &input, &b, &e))?;
        }
    }
}

proptest! {
    #![proptest_config(config(3000))]

    #[test]
    fn views_match_the_reference(b in bytes()) {
        if let Some(input) = decode::<WalkInput>(&b) {
            check_walk(&input).map_err(|e| fail("walk", &input, &b, &e))?;
        }
    }
}

proptest! {
    #![proptest_config(config(300))]

    #[test]
    fn ray_trees_match_the_reference(b in bytes()) {
        if let Some(input) = decode::<RayTreeInput>(&b) {
            check_ray_tree(&input).map(drop).map_err(|e| fail("ray_tree", &input, &b, &e))?;
        }
    }
}

proptest! {
    #![proptest_config(config(2000))]

    #[test]
    fn incremental_construction_is_the_sweep(b in bytes()) {
        if let Some(input) = decode::<IncrementalInput>(&b) {
            check_incremental(&input).map(drop).map_err(|e| fail("ric", &input, &b, &e))?;
        }
    }
}

proptest! {
    #![proptest_config(config(50_000))]

    #[test]
    fn coverage_table_equals_the_pieces(b in bytes()) {
        if let Some(input) = decode::<CoverageInput>(&b) {
            check_coverage(&input).map_err(|e| fail("coverage", &input, &b, &e))?;
        }
    }
}

/// The generators do produce what they are for: many objects, invalid written scenes,
/// copies at small gaps, extreme coordinates, free rays, insertions over budget — so that
/// the properties above are not vacuous.
#[test]
fn generators_are_degenerate() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let (mut objects, mut kept, mut invalid_scenes, mut copies, mut extreme, mut free_rays) =
        (0, 0, 0, 0, 0, 0);
    let n = 400;
    for _ in 0..n {
        let b: Vec<u8> = (0..rng.gen_range(0..1200)).map(|_| rng.gen()).collect();
        let Some(input) = decode::<LocateInput>(&b) else {
            continue;
        };
        let r = input.scene.realize();
        objects += r.written.len();
        kept += r.repaired().len();
        invalid_scenes +=
            usize::from(vcx::Scene::new(r.written.iter().map(|(m, p)| (*m, &p[..]))).is_err());
        copies += input
            .scene
            .objects
            .iter()
            .filter(|o| matches!(o.shape, Shape::Translated { .. } | Shape::Reflected { .. }))
            .count();
        extreme += usize::from(
            r.written
                .iter()
                .flat_map(|(_, p)| p)
                .any(|p| p.x().unsigned_abs() >= (1 << 29) || p.y().unsigned_abs() >= (1 << 29)),
        );
        free_rays += check_locate(&input).unwrap_or_else(|e| panic!("{e}\n{input:?}"));
    }
    let mut rollbacks = 0;
    for _ in 0..n / 4 {
        let b: Vec<u8> = (0..rng.gen_range(0..1200)).map(|_| rng.gen()).collect();
        if let Some(input) = decode::<IncrementalInput>(&b) {
            rollbacks += check_incremental(&input).unwrap_or_else(|e| panic!("{e}\n{input:?}"));
        }
    }
    println!(
        "{n} inputs: {objects} objects written, {kept} kept, {invalid_scenes} invalid scenes, \
         {copies} copies, {extreme} with extreme coordinates, {free_rays} free rays; \
         {rollbacks} insertions over budget rolled back in {} inputs",
        n / 4
    );
    assert!(objects > n * 4, "{objects}");
    assert!(kept > n * 2, "{kept}");
    assert!(invalid_scenes > n / 4, "{invalid_scenes}");
    assert!(copies > n, "{copies}");
    assert!(extreme > n / 10, "{extreme}");
    assert!(free_rays > n, "{free_rays}");
    assert!(rollbacks > n / 40, "{rollbacks}");
}
