//! The binary complex format (`vcx::format`, `docs/format.md`): golden bytes, round trips
//! (views from the decoded complex equal views from the original, and the exact
//! reference), and every class of corrupt input — each truncation offset and each
//! single-bit flip of a small file, with and without the checksum recomputed, counts
//! inflated to the maximum, ids out of range, unknown versions and parts.

mod common;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use vcx::format::{
    self, decode, decode_into, encode, encode_into, Arena, CountProblem, EncodeOptions,
    FormatError, Header, Problem, SceneObject, Scratch, BLANK_CYLINDER, BLANK_VERTEX,
};
use vcx::partition::{
    build_by_sweep, BuildOptions, Complex, CylinderId, History, Wall, ZERO_SLOTS,
};
use vcx::walk::{ray_tree, view};
use vcx::{Eta, Material, ObjectId, Point, QueryPoint, Scene, SceneRef, SubScene};
use vcx_tests::generators::compare_view;

fn pt(x: i32, y: i32) -> Point {
    Point::from_raw(x << 16, y << 16).unwrap()
}

/// The golden scene: an opaque triangle written counter-clockwise and a refractive one
/// written clockwise (so the written order differs from storage).
fn small_scene() -> Scene {
    let a = [pt(0, 0), pt(4, 0), pt(0, 3)];
    let b = [pt(10, 0), pt(8, 5), pt(12, 4)]; // clockwise
    let glass = Material::Refractive {
        eta: Eta::from_f64(1.5).unwrap(),
    };
    Scene::new([(Material::Opaque, &a[..]), (glass, &b[..])]).unwrap()
}

/// The golden scene's file as written by default: version 3, the cylinders replayed.
fn small_file() -> (Scene, Complex, Vec<u8>) {
    small_file_as(false)
}

/// The golden scene's file with every cylinder stored (version 1).
fn small_file_v1() -> (Scene, Complex, Vec<u8>) {
    small_file_as(true)
}

fn small_file_as(explicit_cylinders: bool) -> (Scene, Complex, Vec<u8>) {
    let s = small_scene();
    let c = build_by_sweep(&s.as_ref()).unwrap();
    let options = EncodeOptions {
        seed: Some(7),
        compacted: true,
        explicit_cylinders,
    };
    let bytes = encode(&s.as_ref(), &c, None, &options).unwrap();
    (s, c, bytes)
}

/// Both small files, named.
fn small_files() -> [(&'static str, Vec<u8>); 2] {
    [
        ("version 3", small_file().2),
        ("version 1", small_file_v1().2),
    ]
}

/// Whether two complexes are the same partition up to the numbering of their cylinders:
/// the same vertices, and the same cylinders with the same neighbours, each named by its
/// floor, ceiling, chains and walls.
fn same_partition(a: &Complex, b: &Complex) -> bool {
    type Key = (
        Option<ObjectId>,
        Option<ObjectId>,
        Option<vcx::line_space::Chain>,
        Option<vcx::line_space::Chain>,
        String,
    );
    fn described(c: &Complex) -> Vec<(Key, Option<Key>, Option<Key>)> {
        let key = |i: usize| {
            let y = &c.cylinders()[i];
            (
                y.floor,
                y.ceiling,
                y.bottom,
                y.top,
                format!("{:?}-{:?}", y.left, y.right),
            )
        };
        let mut all: Vec<_> = (0..c.cylinders().len())
            .map(|i| {
                let y = &c.cylinders()[i];
                (
                    key(i),
                    y.left_neighbour.map(|n| key(n.index())),
                    y.right_neighbour.map(|n| key(n.index())),
                )
            })
            .collect();
        all.sort();
        all
    }
    a.vertices() == b.vertices() && described(a) == described(b)
}

/// Recomputes the checksum after an edit, so the structural checks are what is tested.
fn reseal(bytes: &mut [u8]) {
    let at = bytes.len() - format::CHECKSUM_LEN;
    let crc = format::crc32(&bytes[..at]);
    bytes[at..].copy_from_slice(&crc.to_le_bytes());
}

fn set_u32(bytes: &mut [u8], at: usize, v: u32) {
    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

/// A scene with the same objects, written the same way, without its screens (views need
/// a screen-less complex; a `SubScene` shares its parent's vertex array and cannot be
/// written).
fn without_screens(s: &SceneRef<'_>) -> Scene {
    let polys: Vec<(Material, Vec<Point>)> = s
        .objects()
        .iter()
        .filter(|o| o.material != Material::Screen)
        .map(|o| {
            let p = s.polygon(o);
            (
                o.material,
                (0..p.len()).map(|j| p[o.written_vertex_id(j)]).collect(),
            )
        })
        .collect();
    Scene::new(polys.iter().map(|(m, p)| (*m, &p[..]))).unwrap()
}

/// `k` query points spread over the scene's bounding box (some inside objects).
fn sample_points(s: &SceneRef<'_>, k: usize, seed: u64) -> Vec<QueryPoint> {
    let (mut lo, mut hi) = ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN));
    for p in s.vertices() {
        lo = (lo.0.min(p.x().into()), lo.1.min(p.y().into()));
        hi = (hi.0.max(p.x().into()), hi.1.max(p.y().into()));
    }
    if s.vertices().is_empty() {
        (lo, hi) = ((-65536, -65536), (65536, 65536));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..k)
        .filter_map(|_| {
            // Query grid: 2^-32, scene raw << 16; a margin of one unit around the box.
            let x = rng.gen_range((lo.0 - 65536) << 16..=(hi.0 + 65536) << 16);
            let y = rng.gen_range((lo.1 - 65536) << 16..=(hi.1 + 65536) << 16);
            QueryPoint::from_raw(x, y)
        })
        .collect()
}

/// Views as comparable tuples: exact start direction, object, boundary vertex.
type ViewKey = Vec<((i128, i128), Option<ObjectId>, Option<usize>)>;

fn view_key(c: &Complex, s: &SceneRef<'_>, q: QueryPoint) -> Result<ViewKey, String> {
    view(c, s, q)
        .map(|v| {
            v.iter()
                .map(|i| (i.start.vector(), i.object, i.start_vertex))
                .collect()
        })
        .map_err(|e| format!("{e:?}"))
}

/// Encodes, decodes, and checks the decoded scene and complex against the original, their
/// views from `points` against each other, the first `reference` of them against the exact
/// reference (big rationals: slow), and depth-2 ray trees from the first `trees`.
fn round_trip(
    s: &Scene,
    c: &Complex,
    points: &[QueryPoint],
    reference: usize,
    trees: usize,
) -> Vec<u8> {
    let sr = s.as_ref();
    let bytes = encode(&sr, c, None, &EncodeOptions::default()).unwrap();
    let loaded = decode(&bytes).unwrap_or_else(|e| panic!("decode: {e}"));
    let dr = loaded.scene.as_ref();
    assert_eq!(dr.vertices(), sr.vertices());
    assert_eq!(dr.objects(), sr.objects());
    assert_eq!(loaded.complex.vertices(), c.vertices());
    // Version 3 numbers the replayed cylinders as the sweep does: the same partition, and
    // the same numbering when the sweep built it.
    assert_eq!(loaded.header.version, format::VERSION_REPLAY);
    assert!(same_partition(&loaded.complex, c));
    if c.cylinders() == build_by_sweep(&sr).unwrap().cylinders() {
        assert_eq!(loaded.complex.cylinders(), c.cylinders());
    }
    loaded.complex.validate(&dr).unwrap();
    assert_eq!(loaded.header.seed, None);
    let screens = sr.objects().iter().any(|o| o.material == Material::Screen);
    let mut compared = 0;
    for (k, &q) in points.iter().enumerate() {
        if !screens {
            let (a, b) = (view_key(c, &sr, q), view_key(&loaded.complex, &dr, q));
            assert_eq!(a, b, "view from {q:?}");
            if k < reference {
                let sub = SubScene::new(dr, (0..dr.len() as u32).map(ObjectId));
                if compare_view(&dr, &sub, &loaded.complex, q).unwrap() {
                    compared += 1;
                }
            }
        }
        if k >= trees {
            continue;
        }
        let tree = |c: &Complex, s: &SceneRef<'_>| {
            ray_tree(c, s, q, 2)
                .map(|t| format!("{t:?}"))
                .map_err(|e| format!("{e:?}"))
        };
        assert_eq!(
            tree(c, &sr),
            tree(&loaded.complex, &dr),
            "ray tree from {q:?}"
        );
    }
    if reference > 0 && !screens && !points.is_empty() {
        assert!(compared > 0, "no free point compared with the reference");
    }
    bytes
}

