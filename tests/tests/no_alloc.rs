//! Walking a complex in caller-provided storage allocates nothing, and the firmware's code
//! path gives the right views.
//!
//! * A counting global allocator (`stats_alloc`, wrapping `System`) counts every heap
//!   allocation; the complex is built first, then the counter is read around the walk only.
//!   Other tests of this binary run on other threads and the allocator is global, so each
//!   measurement is repeated and the smallest count must be zero: an allocation on the walk
//!   path happens on every repetition and still fails the test.
//! * The firmware (`firmware/`) embeds `firmware/hall.vcx`, the complex file of
//!   `std-demo/scenes/hall.json` as `vcx build std-demo/scenes/hall.json -o
//!   firmware/hall.vcx --history never` writes it, and its viewpoints in
//!   `firmware/src/viewpoints.rs`; `firmware_vcx_is_fresh` and
//!   `firmware_viewpoints_are_fresh` fail when either differs from what a fresh build
//!   produces. Regenerate both with
//!   `cargo test -p vcx-tests --test no_alloc -- --ignored regenerate_firmware_data`.
//! * `firmware/src/app.rs` is included here verbatim and run on the same bytes (decoding,
//!   rebuild, views, counted by the allocator): its views are compared with `walk::view`
//!   on the owned complex and with the exact reference, and its ray-tree frames (depth 4
//!   through the hall's mirrors, 90°, 64 columns) with `walk::frame_tree` on the owned
//!   complex, interval by interval and piece by piece of the coverage.

mod common;

use core::fmt::Write as _;
use std::alloc::System;
use std::sync::Mutex;

use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use vcx::format::{EncodeOptions, FormatError};
use vcx::geom::sos::Angle;
use vcx::partition::{build_by_sweep, BorderSizes, BuildOptions, Complex, Cylinder, History};
use vcx::walk::{view, view_capacity, view_into, ViewInterval, WalkError};
use vcx::{Material, QueryPoint, Scene, SceneRef, SubScene};
use vcx_demo::generate::{generate, SceneKind};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

#[rustfmt::skip]
#[path = "../../firmware/src/viewpoints.rs"]
mod viewpoints;

#[allow(dead_code)]
#[path = "../../firmware/src/app.rs"]
mod app;

/// Serializes the tests of this file: every test takes it, so that no other test's
/// allocations land in a measured region (the counter is global to the process).
static LOCK: Mutex<()> = Mutex::new(());

fn lock() -> std::sync::MutexGuard<'static, ()> {
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

/// Heap allocations (including reallocations) made while `f` runs: the smallest count of
/// five runs (see the module comment). The runs yield between them: the harness's thread,
/// starting the next test while this one holds the lock, allocates in bursts, which a
/// loaded machine can spread over a few short runs (seen once under a load of 5 on 2 cores).
fn allocations<R>(mut f: impl FnMut() -> R) -> (usize, R) {
    let mut least = usize::MAX;
    let mut result = None;
    for _ in 0..5 {
        std::thread::yield_now();
        let region = Region::new(GLOBAL);
        let r = f();
        let stats = region.change();
        least = least.min(stats.allocations + stats.reallocations);
        result = Some(r);
    }
    (least, result.expect("ran five times"))
}

fn same(a: &ViewInterval, b: &ViewInterval) -> bool {
    a.start.cmp_angle(&b.start) == core::cmp::Ordering::Equal
        && a.object == b.object
        && a.start_vertex == b.start_vertex
}

fn dummy() -> ViewInterval {
    ViewInterval {
        start: Angle::ZERO,
        object: None,
        start_vertex: None,
    }
}

/// Viewpoints for a scene: the free points of a 5×5 lattice over its bounding box, with
/// off-grid ones between (query-grid fractions, so they are not on the scene grid).
fn viewpoints(s: &SceneRef<'_>, limit: usize) -> Vec<QueryPoint> {
    let v = s.vertices();
    let (lo, hi) = v.iter().fold(
        ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN)),
        |(lo, hi), p| {
            let (x, y) = (i64::from(p.x()) << 16, i64::from(p.y()) << 16);
            ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y)))
        },
    );
    let mut out = Vec::new();
    for i in 0..5i64 {
        for j in 0..5i64 {
            let x = lo.0 + (hi.0 - lo.0) * (2 * i + 1) / 10 + 12345;
            let y = lo.1 + (hi.1 - lo.1) * (2 * j + 1) / 10 - 6789;
            if let Some(q) = QueryPoint::from_raw(x, y) {
                if vcx::partition::point_in_scene(s, q).is_none() && out.len() < limit {
                    out.push(q);
                }
            }
        }
    }
    out
}

