//! Helpers shared by several integration tests (`mod common;`); each test crate uses a
//! subset.
#![allow(dead_code)]

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use vcx::geom::sos::Angle;
use vcx::partition::{BorderBuffers, BorderSizes, CylinderId};
use vcx::{QueryPoint, Scene, SceneRef};
use vcx_tests::generators::SceneSpec;

/// Owned buffers of the sizes given for the derived state of `Complex::from_slices`.
pub struct BorderVecs {
    angles: Vec<Angle>,
    ids: Vec<CylinderId>,
    offsets: Vec<u32>,
    start: Vec<[[u32; 2]; 2]>,
}

impl BorderVecs {
    pub fn new(sizes: BorderSizes) -> BorderVecs {
        BorderVecs {
            angles: vec![Angle::ZERO; sizes.angles],
            ids: vec![CylinderId::ZERO; sizes.ids],
            offsets: vec![0; sizes.offsets],
            start: vec![[[0; 2]; 2]; sizes.start],
        }
    }

    /// The buffers, borrowed (allocates nothing).
    pub fn buffers(&mut self) -> BorderBuffers<'_> {
        BorderBuffers {
            angles: &mut self.angles,
            ids: &mut self.ids,
            offsets: &mut self.offsets,
            start: &mut self.start,
        }
    }
}

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

/// A degenerate scene from random fuzzer-style bytes (`generators::SceneSpec`, as the fuzz
/// targets decode them), or `None` when the bytes make no spec or no valid scene.
pub fn random_spec_scene(rng: &mut ChaCha8Rng) -> Option<Scene> {
    let len = rng.gen_range(16..600);
    let raw: Vec<u8> = (0..len).map(|_| rng.gen()).collect();
    let spec = vcx_tests::generators::decode::<SceneSpec>(&raw)?;
    spec.realize().scene().ok()
}