// ---------------------------------------------------------------------------------------
// Golden bytes.

/// The encoding of [`small_scene`] built by the sweep, seed 7, compacted, in hex, as
/// written by default (version 3: vertices and the cylinders at θ = 0). To regenerate
/// after an intended format change (which must bump the version, see docs/format.md): run
/// this test and copy the hex lines of the failure message.
const GOLDEN: &str = "\
    5643580003000300030000000200000006000000080000001f00000000000000\
    000000000700000000000000210000002c000000000000000003028080060300\
    0080802000008080188080500080804080802880806080802002050105030203\
    0105020501020301030000000300020301000101020102010200020204020003\
    04000004004f2cc6c0";

/// The same file with every cylinder stored (`explicit_cylinders`, version 1): its bytes
/// have not changed since version 1 was defined.
const GOLDEN_V1: &str = "\
    5643580001000300030000000200000006000000080000001f00000000000000\
    0000000007000000000000002100000008010000000000000003028080060300\
    0080802000008080188080500080804080802880806080802002050105030203\
    0105020501020301030000000300051e150002030100021f0c00010102000318\
    0e0102010200011d090002020400011a00020003040003170f00000400000111\
    0800000200010407110102010401020400010004020102000b0100010202070a\
    1b000203040207021a0000040102030000000104020304030002000301030506\
    0002010104030400120000040004000807020101020405101402000204040600\
    170201030205061200000000010508011e000101030506001802000304060013\
    06000101020600160300000203060700000002020407000c050100010307080b\
    00010203020708001d0102010208001c04000000030800150100020301080000\
    02ae30a22a";

fn hex_lines(bytes: &[u8]) -> String {
    let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
    hex.as_bytes()
        .chunks(64)
        .map(|c| format!("    {}\\\n", core::str::from_utf8(c).unwrap()))
        .collect()
}

fn unhex(text: &str) -> Vec<u8> {
    let digits: Vec<u8> = text.bytes().filter(u8::is_ascii_hexdigit).collect();
    digits
        .chunks(2)
        .map(|p| u8::from_str_radix(core::str::from_utf8(p).unwrap(), 16).unwrap())
        .collect()
}

#[test]
fn golden_bytes() {
    for (version, golden, (s, c, bytes)) in [
        (format::VERSION_REPLAY, GOLDEN, small_file()),
        (format::VERSION, GOLDEN_V1, small_file_v1()),
    ] {
        let golden = unhex(golden);
        assert!(
            bytes == golden,
            "the encoding of version {version} changed ({} bytes); got\n{}",
            bytes.len(),
            hex_lines(&bytes)
        );
        // The golden file decodes to the same complex.
        let loaded = decode(&golden).unwrap();
        assert_eq!(loaded.header.version, version);
        assert_eq!(loaded.complex.cylinders(), c.cylinders());
        assert_eq!(loaded.scene.as_ref().vertices(), s.as_ref().vertices());
        assert_eq!(loaded.header.seed, Some(7));
        assert!(loaded.header.compacted);
    }
    // Version 3 stores 4 of every cylinder's 8 ids, and only for those at θ = 0.
    assert!(unhex(GOLDEN).len() * 2 < unhex(GOLDEN_V1).len());
}

/// The golden scene made opaque, pruned to the box (5, 1)–(7, 2) between its triangles,
/// written by default (version 4: the whole complex replayed and a kept map).
fn small_region_file() -> (Scene, Complex, Vec<u8>) {
    let a = [pt(0, 0), pt(4, 0), pt(0, 3)];
    let b = [pt(10, 0), pt(8, 5), pt(12, 4)];
    let s = Scene::new([(Material::Opaque, &a[..]), (Material::Opaque, &b[..])]).unwrap();
    let sr = s.as_ref();
    let c = build_by_sweep(&sr).unwrap();
    let r = vcx::partition::Region::new(pt(5, 1), pt(7, 2)).unwrap();
    let p = c.prune_to_region(&sr, r).unwrap();
    let bytes = encode(&sr, &p, None, &EncodeOptions::default()).unwrap();
    (s, p, bytes)
}

/// The encoding of [`small_region_file`], in hex (regenerate as [`GOLDEN`]).
const GOLDEN_V4: &str = "\
    5643580004000400030000000200000006000000080000001b00000000000000\
    0000000000000000000000001e0000003e000000000000000003000300008080\
    2000008080188080500080804080802880806080802080802880800880803880\
    8010080205010503020301050205010203010300000003000203010001010201\
    02010200020204020003040000040004afffff1fd62f2ef2";

#[test]
fn golden_bytes_v4() {
    let (s, p, bytes) = small_region_file();
    let golden = unhex(GOLDEN_V4);
    assert!(
        bytes == golden,
        "the encoding of version 4 changed ({} bytes); got\n{}",
        bytes.len(),
        hex_lines(&bytes)
    );
    let loaded = decode(&golden).unwrap();
    assert_eq!(loaded.header.version, format::VERSION_PRUNED);
    assert_eq!(loaded.complex.region(), p.region());
    assert_eq!(loaded.complex.vertices(), p.vertices());
    assert_eq!(loaded.complex.cylinders(), p.cylinders());
    assert_eq!(loaded.scene.as_ref().vertices(), s.as_ref().vertices());
    // Fewer kept than the whole complex's 31 cylinders.
    assert!(loaded.header.cylinders < 31, "{}", loaded.header.cylinders);
}

#[test]
fn header_layout() {
    let (s, c, bytes) = small_file();
    assert_eq!(&bytes[..4], b"VCX\0");
    assert_eq!(
        u16::from_le_bytes([bytes[4], bytes[5]]),
        format::VERSION_REPLAY
    );
    let h = Header::read(&bytes).unwrap();
    assert_eq!(h.objects as usize, s.as_ref().len());
    assert_eq!(h.scene_vertices as usize, s.as_ref().vertices().len());
    assert_eq!(h.complex_vertices as usize, c.vertices().len());
    assert_eq!(h.cylinders as usize, c.cylinders().len());
    assert_eq!(h.file_len() as usize, bytes.len());
    assert!(!h.has_history());
    // CRC-32/IEEE check value.
    assert_eq!(format::crc32(b"123456789"), 0xCBF4_3926);
    assert_eq!(
        format::crc32(&bytes[..bytes.len() - 4]).to_le_bytes(),
        bytes[bytes.len() - 4..]
    );
}