/// Scenes for the allocation and equality checks.
fn scenes() -> Vec<(String, Scene)> {
    let mut out = Vec::new();
    for (kind, n, seed) in [
        (SceneKind::Grid, 16, 1),
        (SceneKind::Hall, 8, 2),
        (SceneKind::Mixed, 10, 3),
    ] {
        let f = generate(kind, n, seed).expect("generator");
        // Views treat screens as transparent; the complex of a view leaves them out.
        let s = f.scene.as_ref();
        let ids: Vec<_> = (0..s.len() as u32)
            .map(vcx::ObjectId)
            .filter(|&id| s.object(id).is_some_and(|o| o.material != Material::Screen))
            .collect();
        let sub = SubScene::new(s, ids);
        let polys: Vec<(Material, Vec<vcx::Point>)> = sub
            .as_ref()
            .objects()
            .iter()
            .map(|o| (o.material, sub.as_ref().polygon(o).to_vec()))
            .collect();
        let scene = Scene::new(polys.iter().map(|(m, p)| (*m, p.as_slice()))).expect("valid");
        out.push((format!("{kind:?} {n}"), scene));
    }
    out
}

/// A view into a caller buffer, over slice storage rebuilt into caller buffers, allocates
/// nothing and equals the view of the owned complex.
#[test]
fn view_into_slices_allocates_nothing() {
    let _g = lock();
    let mut checked = 0;
    for (name, scene) in scenes() {
        let s = scene.as_ref();
        let owned = build_by_sweep(&s).expect("build");
        let sizes = BorderSizes::exact(s.len(), owned.vertices().len(), owned.cylinders());
        let (vertices, cylinders) = (owned.vertices().to_vec(), owned.cylinders().to_vec());
        let mut border = common::BorderVecs::new(sizes);
        let mut out = vec![dummy(); view_capacity(s.len())];
        let points = viewpoints(&s, 12);
        let mut wants = Vec::new();
        for &q in &points {
            wants.push(view(&owned, &s, q).expect("owned view"));
        }

        // Rebuilding the derived state allocates nothing either.
        let (n, complex) = allocations(|| {
            let buffers = border.buffers();
            Complex::from_slices(&s, &vertices, &cylinders, buffers).map(|c| c.vertices().len())
        });
        assert_eq!(n, 0, "{name}: rebuild_into allocated");
        assert_eq!(complex, Ok(vertices.len()));
        let buffers = border.buffers();
        let complex = Complex::from_slices(&s, &vertices, &cylinders, buffers).expect("fits");
        assert_eq!(complex.borders_ref().bytes(), sizes.bytes(), "{name}");

        for (q, want) in points.iter().zip(&wants) {
            let (n, got) = allocations(|| view_into(&complex, &s, *q, &mut out));
            assert_eq!(n, 0, "{name} q {q:?}: view_into allocated");
            let got = got.expect("walk");
            assert_eq!(got, want.len(), "{name} q {q:?}");
            for (g, w) in out.iter().zip(want) {
                assert!(same(g, w), "{name} q {q:?}: {g:?} vs {w:?}");
            }
            // A buffer one short is an error, not a panic or a truncated view.
            if let Some(short) = out.get_mut(..got.saturating_sub(1)) {
                assert!(matches!(
                    view_into(&complex, &s, *q, short),
                    Err(WalkError::BufferFull { .. })
                ));
            }
            checked += 1;
        }

        // Without stored angles (computed per wall): same views, still no allocation.
        let mut lean_border = common::BorderVecs::new(BorderSizes { angles: 0, ..sizes });
        let lean =
            Complex::from_slices(&s, &vertices, &cylinders, lean_border.buffers()).expect("fits");
        for (q, want) in points.iter().zip(&wants) {
            let (n, got) = allocations(|| view_into(&lean, &s, *q, &mut out));
            assert_eq!(n, 0, "{name}: lean view_into allocated");
            assert_eq!(got, Ok(want.len()));
            assert!(out.iter().zip(want).all(|(g, w)| same(g, w)), "{name}");
        }
    }
    assert!(checked >= 20, "{checked}");
}

/// Buffers that are too short are reported by name.
#[test]
fn short_buffers_are_errors() {
    let _g = lock();
    let f = generate(SceneKind::Grid, 9, 4).expect("generator");
    let s = f.scene.as_ref();
    let c = build_by_sweep(&s).expect("build");
    let sizes = BorderSizes::exact(s.len(), c.vertices().len(), c.cylinders());
    let mut border = common::BorderVecs::new(BorderSizes {
        ids: sizes.ids - 1,
        ..sizes
    });
    let buffers = border.buffers();
    let err = Complex::from_slices(&s, c.vertices(), c.cylinders(), buffers).unwrap_err();
    assert_eq!((err.buffer, err.needed), ("ids", sizes.ids));
    let bound = BorderSizes::for_counts(s.len(), c.vertices().len(), c.cylinders().len());
    assert!(bound.ids >= sizes.ids && bound.offsets == sizes.offsets);
}

