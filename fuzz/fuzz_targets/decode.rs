//! The binary complex format (`vcx::format`, `docs/format.md`) never trusts its input:
//! arbitrary bytes, and valid files of degenerate scenes (whole, or pruned to a box: region
//! files) with bytes flipped, cut short and (optionally) the checksum recomputed so the
//! structural checks are reached. Decoding must return `Ok` or `Err`, never panic, hang or
//! allocate without bound; on `Ok` the complex passes `validate`, and a trace and a ray
//! tree of depth 2 walk it (or report an error).
#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use vcx::format::{self, decode, EncodeOptions};
use vcx::partition::{build_by_sweep, Region};
use vcx::{Point, QueryPoint, Scene};
use vcx_tests::generators::SceneSpec;

#[derive(Debug, Arbitrary)]
enum Input {
    /// Any bytes.
    Raw(Vec<u8>),
    /// A valid file, damaged.
    Mutated {
        scene: SceneSpec,
        /// `(offset, xor)`: offsets modulo the file length.
        edits: Vec<(u16, u8)>,
        /// Keep only this many bytes (modulo the length + 1).
        cut: Option<u16>,
        /// Recompute the checksum after the edits.
        reseal: bool,
        /// Store every cylinder (version 1, or 2 with a region) instead of replaying them
        /// (version 3, or 4 with a region).
        explicit_cylinders: bool,
        /// Prune to a box (corners in 256ths of the scene's bounding box).
        region: Option<[u8; 4]>,
    },
}

/// A box in `s`'s bounding box, its corners at `k / 256` of its sides.
fn region_in(s: &Scene, k: [u8; 4]) -> Option<Region> {
    let v = s.as_ref().vertices();
    let (x0, x1) = (
        v.iter().map(|p| p.x()).min()?,
        v.iter().map(|p| p.x()).max()?,
    );
    let (y0, y1) = (
        v.iter().map(|p| p.y()).min()?,
        v.iter().map(|p| p.y()).max()?,
    );
    let at = |lo: i32, hi: i32, k: u8| {
        (i64::from(lo) + (i64::from(hi) - i64::from(lo)) * i64::from(k) / 256) as i32
    };
    let (a, b) = (at(x0, x1, k[0]), at(x0, x1, k[1]));
    let (c, d) = (at(y0, y1, k[2]), at(y0, y1, k[3]));
    Region::new(
        Point::from_raw(a.min(b), c.min(d))?,
        Point::from_raw(a.max(b), c.max(d))?,
    )
}

fn file(
    scene: &SceneSpec,
    edits: &[(u16, u8)],
    cut: Option<u16>,
    reseal: bool,
    explicit_cylinders: bool,
    region: Option<[u8; 4]>,
) -> Option<Vec<u8>> {
    let s = scene.realize().scene().ok()?;
    let mut c = build_by_sweep(&s.as_ref()).ok()?;
    if let Some(k) = region {
        c = c.prune_to_region(&s.as_ref(), region_in(&s, k)?).ok()?;
    }
    let options = EncodeOptions {
        explicit_cylinders,
        ..EncodeOptions::default()
    };
    let mut bytes = format::encode(&s.as_ref(), &c, None, &options).ok()?;
    for &(at, x) in edits {
        let i = usize::from(at) % bytes.len();
        bytes[i] ^= x;
    }
    if let Some(k) = cut {
        bytes.truncate(usize::from(k) % (bytes.len() + 1));
    }
    if reseal && bytes.len() >= format::CHECKSUM_LEN {
        let at = bytes.len() - format::CHECKSUM_LEN;
        let crc = format::crc32(&bytes[..at]);
        bytes[at..].copy_from_slice(&crc.to_le_bytes());
    }
    Some(bytes)
}

fuzz_target!(|input: Input| {
    let bytes = match &input {
        Input::Raw(b) => b.clone(),
        Input::Mutated {
            scene,
            edits,
            cut,
            reseal,
            explicit_cylinders,
            region,
        } => match file(scene, edits, *cut, *reseal, *explicit_cylinders, *region) {
            Some(b) => b,
            None => return,
        },
    };
    let Ok(loaded) = decode(&bytes) else {
        return;
    };
    let s = loaded.scene.as_ref();
    if let Err(e) = loaded.complex.validate(&s) {
        panic!("decoded but invalid: {e}\ninput: {input:?}");
    }
    // A trace from a point near the first vertex (or the origin) walks, or the point is
    // not free; never a panic or an endless loop.
    let q = s
        .vertices()
        .first()
        .and_then(|p| {
            QueryPoint::from_raw((i64::from(p.x()) << 16) - 3, (i64::from(p.y()) << 16) - 5)
        })
        .or(QueryPoint::from_raw(0, 0));
    if let Some(q) = q {
        let _ = loaded.complex.walk_trace(&s, q, |_| {});
        let _ = vcx::walk::ray_tree(&loaded.complex, &s, q, 2);
    }
});