// ---------------------------------------------------------------------------------------
// Round trips.

fn example(name: &str) -> Scene {
    let path = format!(
        "{}/../std-demo/scenes/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    vcx_demo::scene_file::load(path).unwrap().scene
}

/// An example scene: the whole scene (screens included) and ray trees from the decoded
/// complex against the original's; then without screens, views against each other and the
/// exact reference.
fn example_round_trip(name: &str, ric: bool) {
    let full = example(name);
    let fr = full.as_ref();
    let c = if ric {
        let history = History::build(&fr, &BuildOptions::default()).unwrap();
        history.complex(&fr).unwrap()
    } else {
        build_by_sweep(&fr).unwrap()
    };
    round_trip(&full, &c, &sample_points(&fr, 6, 1), 0, 3);
    let s = without_screens(&fr);
    let c = build_by_sweep(&s.as_ref()).unwrap();
    round_trip(&s, &c, &sample_points(&s.as_ref(), 12, 2), 3, 0);
}

#[test]
fn example_grid_round_trips() {
    example_round_trip("grid", false);
}

#[test]
fn example_hall_round_trips() {
    // Built by the randomized construction: cylinders in another order than the sweep's.
    example_round_trip("hall", true);
}

#[test]
fn example_mixed_round_trips() {
    example_round_trip("mixed", false);
}

#[test]
fn generated_scenes_round_trip() {
    use vcx_demo::generate::{generate, SceneKind};
    for seed in 0..4 {
        for kind in [SceneKind::Grid, SceneKind::Hall, SceneKind::Mixed] {
            let n = 2 + (seed as u32 * 3) % 10;
            let file = generate(kind, n, seed).unwrap();
            let s = without_screens(&file.scene.as_ref());
            let c = build_by_sweep(&s.as_ref()).unwrap();
            round_trip(&s, &c, &sample_points(&s.as_ref(), 4, seed), 2, 1);
        }
    }
}

/// Degenerate scenes (collinear lattices, slivers, extreme coordinates) of the fuzz
/// generators, from random bytes.
#[test]
fn degenerate_scenes_round_trip() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut done = 0;
    for _ in 0..400 {
        let Some(s) = common::random_spec_scene(&mut rng) else {
            continue;
        };
        let s = without_screens(&s.as_ref());
        let c = build_by_sweep(&s.as_ref()).unwrap();
        round_trip(&s, &c, &sample_points(&s.as_ref(), 3, done), 0, 1);
        done += 1;
        if done == 60 {
            break;
        }
    }
    assert!(done >= 30, "only {done} degenerate scenes");
}

#[test]
fn empty_scene_round_trips() {
    let s = Scene::new(core::iter::empty()).unwrap();
    let c = build_by_sweep(&s.as_ref()).unwrap();
    round_trip(&s, &c, &[QueryPoint::from_raw(0, 0).unwrap()], 1, 1);
}

/// Decoding into caller storage without allocation gives the same arenas as `decode`;
/// storage too small is a typed error.
#[test]
fn decode_into_fixed_storage() {
    let (s, c, bytes) = small_file();
    let mut objects = [SceneObject::BLANK; 8];
    let mut points = [Point::default(); 32];
    let mut open = [ZERO_SLOTS; Scratch::open_len(8)];
    let mut vertices = [BLANK_VERTEX; 64];
    let mut cylinders = [BLANK_CYLINDER; 256];
    let d = decode_into::<32, 8>(
        &bytes,
        Scratch {
            objects: &mut objects,
            points: &mut points,
            open: &mut open,
        },
        &mut vertices,
        &mut cylinders,
    )
    .unwrap();
    assert_eq!(d.vertices, c.vertices());
    assert_eq!(d.cylinders, c.cylinders());
    assert_eq!(d.scene.as_ref().vertices(), s.as_ref().vertices());
    assert_eq!(d.scene.as_ref().objects(), s.as_ref().objects());
    // Encoding the decoded arenas without allocation gives the same bytes.
    let mut out = [0u8; 2048];
    let n = encode_into(
        &d.scene.as_ref(),
        d.vertices,
        d.cylinders,
        &EncodeOptions {
            seed: Some(7),
            compacted: true,
            explicit_cylinders: false,
        },
        &mut out,
    )
    .unwrap();
    assert_eq!(&out[..n], &bytes[..]);
    let mut small = [BLANK_CYLINDER; 4];
    let e = decode_into::<32, 8>(
        &bytes,
        Scratch {
            objects: &mut objects,
            points: &mut points,
            open: &mut open,
        },
        &mut vertices,
        &mut small,
    )
    .unwrap_err();
    assert!(
        matches!(e, FormatError::Capacity { arena: Arena::Cylinder, needed, capacity: 4 } if needed == c.cylinders().len()),
        "{e:?}"
    );
    let e = decode_into::<4, 8>(
        &bytes,
        Scratch {
            objects: &mut objects,
            points: &mut points,
            open: &mut open,
        },
        &mut vertices,
        &mut cylinders,
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            FormatError::Capacity {
                arena: Arena::Point,
                ..
            }
        ),
        "{e:?}"
    );
    // Too few open-cylinder slots for the replay (version 3 only).
    let e = decode_into::<32, 8>(
        &bytes,
        Scratch {
            objects: &mut objects,
            points: &mut points,
            open: &mut open[..3],
        },
        &mut vertices,
        &mut cylinders,
    )
    .unwrap_err();
    assert_eq!(
        e,
        FormatError::Capacity {
            arena: Arena::OpenSlot,
            needed: Scratch::open_len(s.as_ref().len()),
            capacity: 3
        }
    );
    let (_, _, v1) = small_file_v1();
    let d = decode_into::<32, 8>(
        &v1,
        Scratch {
            objects: &mut objects,
            points: &mut points,
            open: &mut [],
        },
        &mut vertices,
        &mut cylinders,
    )
    .unwrap();
    assert_eq!(d.cylinders, c.cylinders());
    // Too small an output buffer.
    let e = encode_into(
        &s.as_ref(),
        c.vertices(),
        c.cylinders(),
        &EncodeOptions::default(),
        &mut out[..100],
    );
    assert!(
        matches!(e, Err(FormatError::BufferTooSmall { .. })),
        "{e:?}"
    );
}

#[test]
fn sub_scene_is_not_encodable() {
    let s = small_scene();
    let sub = SubScene::new(s.as_ref(), [ObjectId(0), ObjectId(2)]);
    let c = build_by_sweep(&sub.as_ref()).unwrap();
    let e = encode(&sub.as_ref(), &c, None, &EncodeOptions::default()).unwrap_err();
    assert!(matches!(e, FormatError::NotEncodable(_)), "{e:?}");
}

// ---------------------------------------------------------------------------------------
// Corrupt input.

/// After a successful decode of damaged bytes: the complex is valid and walks.
fn check_survivor(loaded: &format::Loaded) {
    let s = loaded.scene.as_ref();
    loaded.complex.validate(&s).unwrap();
    for q in sample_points(&s, 2, 9) {
        let _ = loaded.complex.walk_trace(&s, q, |_| {});
        let _ = ray_tree(&loaded.complex, &s, q, 2);
    }
}

#[test]
fn every_truncation_is_an_error() {
    for (_, bytes) in small_files() {
        truncations(&bytes);
    }
}