// ---------------------------------------------------------------------------------------
// The firmware's data and code path.

const SOURCE_SCENE: &str = "std-demo/scenes/hall.json";
const FIRMWARE_VCX: &str = "firmware/hall.vcx";
const FIRMWARE_VIEWPOINTS: &str = "firmware/src/viewpoints.rs";
/// Viewpoints the firmware walks.
const VIEWPOINT_COUNT: usize = 6;

fn repo_path(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
}

fn source_scene() -> Scene {
    vcx_demo::scene_file::load(repo_path(SOURCE_SCENE))
        .expect("scene file")
        .scene
}

/// The bytes of `firmware/hall.vcx`, as `vcx build SOURCE_SCENE -o firmware/hall.vcx
/// --history never` writes them (`std-demo/src/cmd/build.rs`): the randomized construction
/// with seed 0, its live partition encoded without history, seed recorded.
fn generate_vcx() -> Vec<u8> {
    let scene = source_scene();
    let s = scene.as_ref();
    let options = BuildOptions {
        seed: 0,
        first: Vec::new(),
        ..Default::default()
    };
    let history = History::build(&s, &options).expect("build");
    let complex = history.complex(&s).expect("live partition");
    complex.validate(&s).expect("valid");
    let options = EncodeOptions {
        seed: Some(0),
        compacted: true,
        explicit_cylinders: false,
    };
    vcx::format::encode(&s, &complex, None, &options).expect("encode")
}

/// The source of `firmware/src/viewpoints.rs`.
fn generate_viewpoints() -> String {
    let scene = source_scene();
    let points = viewpoints(&scene.as_ref(), VIEWPOINT_COUNT);
    let mut o = String::new();
    let w = &mut o;
    let _ = writeln!(
        w,
        "//! Generated from `{SOURCE_SCENE}` by\n//! `cargo test -p vcx-tests --test no_alloc -- \
         --ignored regenerate_firmware_data`;\n//! do not edit \
         (`firmware_viewpoints_are_fresh` checks it). The viewpoints the firmware\n//! walks: \
         what the `.vcx` file cannot hold. Not formatted (`#[rustfmt::skip]` where it is\n//! \
         declared).\n\n/// Viewpoints (raw query coordinates, 2⁻³²).\n\
         pub static VIEWPOINTS: [(i64, i64); {}] = [",
        points.len()
    );
    for q in &points {
        let _ = writeln!(w, "    ({}, {}),", q.x(), q.y());
    }
    let _ = writeln!(w, "];");
    o
}

/// Writes `firmware/hall.vcx` and `firmware/src/viewpoints.rs` (run by hand after the
/// scene, the construction or the format changes).
#[test]
#[ignore = "writes firmware/hall.vcx and firmware/src/viewpoints.rs"]
fn regenerate_firmware_data() {
    std::fs::write(repo_path(FIRMWARE_VCX), generate_vcx()).expect("write");
    std::fs::write(repo_path(FIRMWARE_VIEWPOINTS), generate_viewpoints()).expect("write");
}

const STALE: &str = "stale: run `cargo test -p vcx-tests --test no_alloc -- --ignored \
                     regenerate_firmware_data`";

/// The checked-in `.vcx` file is what a fresh build of the scene file writes, and it is
/// the file the firmware embeds.
#[test]
fn firmware_vcx_is_fresh() {
    let _g = lock();
    let want = generate_vcx();
    let got = std::fs::read(repo_path(FIRMWARE_VCX)).expect("read");
    assert!(got == want, "{FIRMWARE_VCX} is {STALE}");
    assert!(app::VCX == want.as_slice(), "app.rs embeds another file");
}

/// The checked-in viewpoints are what the generator produces.
#[test]
fn firmware_viewpoints_are_fresh() {
    let _g = lock();
    let got = std::fs::read_to_string(repo_path(FIRMWARE_VIEWPOINTS)).expect("read");
    assert!(
        got == generate_viewpoints(),
        "{FIRMWARE_VIEWPOINTS} is {STALE}"
    );
}

/// The buffer sizes the firmware reads from the header at compile time are the file's
/// counts, and every buffer is exactly as long as the file needs.
#[test]
fn firmware_capacities_are_the_header_counts() {
    let _g = lock();
    let h = vcx::format::Header::read(app::VCX).expect("header");
    let counts = [h.objects, h.scene_vertices, h.complex_vertices, h.cylinders];
    let capacities = [
        app::OBJECTS,
        app::SCENE_VERTICES,
        app::COMPLEX_VERTICES,
        app::CYLINDERS,
    ];
    assert_eq!(counts.map(|c| c as usize), capacities);
    assert!(
        !h.has_history(),
        "the firmware file is written without history"
    );
}

