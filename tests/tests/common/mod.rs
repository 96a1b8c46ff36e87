//! Helpers shared by several integration tests (`mod common;`).

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use vcx::{QueryPoint, SceneRef};

/// A random point of the scene's bounding box (raw query coordinates with random low bits).
pub fn random_point(rng: &mut ChaCha8Rng, s: &SceneRef<'_>) -> QueryPoint {
    let (lo, hi) = s.vertices().iter().fold(
        ((i32::MAX, i32::MAX), (i32::MIN, i32::MIN)),
        |(lo, hi), p| {
            (
                (lo.0.min(p.x()), lo.1.min(p.y())),
                (hi.0.max(p.x()), hi.1.max(p.y())),
            )
        },
    );
    let r = |rng: &mut ChaCha8Rng, a: i32, b: i32| {
        ((rng.gen_range(a..=b) as i64) << 16) + rng.gen_range(0..1i64 << 16)
    };
    QueryPoint::from_raw(r(rng, lo.0, hi.0), r(rng, lo.1, hi.1)).unwrap()
}