fn truncations(bytes: &[u8]) {
    for len in 0..bytes.len() {
        let cut = &bytes[..len];
        assert!(decode(cut).is_err(), "truncated to {len} bytes: decoded");
        assert!(
            Header::read(cut).is_err(),
            "truncated to {len} bytes: header read"
        );
    }
    // Truncated with the header's lengths and checksum fixed up: the part ends early.
    let mut ended = 0;
    for cut in format::HEADER_LEN..bytes.len() - 4 {
        let mut b = bytes[..cut].to_vec();
        b.extend_from_slice(&[0; 4]);
        let h = Header::read_unchecked(bytes).unwrap();
        let shorter = (bytes.len() - b.len()) as u32;
        if shorter <= h.complex_bytes {
            set_u32(
                &mut b,
                format::offset::COMPLEX_BYTES,
                h.complex_bytes - shorter,
            );
        } else {
            set_u32(&mut b, format::offset::COMPLEX_BYTES, 0);
            set_u32(
                &mut b,
                format::offset::SCENE_BYTES,
                h.scene_bytes - (shorter - h.complex_bytes),
            );
        }
        reseal(&mut b);
        if decode(&b).is_err() {
            ended += 1;
        }
    }
    assert_eq!(ended, bytes.len() - 4 - format::HEADER_LEN);
    // Bytes appended.
    let mut longer = bytes.to_vec();
    longer.push(0);
    assert!(matches!(decode(&longer), Err(FormatError::Length { .. })));
}

/// Flips every bit of `bytes` once: the checksum catches each flip (or, in the header, a
/// check before it); then, with the checksum recomputed, the structural checks alone never
/// panic, and a file that still decodes must pass `check` (it describes a valid complex).
fn flip_every_bit(what: &str, bytes: &[u8], check: fn(&format::Loaded)) {
    let mut survivors = 0;
    let mut classes = std::collections::BTreeMap::<String, usize>::new();
    for i in 0..bytes.len() * 8 {
        let mut b = bytes.to_vec();
        b[i / 8] ^= 1 << (i % 8);
        match decode(&b) {
            Err(FormatError::Checksum { .. }) => {}
            // Flips in the magic, version, flags, parts or counts are caught before the
            // checksum is computed.
            Err(_) if i / 8 < format::HEADER_LEN => {}
            other => panic!("{what}: bit {i}: {:?}", other.map(|_| "decoded")),
        }
        if i / 8 < bytes.len() - 4 {
            reseal(&mut b);
        }
        match decode(&b) {
            Ok(loaded) => {
                check(&loaded);
                survivors += 1;
            }
            Err(e) => {
                let name = format!("{e:?}");
                let class = name.split([' ', '(', '{']).next().unwrap_or("").to_string();
                *classes.entry(class).or_default() += 1;
            }
        }
    }
    eprintln!(
        "{what}: {} bit flips, checksum recomputed: {survivors} still valid, errors {classes:?}",
        bytes.len() * 8
    );
}

#[test]
fn every_bit_flip_is_an_error() {
    for (what, bytes) in small_files() {
        flip_every_bit(what, &bytes, check_survivor);
    }
}

#[test]
fn random_multi_byte_damage_never_panics() {
    for (_, bytes) in small_files() {
        multi_byte_damage(&bytes);
    }
}

fn multi_byte_damage(bytes: &[u8]) {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for _ in 0..3000 {
        let mut b = bytes.to_vec();
        for _ in 0..rng.gen_range(1..6) {
            let i = rng.gen_range(format::HEADER_LEN..b.len());
            b[i] = rng.gen();
        }
        reseal(&mut b);
        if let Ok(loaded) = decode(&b) {
            check_survivor(&loaded);
        }
    }
}

#[test]
fn counts_inflated_to_the_maximum() {
    for (_, bytes) in small_files() {
        inflated_counts(bytes);
    }
}