/// The firmware's code path (`app::decode` of the embedded bytes into `app::Arenas`,
/// `app::complex` into `app::Ram`, `app::views`) allocates nothing, decodes the same
/// complex as the allocating `format::decode`, and its views equal `walk::view` of the
/// owned complex built by the sweep and the exact reference.
#[test]
fn firmware_walk_matches_owned_view_and_reference() {
    let _g = lock();
    let mut arenas = Box::new(app::Arenas::new());
    let mut ram = Box::new(app::Ram::new());
    let mut out = app::out();
    // Results are copied into preallocated storage, so the callback allocates nothing.
    let mut got: Vec<Vec<ViewInterval>> = (0..viewpoints::VIEWPOINTS.len())
        .map(|_| Vec::with_capacity(app::CAPACITY))
        .collect();
    // As `firmware/src/main.rs` does: decode and check the file, rebuild the derived
    // state, walk the views.
    let (n, checksum) = allocations(|| {
        for g in got.iter_mut() {
            g.clear();
        }
        let file = app::decode(app::VCX, &mut arenas)?;
        let s = file.scene.as_ref();
        let complex = app::complex(&s, file.vertices, file.cylinders, &mut ram)?;
        app::views(&complex, &s, &mut out, |k, view| {
            if let Some(g) = got.get_mut(k) {
                g.extend_from_slice(view);
            }
        })
    });
    assert_eq!(n, 0, "the firmware path allocated");
    checksum.expect("firmware run");

    // The allocating decoder reads the same scene and complex.
    let loaded = vcx::format::decode(app::VCX).expect("decode");
    let file = app::decode(app::VCX, &mut arenas).expect("decode_into");
    let s = file.scene.as_ref();
    assert_eq!(file.vertices, loaded.complex.vertices());
    assert_eq!(file.cylinders, loaded.complex.cylinders());
    let source = source_scene();
    assert_eq!(s.objects(), source.as_ref().objects());
    assert_eq!(s.vertices(), source.as_ref().vertices());

    // The same views from the owned complex of the same scene (built by the other
    // construction), and from the reference.
    let owned = build_by_sweep(&s).expect("build");
    let all = SubScene::new(s, (0..s.len() as u32).map(vcx::ObjectId));
    let mut compared = 0;
    for (k, &(x, y)) in viewpoints::VIEWPOINTS.iter().enumerate() {
        let q = QueryPoint::from_raw(x, y).expect("in range");
        let want = view(&owned, &s, q).expect("owned view");
        assert_eq!(got[k].len(), want.len(), "viewpoint {k}");
        for (g, w) in got[k].iter().zip(&want) {
            assert!(same(g, w), "viewpoint {k}: {g:?} vs {w:?}");
        }
        assert!(
            vcx_tests::generators::compare_view(&s, &all, &owned, q).expect("matches reference"),
            "viewpoint {k} is free"
        );
        compared += 1;
    }
    assert_eq!(compared, VIEWPOINT_COUNT);
}

