//! The binary complex format (`vcx::format`, `docs/format.md`) never trusts its input:
//! arbitrary bytes, and valid files of degenerate scenes with bytes flipped, cut short and
//! (optionally) the checksum recomputed so the structural checks are reached. Decoding
//! must return `Ok` or `Err`, never panic, hang or allocate without bound; on `Ok` the
//! complex passes `validate` and a trace walks it (or reports a point that is not free).
#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use vcx::format::{self, decode, EncodeOptions};
use vcx::partition::build_by_sweep;
use vcx::QueryPoint;
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
        /// Store every cylinder (version 1) instead of replaying them (version 3).
        explicit_cylinders: bool,
    },
}

fn file(
    scene: &SceneSpec,
    edits: &[(u16, u8)],
    cut: Option<u16>,
    reseal: bool,
    explicit_cylinders: bool,
) -> Option<Vec<u8>> {
    let s = scene.realize().scene().ok()?;
    let c = build_by_sweep(&s.as_ref()).ok()?;
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
        } => match file(scene, edits, *cut, *reseal, *explicit_cylinders) {
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
    }
});