fn inflated_counts(bytes: Vec<u8>) {
    use format::offset::*;
    for (field, at) in [
        ("objects", OBJECTS),
        ("scene_vertices", SCENE_VERTICES),
        ("complex_vertices", COMPLEX_VERTICES),
        ("cylinders", CYLINDERS),
        ("history_nodes", HISTORY_NODES),
        ("history_links", HISTORY_LINKS),
        ("scene_bytes", SCENE_BYTES),
        ("complex_bytes", COMPLEX_BYTES),
        ("history_bytes", HISTORY_BYTES),
    ] {
        for v in [u32::MAX, u32::MAX / 3, 1 << 20] {
            let mut b = bytes.clone();
            set_u32(&mut b, at, v);
            reseal(&mut b);
            let e = decode(&b).unwrap_err();
            // Rejected by the header checks, before any arena is reserved.
            assert!(
                matches!(e, FormatError::Count { .. } | FormatError::Length { .. }),
                "{field} = {v}: {e:?}"
            );
            assert_eq!(Header::read(&b).unwrap_err(), e);
        }
    }
    // All counts consistent with each other but far beyond the bytes.
    let mut b = bytes.clone();
    set_u32(&mut b, OBJECTS, 1 << 20);
    set_u32(&mut b, SCENE_VERTICES, 3 << 20);
    set_u32(&mut b, COMPLEX_VERTICES, 1 << 28);
    set_u32(&mut b, CYLINDERS, (3 << 20) + 1 + (3 << 28));
    reseal(&mut b);
    let e = decode(&b).unwrap_err();
    assert!(
        matches!(
            e,
            FormatError::Count {
                field: "objects",
                problem: CountProblem::ExceedsPart { .. },
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("byte 12"), "{e}");
}

#[test]
fn unknown_version_flags_and_parts() {
    let (_, _, bytes) = small_file();
    let mut b = bytes.clone();
    // Version 2 is the region format (tests/tests/region.rs), 3 the replayed one, 4 the
    // replayed region format; 5 is unknown.
    b[4..6].copy_from_slice(&5u16.to_le_bytes());
    reseal(&mut b);
    let e = decode(&b).unwrap_err();
    assert_eq!(
        e,
        FormatError::UnsupportedVersion {
            found: 5,
            supported: format::VERSION_PRUNED
        }
    );
    assert!(e.to_string().contains("version 5"), "{e}");
    // Version 4 without its region flag.
    let mut b = bytes.clone();
    b[4..6].copy_from_slice(&4u16.to_le_bytes());
    reseal(&mut b);
    assert_eq!(decode(&b).unwrap_err(), FormatError::RegionFlagMissing);
    // The same bytes read as version 1: the complex part is too short for its cylinders.
    let mut b = bytes.clone();
    b[4..6].copy_from_slice(&1u16.to_le_bytes());
    reseal(&mut b);
    assert!(
        matches!(
            decode(&b),
            Err(FormatError::Count {
                field: "cylinders",
                ..
            })
        ),
        "{:?}",
        decode(&b)
    );
    // Version 2 without its region flag.
    let mut b = bytes.clone();
    b[4..6].copy_from_slice(&2u16.to_le_bytes());
    reseal(&mut b);
    assert_eq!(decode(&b).unwrap_err(), FormatError::RegionFlagMissing);
    // A version this reader does not know is rejected even if nothing else would parse.
    assert!(matches!(
        decode(b"VCX\0\x09\x00"),
        Err(FormatError::UnsupportedVersion { found: 9, .. })
    ));
    assert!(matches!(
        decode(b"VCY\0\x01\x00"),
        Err(FormatError::BadMagic { .. })
    ));
    let mut b = bytes.clone();
    b[6] |= 0x80;
    reseal(&mut b);
    assert_eq!(
        decode(&b).unwrap_err(),
        FormatError::UnknownFlags { bits: 0x80 }
    );
    let mut b = bytes.clone();
    b[8] |= 1 << 5;
    reseal(&mut b);
    assert_eq!(
        decode(&b).unwrap_err(),
        FormatError::UnknownParts { bits: 1 << 5 }
    );
    // Version 3 has no history part.
    let mut b = bytes.clone();
    b[8] |= 1 << 2;
    reseal(&mut b);
    assert_eq!(
        decode(&b).unwrap_err(),
        FormatError::UnknownParts { bits: 1 << 2 }
    );
    // The history bit without history counts (version 1): an inconsistent header.
    let mut b = small_file_v1().2;
    b[8] |= 1 << 2;
    reseal(&mut b);
    assert!(
        matches!(
            decode(&b).unwrap_err(),
            FormatError::Count {
                field: "history_nodes",
                problem: CountProblem::Inconsistent,
                ..
            }
        ),
        "{:?}",
        decode(&b)
    );
    // Without the seed flag the seed field must be zero.
    let mut b = bytes.clone();
    b[6] &= !1;
    reseal(&mut b);
    assert!(matches!(
        decode(&b),
        Err(FormatError::Count {
            field: "seed",
            problem: CountProblem::MustBeZero,
            ..
        })
    ));
}

/// Writes arenas edited to be wrong (the encoder trusts its input) as version 1 (every
/// cylinder stored) and decodes.
fn decode_edited(
    s: &Scene,
    c: &Complex,
    edit: impl FnOnce(&mut Vec<vcx::partition::Vertex>, &mut Vec<vcx::partition::Cylinder>),
) -> FormatError {
    decode_edited_as(true, s, c, edit)
}

/// [`decode_edited`], as version 3 unless `explicit_cylinders`.
fn decode_edited_as(
    explicit_cylinders: bool,
    s: &Scene,
    c: &Complex,
    edit: impl FnOnce(&mut Vec<vcx::partition::Vertex>, &mut Vec<vcx::partition::Cylinder>),
) -> FormatError {
    let (mut v, mut cy) = (c.vertices().to_vec(), c.cylinders().to_vec());
    edit(&mut v, &mut cy);
    let mut out = vec![0u8; 1 << 16];
    let options = EncodeOptions {
        explicit_cylinders,
        ..Default::default()
    };
    let n = encode_into(&s.as_ref(), &v, &cy, &options, &mut out).unwrap();
    let e = decode(&out[..n]).unwrap_err();
    // The same checks without allocation.
    let mut objects = [SceneObject::BLANK; 8];
    let mut points = [Point::default(); 32];
    let mut open = [ZERO_SLOTS; Scratch::open_len(8)];
    let mut vs = [BLANK_VERTEX; 64];
    let mut cs = [BLANK_CYLINDER; 256];
    let scratch = Scratch {
        objects: &mut objects,
        points: &mut points,
        open: &mut open,
    };
    if let Err(e2) = decode_into::<32, 8>(&out[..n], scratch, &mut vs, &mut cs) {
        assert_eq!(e2, e);
    }
    e
}

#[test]
fn ids_out_of_range_are_named() {
    let (s, c, _) = small_file();
    let nc = c.cylinders().len();
    let nv = c.vertices().len();
    let e = decode_edited(&s, &c, |_, cy| {
        cy[17].left_neighbour = CylinderId::from_index(9999)
    });
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: Arena::Cylinder,
                index: 17,
                field: "left_neighbour",
                problem: Problem::OutOfRange { value: 9999, limit },
                ..
            } if limit == nc as u64
        ),
        "{e:?}"
    );
    let text = e.to_string();
    assert!(
        text.starts_with(&format!(
            "cylinder 17: left_neighbour 9999 out of range (must be < {nc}) (byte "
        )),
        "{text}"
    );
    let e = decode_edited(&s, &c, |_, cy| cy[3].floor = Some(ObjectId(3)));
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: Arena::Cylinder,
                index: 3,
                field: "floor",
                ..
            }
        ),
        "{e:?}"
    );
    let e = decode_edited(&s, &c, |_, cy| {
        cy[5].top = Some(vcx::line_space::Chain {
            object: ObjectId(7),
            bound: vcx::line_space::Bound::Upper,
        })
    });
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: Arena::Cylinder,
                index: 5,
                field: "top",
                ..
            }
        ),
        "{e:?}"
    );
    let e = decode_edited(&s, &c, |_, cy| {
        cy[0].right = Wall::Vertex(vcx::partition::VertexId::from_index(nv).unwrap())
    });
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: Arena::Cylinder,
                index: 0,
                field: "right",
                ..
            }
        ),
        "{e:?}"
    );
    let e = decode_edited(&s, &c, |v, _| v[2].bitangent.second = 1000);
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: Arena::Vertex,
                index: 2,
                field: "second",
                problem: Problem::OutOfRange { value: 1000, .. },
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn broken_links_are_named() {
    let (s, c, _) = small_file();
    // A neighbour that does not link back.
    let i = c
        .cylinders()
        .iter()
        .position(|c| c.right_neighbour.is_some())
        .unwrap();
    let e = decode_edited(&s, &c, |_, cy| {
        let r = cy[i].right_neighbour.unwrap().index();
        cy[r].left_neighbour = None;
    });
    assert!(
        matches!(e, FormatError::Element { arena: Arena::Cylinder, index, field: "right_neighbour", problem: Problem::NotSymmetric, .. } if index == i),
        "{e:?}"
    );
    // Vertices out of θ order.
    let e = decode_edited(&s, &c, |v, _| v.swap(0, 1));
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: Arena::Vertex,
                index: 1,
                problem: Problem::NotSorted,
                ..
            }
        ),
        "{e:?}"
    );
    // A vertex that is not a bitangent: the tangent vertex moved along its object.
    let e = decode_edited(&s, &c, |v, _| {
        let b = &mut v[0].bitangent;
        let o = s.as_ref().object(b.first_object).unwrap();
        b.first = o.first_vertex() + (b.first - o.first_vertex() + 1) % o.len();
    });
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: Arena::Vertex,
                index: 0,
                problem: Problem::NotTangent | Problem::NotSorted,
                ..
            }
        ),
        "{e:?}"
    );
    // Walls in the wrong order.
    let k = c
        .cylinders()
        .iter()
        .position(|c| matches!((c.left, c.right), (Wall::Vertex(_), Wall::Vertex(_))))
        .unwrap();
    let e = decode_edited(&s, &c, |_, cy| {
        let (l, r) = (cy[k].left, cy[k].right);
        cy[k].left = r;
        cy[k].right = l;
    });
    assert!(
        matches!(e, FormatError::Element { arena: Arena::Cylinder, index, .. } if index == k)
            || matches!(
                e,
                FormatError::Element {
                    arena: Arena::Cylinder,
                    ..
                }
            ),
        "{e:?}"
    );
    // Everything in range and linked, but the complex is wrong (a chain at θ = 0 on the
    // wrong side of its object): `validate` catches it.
    let e = decode_edited(&s, &c, |_, cy| {
        let j = cy
            .iter()
            .position(|c| c.left == Wall::Zero && c.bottom.is_some())
            .unwrap();
        let b = cy[j].bottom.as_mut().unwrap();
        b.bound = match b.bound {
            vcx::line_space::Bound::Lower => vcx::line_space::Bound::Upper,
            vcx::line_space::Bound::Upper => vcx::line_space::Bound::Lower,
        };
    });
    assert!(matches!(e, FormatError::Complex { .. }), "{e:?}");
}