/// The firmware's ray-tree frames (`app::trees`: `frame_tree_into` through its
/// `TreeScratch`, kept in its fixed-capacity `Frame`, `angle_order`, `coverage`) allocate
/// nothing on the embedded bytes, and every frame equals `walk::frame_tree` of the owned
/// complex built by the sweep (which `tests/tests/ray_trees.rs` checks against the exact
/// reference) with the same camera: the same intervals (branch, start bits) in the same
/// order, and the same coverage, which covers each column once. The frames reach the full
/// depth, so the scratch's `depth + 1` walks and `depth` splits and hops are needed: one
/// fewer of any is `TreeTooDeep`.
#[test]
fn firmware_trees_match_owned_frame_tree() {
    use vcx::render::{angle_order, coverage, Camera, FrameInterval, Piece};
    use vcx::walk::frame_tree;
    let _g = lock();
    let mut arenas = Box::new(app::Arenas::new());
    let mut ram = Box::new(app::Ram::new());
    let mut scratch = Box::new(app::TreeRam::new());
    let mut frame = Box::new(app::Frame::new());
    let k_max = viewpoints::VIEWPOINTS.len();
    // Results are copied into preallocated storage, so the callback allocates nothing.
    let mut got: Vec<(Vec<FrameInterval>, Vec<Piece>, f64)> = (0..k_max)
        .map(|_| {
            (
                Vec::with_capacity(app::FRAME_CAPACITY),
                Vec::with_capacity(4 * app::FRAME_CAPACITY + app::COLUMNS),
                0.0,
            )
        })
        .collect();
    let file = app::decode(app::VCX, &mut arenas).expect("decode_into");
    let s = file.scene.as_ref();
    let complex = app::complex(&s, file.vertices, file.cylinders, &mut ram).expect("rebuild");
    let (n, checksum) = allocations(|| {
        for g in got.iter_mut() {
            g.0.clear();
            g.1.clear();
        }
        app::trees(
            &complex,
            &s,
            &mut scratch,
            &mut frame,
            |k, camera, f, sum| {
                if let Some(g) = got.get_mut(k) {
                    g.0.extend_from_slice(f);
                    coverage(camera, f, |p| {
                        if g.1.len() < g.1.capacity() {
                            g.1.push(p)
                        }
                    });
                    g.2 = sum;
                }
            },
        )
    });
    assert_eq!(n, 0, "the firmware's ray-tree frames allocated");
    checksum.expect("firmware trees");

    let owned = build_by_sweep(&s).expect("build");
    let mut most = 0;
    let mut deepest = 0;
    for (k, &(x, y)) in viewpoints::VIEWPOINTS.iter().enumerate() {
        let q = QueryPoint::from_raw(x, y).expect("in range");
        let camera = Camera::new(q, app::heading(k), app::FOV, app::COLUMNS).expect("camera");
        let (from, to) = camera.range();
        let mut want = frame_tree(&owned, &s, q, app::TREE_DEPTH, from, to).expect("owned tree");
        angle_order(&mut want);
        let (g, pieces, sum) = &got[k];
        assert_eq!(g.len(), want.len(), "viewpoint {k}");
        for (a, b) in g.iter().zip(&want) {
            assert_eq!(a.branch.as_slice(), b.branch.as_slice(), "viewpoint {k}");
            assert_eq!(a.start.to_bits(), b.start.to_bits(), "viewpoint {k}");
            let exact = match (&a.exact_start, &b.exact_start) {
                (Some(x), Some(y)) => x.cmp_angle(y) == core::cmp::Ordering::Equal,
                (x, y) => x.is_none() && y.is_none(),
            };
            assert!(exact, "viewpoint {k}: exact starts differ");
        }
        let mut want_pieces = Vec::new();
        coverage(&camera, &want, |p| want_pieces.push(p));
        assert_eq!(pieces, &want_pieces, "viewpoint {k}");
        let want_sum: f64 = want_pieces.iter().map(|p| p.fraction).sum();
        assert_eq!(sum.to_bits(), want_sum.to_bits(), "viewpoint {k}");
        let mut per_column = vec![0.0; app::COLUMNS];
        for p in &want_pieces {
            per_column[p.column] += p.fraction;
        }
        for (c, f) in per_column.iter().enumerate() {
            assert!((f - 1.0).abs() < 1e-9, "viewpoint {k} column {c}: {f}");
        }
        most = most.max(want.len());
        deepest = deepest.max(want.iter().map(|i| i.branch.len()).max().unwrap_or(0));
    }

    // The capacity holds the frame of any heading from these viewpoints (every 5°), not
    // only the six the firmware walks.
    let mut any_heading = 0;
    for &(x, y) in viewpoints::VIEWPOINTS.iter() {
        let q = QueryPoint::from_raw(x, y).expect("in range");
        for h in 0..72 {
            let heading = f64::from(h) * core::f64::consts::TAU / 72.0;
            let camera = Camera::new(q, heading, app::FOV, app::COLUMNS).expect("camera");
            let (from, to) = camera.range();
            let tree = frame_tree(&owned, &s, q, app::TREE_DEPTH, from, to).expect("owned tree");
            any_heading = any_heading.max(tree.len());
        }
    }
    println!(
        "firmware ray-tree frames: at most {most} intervals ({any_heading} over all headings, \
         capacity {}), branches up to {deepest} objects",
        app::FRAME_CAPACITY
    );
    assert_eq!(
        deepest,
        app::TREE_DEPTH + 1,
        "the trees reach the full depth"
    );
    assert!(
        any_heading <= app::FRAME_CAPACITY,
        "{any_heading} intervals"
    );

    // One walk fewer than the firmware's scratch is too few for some viewpoint, and says
    // so; so are one split and one hop fewer.
    use app::{TREE_HOPS as H, TREE_SPLITS as S, TREE_WALKS as W};
    assert!(
        some_tree_too_deep::<_, { W - 1 }, S, H>(&complex, &s),
        "TREE_WALKS is more than the trees need"
    );
    assert!(
        some_tree_too_deep::<_, W, { S - 1 }, H>(&complex, &s),
        "TREE_SPLITS is more than the trees need"
    );
    assert!(
        some_tree_too_deep::<_, W, S, { H - 1 }>(&complex, &s),
        "TREE_HOPS is more than the trees need"
    );
}

/// Whether the firmware's frame from some viewpoint is `TreeTooDeep` with a
/// `TreeScratch<W, S, H>`.
fn some_tree_too_deep<
    T: vcx::partition::Storage,
    const W: usize,
    const S: usize,
    const H: usize,
>(
    complex: &vcx::partition::Complex<T>,
    s: &vcx::SceneRef<'_>,
) -> bool {
    use vcx::render::Camera;
    let mut scratch = Box::new(vcx::walk::TreeScratch::<W, S, H>::new());
    viewpoints::VIEWPOINTS
        .iter()
        .enumerate()
        .any(|(k, &(x, y))| {
            let q = QueryPoint::from_raw(x, y).expect("in range");
            let camera = Camera::new(q, app::heading(k), app::FOV, app::COLUMNS).expect("camera");
            let (from, to) = camera.range();
            let r = vcx::walk::frame_tree_into(
                complex,
                s,
                q,
                app::TREE_DEPTH,
                from,
                to,
                &mut scratch,
                |_| {},
            );
            r == Err(WalkError::TreeTooDeep)
        })
}

/// A damaged embedded file is an `app::Error::Format` on the firmware path, not a panic.
#[test]
fn firmware_rejects_a_damaged_file() {
    let _g = lock();
    let mut arenas = Box::new(app::Arenas::new());
    let mut bytes = app::VCX.to_vec();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    assert!(matches!(
        app::decode(&bytes, &mut arenas),
        Err(app::Error::Format(FormatError::Checksum { .. }))
    ));
    assert!(matches!(
        app::decode(&bytes[..bytes.len() / 2], &mut arenas),
        Err(app::Error::Format(_))
    ));
}

/// The counter sees allocations (a positive control: otherwise the zero counts above would
/// prove nothing), and the sizes `ARCHITECTURE.md` quotes (`--nocapture`).
#[test]
fn the_counter_sees_allocations() {
    use core::mem::size_of;
    let _g = lock();
    let mut arenas = Box::new(app::Arenas::new());
    let file = app::decode(app::VCX, &mut arenas).expect("embedded file decodes");
    let s = file.scene.as_ref();
    let owned = build_by_sweep(&s).expect("build");
    let &(x, y) = viewpoints::VIEWPOINTS.first().expect("a viewpoint");
    let q = QueryPoint::from_raw(x, y).expect("in range");
    let (n, v) = allocations(|| view(&owned, &s, q));
    assert!(n > 0 && v.is_ok(), "the owned view allocates its Vec: {n}");
    println!(
        "host sizes: ViewInterval {} B, Angle {} B, Cylinder {} B, Vertex {} B; firmware file: \
         {} bytes, {} objects, {} complex vertices, {} cylinders; decoded arenas {} B, derived \
         state without angles {} B",
        size_of::<ViewInterval>(),
        size_of::<Angle>(),
        size_of::<Cylinder>(),
        size_of::<vcx::partition::Vertex>(),
        app::VCX.len(),
        app::OBJECTS,
        app::COMPLEX_VERTICES,
        app::CYLINDERS,
        size_of::<app::Arenas>(),
        size_of::<app::Ram>(),
    );
}

/// The per-column work of a frame (`render::centre_intervals`, `render::centre_hits`,
/// `render::coverage` into a caller's column buffer) allocates nothing, and the sweep of
/// `centre_hits` finds the intervals `centre_intervals` does.
#[test]
fn frame_columns_allocate_nothing() {
    use vcx::render::{centre_hits, centre_intervals, coverage, Camera};
    let _g = lock();
    let path = repo_path("std-demo/scenes/hall.json");
    let scene = vcx_demo::scene_file::load(&path).expect("hall").scene;
    let s = scene.as_ref();
    let complex = build_by_sweep(&s).expect("build");
    let mut checked = 0;
    for q in viewpoints(&s, 6) {
        let tree = vcx::walk::ray_tree(&complex, &s, q, 4).expect("ray tree");
        let camera = Camera::new(q, 0.3 + checked as f64, 1.4, 400).expect("camera");
        let (mut centre, mut seen) = (vec![0usize; 400], vec![usize::MAX; 400]);
        let (n, sum) = allocations(|| {
            let mut sum = 0.0;
            centre_intervals(&camera, &tree, &mut centre);
            centre_hits(&s, &camera, &tree, |c, k, hit| {
                if let Some(slot) = seen.get_mut(c) {
                    *slot = k;
                }
                sum += hit.map_or(0.0, |h| h.length);
            });
            coverage(&camera, &tree, |p| sum += p.fraction);
            sum
        });
        assert_eq!(n, 0, "q {q:?}: the frame allocated");
        assert!(sum >= 400.0 - 1e-6, "q {q:?}: coverage sums to {sum}");
        assert_eq!(centre, seen, "q {q:?}");
        checked += 1;
    }
    assert!(checked >= 3, "{checked}");
}