/// Version 3: vertices and cylinders at θ = 0 that do not replay into a partition are
/// named (the vertex, or the cylinder at θ = 0, and its byte offset).
#[test]
fn replay_failures_are_named() {
    let (s, c, _) = small_file();
    let at_zero = |cy: &[vcx::partition::Cylinder]| {
        cy.iter()
            .enumerate()
            .filter(|(_, c)| c.left == Wall::Zero)
            .map(|(i, _)| i)
            .collect::<Vec<_>>()
    };
    let zero = at_zero(c.cylinders());
    assert_eq!(zero.len(), 3 * s.as_ref().len() + 1);
    // A vertex left out (and three cylinders, so the counts agree): some later vertex
    // closes a corner face that is not open, or the cylinders open at 2π do not match.
    let e = decode_edited_as(false, &s, &c, |v, cy| {
        v.remove(1);
        cy.truncate(cy.len() - 3);
    });
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: Arena::Vertex | Arena::Cylinder,
                problem: Problem::Replay(_),
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("do not replay"), "{e}");
    // Every vertex removed but the first: the first replays, the wrap at 2π does not.
    let e = decode_edited_as(false, &s, &c, |v, cy| {
        let n = v.len();
        v.truncate(1);
        cy.truncate(cy.len() - 3 * (n - 1));
    });
    assert!(
        matches!(
            e,
            FormatError::Element {
                problem: Problem::Replay(_),
                ..
            }
        ),
        "{e:?}"
    );
    // A cylinder at θ = 0 copied over another: three on one chain.
    let (a, b) = (zero[1], zero[2]);
    let e = decode_edited_as(false, &s, &c, |_, cy| {
        let copy = cy[a];
        cy[b] = copy;
    });
    assert!(
        matches!(
            e,
            FormatError::Element {
                problem: Problem::Replay(_) | Problem::NotSymmetric,
                ..
            } | FormatError::Complex { .. }
        ),
        "{e:?}"
    );
    // A floor at θ = 0 changed: the replay may still close every corner face, but the
    // partition is wrong: either the replay or `validate` (the cross-section) refuses it.
    for &i in &zero {
        let e = decode_edited_as(false, &s, &c, |_, cy| {
            cy[i].floor = match cy[i].floor {
                None => Some(ObjectId(0)),
                Some(_) => None,
            }
        });
        assert!(
            matches!(
                e,
                FormatError::Element {
                    problem: Problem::Replay(_),
                    ..
                } | FormatError::Complex { .. }
            ),
            "cylinder {i}: {e:?}"
        );
    }
}

#[test]
fn bad_scene_values_are_named() {
    let (_, _, bytes) = small_file();
    let h = Header::read(&bytes).unwrap();
    let start = h.part_range(format::Part::Scene).start;
    // Object 0: material discriminant 0 (opaque) → 9.
    let mut b = bytes.clone();
    assert_eq!(b[start], 0);
    b[start] = 9;
    reseal(&mut b);
    let e = decode(&b).unwrap_err();
    assert!(
        matches!(e, FormatError::Element { arena: Arena::Object, index: 0, field: "material", offset, .. } if offset == start),
        "{e:?}"
    );
    // Object 0: 3 vertices → 2.
    let mut b = bytes.clone();
    assert_eq!(b[start + 1], 3);
    b[start + 1] = 2;
    reseal(&mut b);
    let e = decode(&b).unwrap_err();
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: Arena::Object,
                index: 0,
                field: "vertices",
                problem: Problem::TooFewVertices(2),
                ..
            }
        ),
        "{e:?}"
    );
    // A scene that decodes but is invalid (objects overlap) is a scene error.
    let tri = [pt(0, 0), pt(4, 0), pt(0, 3)];
    let s = Scene::new([(Material::Opaque, &tri[..])]).unwrap();
    let c = build_by_sweep(&s.as_ref()).unwrap();
    let mut b = encode(&s.as_ref(), &c, None, &EncodeOptions::default()).unwrap();
    // Move vertex 1 onto vertex 0: x of vertex 1 is at scene start + 2 + 2·(varint x0, y0).
    let h = Header::read(&b).unwrap();
    let p = h.part_range(format::Part::Scene).start + 2;
    assert_eq!(&b[p..p + 2], &[0, 0]);
    let x1 = p + 2;
    // 4 units = 2^18 raw, zigzag 2^19: a 3-byte varint.
    let len = 3;
    b.splice(x1..x1 + len, [0u8]);
    let scene_bytes = h.scene_bytes - (len as u32 - 1);
    set_u32(&mut b, format::offset::SCENE_BYTES, scene_bytes);
    reseal(&mut b);
    let e = decode(&b).unwrap_err();
    assert!(matches!(e, FormatError::Scene { .. }), "{e:?}");
}

/// The device path: decode into caller storage, rebuild the derived state into caller
/// buffers (`Complex::from_slices`), walk — the views equal those of the `alloc` path.
#[test]
fn decoded_slices_walk_like_the_owned_complex() {
    use vcx::partition::BorderSizes;
    let s = without_screens(&example("hall").as_ref());
    let c = build_by_sweep(&s.as_ref()).unwrap();
    let bytes = encode(&s.as_ref(), &c, None, &EncodeOptions::default()).unwrap();
    let h = Header::read(&bytes).unwrap();
    let (n, nv, v, nc) = (
        h.objects as usize,
        h.scene_vertices as usize,
        h.complex_vertices as usize,
        h.cylinders as usize,
    );
    let mut objects = vec![SceneObject::BLANK; n];
    let mut points = vec![Point::default(); nv];
    let mut open = vec![ZERO_SLOTS; Scratch::open_len(n)];
    let mut vertices = vec![BLANK_VERTEX; v];
    let mut cylinders = vec![BLANK_CYLINDER; nc];
    let d = decode_into::<128, 32>(
        &bytes,
        Scratch {
            objects: &mut objects,
            points: &mut points,
            open: &mut open,
        },
        &mut vertices,
        &mut cylinders,
    )
    .unwrap();
    let sizes = BorderSizes::for_counts(n, v, nc);
    let mut border = common::BorderVecs::new(sizes);
    let scene = d.scene.as_ref();
    let walkable = Complex::from_slices(&scene, d.vertices, d.cylinders, border.buffers()).unwrap();
    let owned = decode(&bytes).unwrap();
    let mut compared = 0;
    for q in sample_points(&scene, 20, 4) {
        let a = view(&walkable, &scene, q).map(|v| {
            v.iter()
                .map(|i| (i.start.vector(), i.object, i.start_vertex))
                .collect::<Vec<_>>()
        });
        let b = view_key(&owned.complex, &owned.scene.as_ref(), q);
        match (a, b) {
            (Ok(a), Ok(b)) => {
                assert_eq!(a, b, "{q:?}");
                compared += 1;
            }
            (Err(_), Err(_)) => {}
            (a, b) => panic!("{q:?}: slices {a:?}, owned {b:?}"),
        }
    }
    assert!(compared > 5);
}

// ---------------------------------------------------------------------------------------
// The history part.