/// Ray trees walked in lock step ([`vcx::walk::frame_tree_into`]) over slice storage
/// allocate nothing — the sweep, the copy into a caller's buffer of `FrameInterval`s and
/// the frame's coverage — and give the intervals of `frame_tree` on the owned complex
/// (which `tests/tests/ray_trees.rs` checks against the reference), for fields of view and
/// the full circle, through mirrors, refractive objects and screens.
#[test]
fn lock_step_ray_trees_allocate_nothing() {
    use vcx::geom::predicates::Direction;
    use vcx::render::{angle_order, coverage, Camera, FrameInterval};
    use vcx::walk::{frame_tree, frame_tree_into, TreeScratch};
    let _g = lock();
    let mut scratch = Box::new(TreeScratch::<32>::new());
    let mut buf: Box<heapless::Vec<FrameInterval, 1024>> = Box::default();
    let mut checked = 0;
    for (kind, n, seed) in [(SceneKind::Hall, 8, 2), (SceneKind::Mixed, 10, 3)] {
        let scene = generate(kind, n, seed).expect("generator").scene;
        let s = scene.as_ref();
        let owned = build_by_sweep(&s).expect("build");
        let sizes = BorderSizes::exact(s.len(), owned.vertices().len(), owned.cylinders());
        let (vertices, cylinders) = (owned.vertices().to_vec(), owned.cylinders().to_vec());
        let mut border = common::BorderVecs::new(sizes);
        let complex =
            Complex::from_slices(&s, &vertices, &cylinders, border.buffers()).expect("fits");
        for (k, q) in viewpoints(&s, 10).into_iter().enumerate() {
            let camera = Camera::new(q, 0.7 * k as f64, 1.3, 320).expect("camera");
            let (from, to) = camera.range();
            let full = Direction { x: 3, y: -1 };
            for (depth, (from, to)) in [(5, (from, to)), (3, (full, full))] {
                let Ok(mut want) = frame_tree(&owned, &s, q, depth, from, to) else {
                    continue;
                };
                angle_order(&mut want);
                let (allocated, got) = allocations(|| {
                    buf.clear();
                    let mut fits = true;
                    let r = frame_tree_into(&complex, &s, q, depth, from, to, &mut scratch, |i| {
                        fits &= FrameInterval::new(&i).is_some_and(|f| buf.push(f).is_ok());
                    });
                    angle_order(&mut buf[..]);
                    let mut sum = 0.0;
                    coverage(&camera, &buf[..], |p| sum += p.fraction);
                    (r, fits, sum)
                });
                assert_eq!(
                    allocated, 0,
                    "{kind:?} q {q:?}: the lock-step tree allocated"
                );
                let (r, fits, sum) = got;
                assert!(r.is_ok() && fits, "{kind:?} q {q:?}: {r:?}");
                assert!(sum >= 320.0 - 1e-6, "{kind:?} q {q:?}: coverage {sum}");
                assert_eq!(buf.len(), want.len(), "{kind:?} q {q:?}");
                for (g, w) in buf.iter().zip(&want) {
                    assert_eq!(g.branch.as_slice(), w.branch.as_slice(), "{kind:?} q {q:?}");
                    assert_eq!(g.start.to_bits(), w.start.to_bits(), "{kind:?} q {q:?}");
                }
                checked += 1;
            }
        }
    }
    assert!(checked >= 20, "{checked}");
}

/// A scratch too small for the tree, in walks, splits or hops, is an error, never a panic or
/// a cut tree; a tree through mirrors only needs a walk per level and one more, a split and
/// a hop per level; and the scratch's size is within the documented
/// `224·W + 80·S + 128·H + 368` (`216·W + 72·S + 120·H + 280` on x86-64).
#[test]
fn tree_scratch_is_bounded() {
    let _g = lock();
    use vcx::geom::predicates::Direction;
    use vcx::walk::{frame_tree_into, TreeScratch};
    let scene = generate(SceneKind::Hall, 8, 2).expect("generator").scene;
    let s = scene.as_ref();
    assert!(s
        .objects()
        .iter()
        .all(|o| matches!(o.material, vcx::Material::Mirror | vcx::Material::Opaque)));
    let complex = build_by_sweep(&s).expect("build");
    let q = viewpoints(&s, 1)[0];
    let d = Direction { x: 1, y: 0 };
    let mut small = TreeScratch::<3>::new();
    let r = frame_tree_into(&complex, &s, q, 5, d, d, &mut small, |_| {});
    assert_eq!(r, Err(WalkError::TreeTooDeep));
    let mut enough = Box::new(TreeScratch::<16>::new());
    let r = frame_tree_into(&complex, &s, q, 5, d, d, &mut enough, |_| {});
    assert_eq!(r, Ok(()));
    let mut mirrors = Box::new(TreeScratch::<6, 5>::new());
    let r = frame_tree_into(&complex, &s, q, 5, d, d, &mut mirrors, |_| {});
    assert_eq!(r, Ok(()));
    let mut fewer_walks = Box::new(TreeScratch::<5, 16, 16>::new());
    let r = frame_tree_into(&complex, &s, q, 5, d, d, &mut fewer_walks, |_| {});
    assert_eq!(r, Err(WalkError::TreeTooDeep));
    let mut fewer_splits = Box::new(TreeScratch::<16, 4, 16>::new());
    let r = frame_tree_into(&complex, &s, q, 5, d, d, &mut fewer_splits, |_| {});
    assert_eq!(r, Err(WalkError::TreeTooDeep));
    let mut fewer_hops = Box::new(TreeScratch::<16, 16, 4>::new());
    let r = frame_tree_into(&complex, &s, q, 5, d, d, &mut fewer_hops, |_| {});
    assert_eq!(r, Err(WalkError::TreeTooDeep));
    for (w, sp, h, size) in [
        (1, 1, 1, size_of::<TreeScratch<1>>()),
        (5, 4, 4, size_of::<TreeScratch<5, 4>>()),
        (6, 5, 5, size_of::<TreeScratch<6, 5>>()),
        (9, 10, 10, size_of::<TreeScratch<9, 10>>()),
        (16, 16, 16, size_of::<TreeScratch<16>>()),
        (32, 32, 32, size_of::<TreeScratch<32>>()),
    ] {
        println!("TreeScratch<{w}, {sp}, {h}>: {size} bytes");
        assert!(
            size <= 224 * w + 80 * sp + 128 * h + 368,
            "TreeScratch<{w}, {sp}, {h}> is {size} bytes"
        );
    }
}

/// A region file (format version 4) decodes into caller storage of exactly the kept
/// counts, without allocating: the streaming replay keeps only the kept cylinders and
/// vertices, with the open cylinders in `Scratch::open`.
#[test]
fn region_file_decodes_into_kept_storage_without_allocating() {
    use vcx::format::{decode, decode_into, Header, SceneObject, Scratch};
    use vcx::format::{BLANK_CYLINDER, BLANK_VERTEX};
    use vcx::partition::{Region, ZERO_SLOTS};
    let _g = lock();
    let f = generate(SceneKind::Grid, 32, 3).expect("grid");
    let s = f.scene.as_ref();
    let whole = build_by_sweep(&s).expect("build");
    let at = |x: i32, y: i32| vcx::Point::from_raw(x << 16, y << 16).expect("point");
    let region = Region::new(at(15, 15), at(25, 25)).expect("box");
    let bytes =
        vcx::format::encode_region(&s, &whole, region, &EncodeOptions::default()).expect("encode");
    let h = Header::read(&bytes).expect("header");
    assert!((h.cylinders as usize) < whole.cylinders().len());
    let (n, nv) = (h.objects as usize, h.scene_vertices as usize);
    let mut objects = vec![SceneObject::BLANK; n];
    let mut points = vec![vcx::Point::default(); nv];
    let mut open = vec![ZERO_SLOTS; Scratch::open_len(n)];
    let mut vertices = vec![BLANK_VERTEX; h.complex_vertices as usize];
    let mut cylinders = vec![BLANK_CYLINDER; h.cylinders as usize];
    let (k, counts) = allocations(|| {
        decode_into::<512, 64>(
            &bytes,
            Scratch {
                objects: &mut objects,
                points: &mut points,
                open: &mut open,
            },
            &mut vertices,
            &mut cylinders,
        )
        .map(|d| (d.vertices.len(), d.cylinders.len(), d.region))
    });
    assert_eq!(k, 0, "decode_into of a version-4 file allocated");
    let loaded = decode(&bytes).expect("decode");
    assert_eq!(
        counts,
        Ok((
            loaded.complex.vertices().len(),
            loaded.complex.cylinders().len(),
            Some(region)
        ))
    );
    assert_eq!(vertices, loaded.complex.vertices());
    assert_eq!(cylinders, loaded.complex.cylinders());
    println!(
        "open slots: {} entries of {} bytes",
        Scratch::open_len(n),
        size_of::<vcx::partition::Slots>()
    );
}