/// A scene built by the randomized construction and written with its history.
fn with_history(s: &Scene, seed: u64) -> (History, Complex, Vec<u8>) {
    let sr = s.as_ref();
    let h = History::build(
        &sr,
        &BuildOptions {
            seed,
            ..Default::default()
        },
    )
    .unwrap();
    let c = h.complex(&sr).unwrap();
    let options = EncodeOptions {
        seed: Some(seed),
        compacted: false,
        explicit_cylinders: false,
    };
    let bytes = encode(&sr, &c, Some(&h), &options).unwrap();
    (h, c, bytes)
}

/// The small golden scene with its history: small enough for every bit flip.
fn small_history_file() -> (Scene, History, Vec<u8>) {
    let s = small_scene();
    let (h, _, bytes) = with_history(&s, 7);
    (s, h, bytes)
}

/// Random rays over the scene's box: free points only (`locate` needs one) and non-zero
/// directions, some through pairs of scene vertices (degenerate on purpose).
fn random_rays(
    s: &SceneRef<'_>,
    k: usize,
    seed: u64,
) -> Vec<(QueryPoint, vcx::geom::predicates::Direction)> {
    use vcx::geom::predicates::Direction;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let points = sample_points(s, 3 * k, seed);
    let v = s.vertices();
    let mut rays = Vec::new();
    for q in points {
        if rays.len() == k {
            break;
        }
        if vcx::partition::point_in_scene(s, q).is_some() {
            continue;
        }
        let d = if rng.gen_bool(0.3) && v.len() >= 2 {
            let (a, b) = (v[rng.gen_range(0..v.len())], v[rng.gen_range(0..v.len())]);
            Direction::new(
                i64::from(b.x()) - i64::from(a.x()),
                i64::from(b.y()) - i64::from(a.y()),
            )
        } else {
            Direction::new(rng.gen_range(-1000..=1000), rng.gen_range(-1000..=1000))
        };
        if let Some(d) = d {
            rays.push((q, d));
        }
    }
    rays
}

/// Round trip with history: the header and flags, the decoded history's statistics, and
/// `locate` / `locate_on_sheet` of the decoded history equal the original's on thousands of
/// random rays; the located floor and ceiling agree with the exact reference on some.
fn history_round_trip(name: &str, rays: usize) {
    use vcx_tests::reference::{shoot_perturbed, Vec2};
    let s = example(name);
    let sr = s.as_ref();
    let (h, c, bytes) = with_history(&s, 3);
    let header = Header::read(&bytes).unwrap();
    assert!(header.has_history());
    assert!(
        header.compacted,
        "a written history sets the compacted flag"
    );
    assert_eq!(header.history_nodes as usize, h.stats().nodes);
    assert_eq!(header.history_links as usize, h.stats().links);
    let loaded = decode(&bytes).unwrap_or_else(|e| panic!("{name}: decode: {e}"));
    let back = loaded.history.as_ref().expect("the history is decoded");
    let dr = loaded.scene.as_ref();
    back.validate(&dr).unwrap();
    assert_eq!(back.stats(), h.stats());
    assert_eq!(back.order(), h.order());
    assert_eq!(loaded.complex.cylinders(), c.cylinders());
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let (mut located, mut on_sheet, mut referenced) = (0, 0, 0);
    for (k, (q, d)) in random_rays(&sr, rays, 5).into_iter().enumerate() {
        let a = h.locate(&sr, q, d).map(|(i, c)| (i, *c));
        let b = back.locate(&dr, q, d).map(|(i, c)| (i, *c));
        assert_eq!(a, b, "{name}: locate {q:?} {d:?}");
        located += usize::from(a.is_some());
        if k < 40 {
            let want = shoot_perturbed(sr, &Vec2::from_query(q), &Vec2::from_i64(d.x, d.y))
                .unwrap_or_else(|e| panic!("{name}: reference {q:?}: {e:?}"));
            let got = b.unwrap_or_else(|| panic!("{name}: nothing located for {q:?} {d:?}"));
            assert_eq!(
                (got.1.ceiling, got.1.floor),
                (want.forward, want.backward),
                "{name}: {q:?} {d:?} against the reference"
            );
            referenced += 1;
        }
        // Sheet-anchored location from every kind of object, the line crossing it or not.
        let m = ObjectId(rng.gen_range(0..sr.len() as u32));
        let a = h.locate_on_sheet(&sr, m, q, d).map(|(i, c)| (i, *c));
        let b = back.locate_on_sheet(&dr, m, q, d).map(|(i, c)| (i, *c));
        assert_eq!(a, b, "{name}: locate_on_sheet {m:?} {q:?} {d:?}");
        on_sheet += usize::from(a.is_some());
    }
    eprintln!("{name}: {located} located, {on_sheet} on a sheet, {referenced} referenced");
    assert!(
        located >= rays * 9 / 10,
        "{name}: only {located} rays located"
    );
    assert!(on_sheet > 20, "{name}: only {on_sheet} sheet locations");
}

#[test]
fn history_round_trip_mixed() {
    history_round_trip("mixed", 3000);
}

#[test]
fn history_round_trip_hall() {
    history_round_trip("hall", 3000);
}

/// A history built without search path compaction (§4.4) is written with the compacted
/// flag clear and loads back as it was: the same arenas, not compacted, `locate` and
/// `locate_on_sheet` as the original's. Setting the flag on it is refused (its piece
/// nodes are not compacted); clearing it on a compacted history is accepted.
#[test]
fn uncompacted_history_round_trip() {
    use vcx::partition::ComplexError;
    let s = example("mixed");
    let sr = s.as_ref();
    let h = History::build(
        &sr,
        &BuildOptions {
            seed: 3,
            compaction: false,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(!h.is_compacted());
    let c = h.complex(&sr).unwrap();
    let options = EncodeOptions {
        seed: Some(3),
        compacted: true,
        explicit_cylinders: false,
    };
    let bytes = encode(&sr, &c, Some(&h), &options).unwrap();
    let header = Header::read(&bytes).unwrap();
    assert!(header.has_history() && !header.compacted);
    assert_eq!(header.history_nodes as usize, h.stats().nodes);
    let loaded = decode(&bytes).unwrap();
    let back = loaded.history.as_ref().unwrap();
    assert!(!back.is_compacted());
    assert_eq!(back.to_parts(), h.to_parts());
    assert_eq!(back.stats(), h.stats());
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for (q, d) in random_rays(&sr, 500, 9) {
        let a = h.locate(&sr, q, d).map(|(i, c)| (i, *c));
        assert_eq!(a, back.locate(&sr, q, d).map(|(i, c)| (i, *c)));
        let m = ObjectId(rng.gen_range(0..sr.len() as u32));
        let a = h.locate_on_sheet(&sr, m, q, d).map(|(i, c)| (i, *c));
        assert_eq!(a, back.locate_on_sheet(&sr, m, q, d).map(|(i, c)| (i, *c)));
    }
    // The flag set on the uncompacted history: refused, naming a piece node.
    let compacted = History::build(
        &sr,
        &BuildOptions {
            seed: 3,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(
        h.stats().nodes > compacted.stats().nodes,
        "no piece nodes on this scene"
    );
    let flags = format::offset::FLAGS;
    let mut b = bytes.clone();
    b[flags] |= format::FLAG_COMPACTED as u8;
    reseal(&mut b);
    let e = decode(&b).unwrap_err();
    assert!(
        matches!(
            e,
            FormatError::History {
                error: ComplexError::History { what, .. },
                ..
            } if what.contains("piece")
        ),
        "{e:?}"
    );
    // The flag cleared on a compacted history: a valid (trivially uncompacted) history.
    let mut b = encode(&sr, &c, Some(&compacted), &options).unwrap();
    assert!(Header::read(&b).unwrap().compacted);
    b[flags] &= !(format::FLAG_COMPACTED as u8);
    reseal(&mut b);
    let loaded = decode(&b).unwrap();
    assert!(!loaded.history.unwrap().is_compacted());
}

/// A file with history decodes without allocation too: the history part is skipped
/// (devices walk without it), the arenas equal those of the file without history.
#[test]
fn decode_into_skips_the_history() {
    let s = small_scene();
    let (_, c, bytes) = with_history(&s, 7);
    let plain = encode(
        &s.as_ref(),
        &c,
        None,
        &EncodeOptions {
            seed: Some(7),
            compacted: true,
            explicit_cylinders: true,
        },
    )
    .unwrap();
    assert!(bytes.len() > plain.len());
    // Scene and complex parts are the same bytes with or without the history (both store
    // every cylinder: version 1).
    let h = Header::read(&bytes).unwrap();
    let end = h.part_range(format::Part::Complex).end;
    assert_eq!(
        bytes[format::HEADER_LEN..end],
        plain[format::HEADER_LEN..end]
    );
    let mut objects = [SceneObject::BLANK; 8];
    let mut points = [Point::default(); 32];
    let mut vertices = [BLANK_VERTEX; 64];
    let mut cylinders = [BLANK_CYLINDER; 256];
    let d = decode_into::<32, 8>(
        &bytes,
        Scratch {
            objects: &mut objects,
            points: &mut points,
            open: &mut [],
        },
        &mut vertices,
        &mut cylinders,
    )
    .unwrap();
    assert!(d.header.has_history());
    assert_eq!(d.vertices, c.vertices());
    assert_eq!(d.cylinders, c.cylinders());
    // The checksum still covers the history part.
    let mut b = bytes.clone();
    let last = b.len() - 5;
    b[last] ^= 1;
    let e = decode_into::<32, 8>(
        &b,
        Scratch {
            objects: &mut objects,
            points: &mut points,
            open: &mut [],
        },
        &mut vertices,
        &mut cylinders,
    )
    .unwrap_err();
    assert!(matches!(e, FormatError::Checksum { .. }), "{e:?}");
}

/// After a successful decode of a damaged file with history: the history is valid too.
fn check_history_survivor(loaded: &format::Loaded) {
    check_survivor(loaded);
    if let Some(h) = &loaded.history {
        let s = loaded.scene.as_ref();
        h.validate(&s).unwrap();
        for (q, d) in random_rays(&s, 4, 3) {
            let _ = h.locate(&s, q, d);
            let _ = h.locate_on_sheet(&s, ObjectId(0), q, d);
        }
    }
}

#[test]
fn every_truncation_with_history_is_an_error() {
    let (_, _, bytes) = small_history_file();
    for len in 0..bytes.len() {
        assert!(
            decode(&bytes[..len]).is_err(),
            "truncated to {len}: decoded"
        );
    }
    // Truncated inside the history part with its length and the checksum fixed up.
    let h = Header::read(&bytes).unwrap();
    let start = h.part_range(format::Part::History).start;
    for cut in start..bytes.len() - 4 {
        let mut b = bytes[..cut].to_vec();
        b.extend_from_slice(&[0; 4]);
        set_u32(&mut b, format::offset::HISTORY_BYTES, (cut - start) as u32);
        reseal(&mut b);
        let e = decode(&b);
        assert!(e.is_err(), "history cut at {cut}: decoded");
    }
}

#[test]
fn every_bit_flip_with_history_is_an_error() {
    let (_, _, bytes) = small_history_file();
    flip_every_bit("file with history", &bytes, check_history_survivor);
}

/// A child link to an older node (a cycle in the DAG) is refused, naming the history
/// part; so are other arenas that do not fit.
#[test]
fn history_cycle_is_refused() {
    use vcx::partition::ComplexError;
    let s = small_scene();
    let sr = s.as_ref();
    let (h, c, _) = with_history(&s, 7);
    let parts = h.to_parts();
    // A dead node past the root: its first child becomes its parent-or-older node.
    let (node, &(start, _)) = parts
        .children
        .iter()
        .enumerate()
        .skip(1)
        .find(|(_, k)| k.1 > 0)
        .unwrap();
    let mut bad = parts.clone();
    bad.links[start as usize] = CylinderId::from_index(node - 1).unwrap();
    let bytes = format::encode_history_parts(&sr, &c, &bad, &EncodeOptions::default()).unwrap();
    let e = decode(&bytes).unwrap_err();
    let at = Header::read(&bytes)
        .unwrap()
        .part_range(format::Part::History)
        .start;
    assert!(
        matches!(e, FormatError::History { offset, error: ComplexError::History { node: n, .. } } if offset == at && n == node),
        "{e:?}"
    );
    let text = e.to_string();
    assert!(
        text.starts_with(&format!("history part (byte {at})")),
        "{text}"
    );
    assert!(text.contains("younger"), "{text}");
    // A link out of range is named by element.
    let mut bad = parts.clone();
    bad.links[start as usize] = CylinderId::from_index(parts.nodes.len()).unwrap();
    let bytes = format::encode_history_parts(&sr, &c, &bad, &EncodeOptions::default()).unwrap();
    let e = decode(&bytes).unwrap_err();
    assert!(
        matches!(
            e,
            FormatError::Element {
                arena: Arena::Link,
                field: "node",
                problem: Problem::OutOfRange { .. },
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().starts_with("history part: link "), "{e}");
    // Live cylinders that are not the complex part's: another complex with this history.
    let other = build_by_sweep(&sr).unwrap();
    if other.cylinders() != c.cylinders() {
        let bytes =
            format::encode_history_parts(&sr, &other, &parts, &EncodeOptions::default()).unwrap();
        assert!(
            matches!(decode(&bytes), Err(FormatError::History { .. })),
            "{:?}",
            decode(&bytes).map(|_| ())
        );
        // `encode` refuses to write it.
        assert!(matches!(
            encode(&sr, &other, Some(&h), &EncodeOptions::default()),
            Err(FormatError::NotEncodable(_))
        ));
    }
    // The vertex count prefix inflated: refused before anything is reserved.
    let good = encode(&sr, &c, Some(&h), &EncodeOptions::default()).unwrap();
    let at = Header::read(&good)
        .unwrap()
        .part_range(format::Part::History)
        .start;
    let mut b = good[..at].to_vec();
    b.extend_from_slice(&[0xff, 0xff, 0xff, 0xff, 0x0f]);
    let old = {
        let mut n = 0;
        while good[at + n] & 0x80 != 0 {
            n += 1;
        }
        n + 1
    };
    b.extend_from_slice(&good[at + old..]);
    let hb = u32::from_le_bytes(good[52..56].try_into().unwrap()) + 5 - old as u32;
    set_u32(&mut b, format::offset::HISTORY_BYTES, hb);
    reseal(&mut b);
    let e = decode(&b).unwrap_err();
    assert!(
        matches!(
            e,
            FormatError::Count {
                field: "history_vertices",
                problem: CountProblem::ExceedsPart { .. },
                ..
            }
        ),
        "{e:?}"
    );
    assert!(
        e.to_string().starts_with("history part: history_vertices"),
        "{e}"
    );
}
