//! Walking a complex in caller-provided storage allocates nothing, and the firmware's code
//! path gives the right views.
//!
//! * A counting global allocator (`stats_alloc`, wrapping `System`) counts every heap
//!   allocation; the complex is built first, then the counter is read around the walk only.
//!   Other tests of this binary run on other threads and the allocator is global, so each
//!   measurement is repeated and the smallest count must be zero: an allocation on the walk
//!   path happens on every repetition and still fails the test.
//! * The firmware (`firmware/`) embeds `firmware/src/scene_data.rs`, generated here from
//!   `std-demo/scenes/hall.json`; `scene_data_is_fresh` fails when it differs from what a
//!   fresh build produces. Regenerate with
//!   `cargo test -p vcx-tests --test no_alloc -- --ignored regenerate_scene_data`.
//! * `firmware/src/app.rs` is included here verbatim and run on the same data: its views
//!   are compared with `walk::view` on the owned complex and with the exact reference.

use core::fmt::Write as _;
use std::alloc::System;
use std::sync::Mutex;

use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use vcx::geom::sos::Angle;
use vcx::line_space::Bound;
use vcx::partition::{
    build_by_sweep, BorderBuffers, BorderSizes, Complex, Cylinder, CylinderId, Wall,
};
use vcx::walk::{view, view_capacity, view_into, ViewInterval, WalkError};
use vcx::{Material, QueryPoint, Scene, SceneRef, SubScene};
use vcx_demo::generate::{generate, SceneKind};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

#[allow(dead_code)]
#[rustfmt::skip]
#[path = "../../firmware/src/scene_data.rs"]
mod scene_data;

#[allow(dead_code)]
#[path = "../../firmware/src/app.rs"]
mod app;

/// Serializes the tests of this file, so that the measured regions see less noise.
static LOCK: Mutex<()> = Mutex::new(());

fn lock() -> std::sync::MutexGuard<'static, ()> {
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

/// Heap allocations (including reallocations) made while `f` runs: the smallest count of
/// three runs (see the module comment).
fn allocations<R>(mut f: impl FnMut() -> R) -> (usize, R) {
    let mut least = usize::MAX;
    let mut result = None;
    for _ in 0..3 {
        let region = Region::new(GLOBAL);
        let r = f();
        let stats = region.change();
        least = least.min(stats.allocations + stats.reallocations);
        result = Some(r);
    }
    (least, result.expect("ran three times"))
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
        let mut angles = vec![Angle::ZERO; sizes.angles];
        let mut ids = vec![CylinderId::ZERO; sizes.ids];
        let mut offsets = vec![0u32; sizes.offsets];
        let mut start = vec![[[0u32; 2]; 2]; sizes.start];
        let mut out = vec![dummy(); view_capacity(s.len())];
        let points = viewpoints(&s, 12);
        let mut wants = Vec::new();
        for &q in &points {
            wants.push(view(&owned, &s, q).expect("owned view"));
        }

        // Rebuilding the derived state allocates nothing either.
        let (n, complex) = allocations(|| {
            let buffers = BorderBuffers {
                angles: &mut angles,
                ids: &mut ids,
                offsets: &mut offsets,
                start: &mut start,
            };
            Complex::from_slices(&s, &vertices, &cylinders, buffers).map(|c| c.vertices().len())
        });
        assert_eq!(n, 0, "{name}: rebuild_into allocated");
        assert_eq!(complex, Ok(vertices.len()));
        let buffers = BorderBuffers {
            angles: &mut angles,
            ids: &mut ids,
            offsets: &mut offsets,
            start: &mut start,
        };
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
        let buffers = BorderBuffers {
            angles: &mut [],
            ids: &mut ids,
            offsets: &mut offsets,
            start: &mut start,
        };
        let lean = Complex::from_slices(&s, &vertices, &cylinders, buffers).expect("fits");
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
    let mut angles = vec![Angle::ZERO; sizes.angles];
    let mut ids = vec![CylinderId::ZERO; sizes.ids - 1];
    let mut offsets = vec![0u32; sizes.offsets];
    let mut start = vec![[[0u32; 2]; 2]; sizes.start];
    let buffers = BorderBuffers {
        angles: &mut angles,
        ids: &mut ids,
        offsets: &mut offsets,
        start: &mut start,
    };
    let err = Complex::from_slices(&s, c.vertices(), c.cylinders(), buffers).unwrap_err();
    assert_eq!((err.buffer, err.needed), ("ids", sizes.ids));
    let bound = BorderSizes::for_counts(s.len(), c.vertices().len(), c.cylinders().len());
    assert!(bound.ids >= sizes.ids && bound.offsets == sizes.offsets);
}

// ---------------------------------------------------------------------------------------
// The firmware's data and code path.

const SOURCE_SCENE: &str = "std-demo/scenes/hall.json";
const FIRMWARE_VIEWPOINTS: usize = 6;

fn repo_path(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
}

/// The source of `firmware/src/scene_data.rs` for the scene file.
fn generate_scene_data() -> String {
    let file = vcx_demo::scene_file::load(repo_path(SOURCE_SCENE)).expect("scene file");
    let s = file.scene.as_ref();
    let c = build_by_sweep(&s).expect("build");
    let points = viewpoints(&s, FIRMWARE_VIEWPOINTS);
    let none = |x: Option<u32>| x.map_or("N".to_string(), |v| v.to_string());
    let chain = |ch: Option<vcx::line_space::Chain>| {
        none(ch.map(|ch| 2 * ch.object.0 + u32::from(ch.bound == Bound::Upper)))
    };
    let wall = |w: Wall| match w {
        Wall::Zero => "N".to_string(),
        Wall::Vertex(v) => v.index().to_string(),
    };
    let bound = |b: Bound| u32::from(b == Bound::Upper);
    let mut o = String::new();
    let w = &mut o;
    let _ = writeln!(
        w,
        "//! Generated from `{SOURCE_SCENE}` by\n//! `cargo test -p vcx-tests --test no_alloc -- \
         --ignored regenerate_scene_data`;\n//! do not edit (`scene_data_is_fresh` checks it). \
         The scene's polygons (stored,\n//! counter-clockwise), the vertices and cylinders of \
         its complex (`build_by_sweep`) and\n//! viewpoints. Not formatted \
         (`#[rustfmt::skip]` where it is declared).\n\n\
         use vcx::line_space::{{Bitangent, Bound, Chain}};\n\
         use vcx::partition::{{Cylinder, CylinderId, Vertex, VertexId, Wall}};\n\
         use vcx::{{Material, ObjectId, Point}};\n"
    );
    let _ = writeln!(
        w,
        "/// Objects of the scene.\npub const OBJECTS: usize = {};",
        s.len()
    );
    let _ = writeln!(
        w,
        "/// Vertices of the scene.\npub const SCENE_VERTICES: usize = {};",
        s.vertices().len()
    );
    let _ = writeln!(
        w,
        "/// Vertices of the complex.\npub const COMPLEX_VERTICES: usize = {};",
        c.vertices().len()
    );
    let _ = writeln!(
        w,
        "/// Cylinders of the complex.\npub const CYLINDERS: usize = {};\n",
        c.cylinders().len()
    );
    w.push_str(
        r#"const N: u32 = u32::MAX;

const fn p(x: i32, y: i32) -> Point {
    match Point::from_raw(x, y) {
        Some(p) => p,
        None => panic!("coordinate out of range"),
    }
}

const fn bound(b: u32) -> Bound {
    if b == 0 {
        Bound::Lower
    } else {
        Bound::Upper
    }
}

const fn v(a: u32, i: usize, ab: u32, b: u32, j: usize, bb: u32) -> Vertex {
    Vertex {
        bitangent: Bitangent {
            first_object: ObjectId(a),
            first: i,
            first_bound: bound(ab),
            second_object: ObjectId(b),
            second: j,
            second_bound: bound(bb),
        },
    }
}

const fn object(x: u32) -> Option<ObjectId> {
    if x == N {
        None
    } else {
        Some(ObjectId(x))
    }
}

const fn chain(x: u32) -> Option<Chain> {
    if x == N {
        None
    } else {
        Some(Chain {
            object: ObjectId(x / 2),
            bound: bound(x % 2),
        })
    }
}

const fn wall(x: u32) -> Wall {
    if x == N {
        Wall::Zero
    } else {
        Wall::Vertex(VertexId::from_raw(x))
    }
}

const fn cylinder(x: u32) -> Option<CylinderId> {
    if x == N {
        None
    } else {
        Some(CylinderId::from_raw(x))
    }
}

/// A cylinder: floor, ceiling, bottom and top chain (2·object + upper), left and right
/// wall (vertex), left and right neighbour; `N` for none (θ = 0 for a wall).
#[allow(clippy::too_many_arguments)]
const fn c(f: u32, g: u32, b: u32, t: u32, l: u32, r: u32, ln: u32, rn: u32) -> Cylinder {
    Cylinder {
        floor: object(f),
        ceiling: object(g),
        bottom: chain(b),
        top: chain(t),
        left: wall(l),
        right: wall(r),
        left_neighbour: cylinder(ln),
        right_neighbour: cylinder(rn),
    }
}

"#,
    );
    for (k, obj) in s.objects().iter().enumerate() {
        let pts: Vec<String> = s
            .polygon(obj)
            .iter()
            .map(|p| format!("p({}, {})", p.x(), p.y()))
            .collect();
        let _ = writeln!(
            w,
            "static O{k}: [Point; {}] = [{}];",
            pts.len(),
            pts.join(", ")
        );
    }
    let _ = writeln!(
        w,
        "\n/// The polygons, counter-clockwise.\npub static POLYGONS: [(Material, &[Point]); OBJECTS] = ["
    );
    for (k, obj) in s.objects().iter().enumerate() {
        let m = match obj.material {
            Material::Opaque => "Opaque",
            Material::Mirror => "Mirror",
            Material::Screen => "Screen",
            Material::Refractive { .. } => panic!("the firmware scene has no refractive object"),
        };
        let _ = writeln!(w, "    (Material::{m}, &O{k}),");
    }
    let _ = writeln!(
        w,
        "];\n\n/// The vertices of the complex (first object, vertex, bound; second …).\n\
         pub static VERTICES: [Vertex; COMPLEX_VERTICES] = ["
    );
    for v in c.vertices() {
        let b = v.bitangent;
        let _ = writeln!(
            w,
            "    v({}, {}, {}, {}, {}, {}),",
            b.first_object.0,
            b.first,
            bound(b.first_bound),
            b.second_object.0,
            b.second,
            bound(b.second_bound)
        );
    }
    let _ = writeln!(
        w,
        "];\n\n/// The cylinders of the complex.\npub static CYLINDER_DATA: [Cylinder; CYLINDERS] = ["
    );
    for cy in c.cylinders() {
        let _ = writeln!(
            w,
            "    c({}, {}, {}, {}, {}, {}, {}, {}),",
            none(cy.floor.map(|o| o.0)),
            none(cy.ceiling.map(|o| o.0)),
            chain(cy.bottom),
            chain(cy.top),
            wall(cy.left),
            wall(cy.right),
            none(cy.left_neighbour.map(|c| c.index() as u32)),
            none(cy.right_neighbour.map(|c| c.index() as u32)),
        );
    }
    let _ = writeln!(
        w,
        "];\n\n/// Viewpoints (raw query coordinates, 2⁻³²).\npub static VIEWPOINTS: [(i64, i64); {}] = [",
        points.len()
    );
    for q in &points {
        let _ = writeln!(w, "    ({}, {}),", q.x(), q.y());
    }
    let _ = writeln!(w, "];");
    o
}

fn scene_data_path() -> std::path::PathBuf {
    repo_path("firmware/src/scene_data.rs")
}

/// Writes `firmware/src/scene_data.rs` (run by hand after the scene or the construction
/// changes).
#[test]
#[ignore = "writes firmware/src/scene_data.rs"]
fn regenerate_scene_data() {
    std::fs::write(scene_data_path(), generate_scene_data()).expect("write");
}

/// The checked-in firmware data is what a fresh build of the scene file produces.
#[test]
fn scene_data_is_fresh() {
    let _g = lock();
    let want = generate_scene_data();
    let got = std::fs::read_to_string(scene_data_path()).expect("read");
    assert!(
        got == want,
        "firmware/src/scene_data.rs is stale: run `cargo test -p vcx-tests --test no_alloc \
         -- --ignored regenerate_scene_data`"
    );
}

/// The firmware's code path (`app::run` over the embedded statics, fixed-capacity scene,
/// buffers in one `Ram` block) allocates nothing, and its views equal `walk::view` of the
/// owned complex and the exact reference.
#[test]
fn firmware_walk_matches_owned_view_and_reference() {
    let _g = lock();
    let scene = app::scene().expect("embedded scene validates");
    let s = scene.as_ref();
    let mut ram = Box::new(app::Ram::new());
    let mut out = app::out();
    // Results are copied into preallocated storage, so the callback allocates nothing.
    let mut got: Vec<Vec<ViewInterval>> = (0..scene_data::VIEWPOINTS.len())
        .map(|_| Vec::with_capacity(app::CAPACITY))
        .collect();
    // As `firmware/src/main.rs` does: rebuild the derived state, then walk the views.
    let (n, checksum) = allocations(|| {
        for g in got.iter_mut() {
            g.clear();
        }
        let complex = app::complex(
            &s,
            &scene_data::VERTICES,
            &scene_data::CYLINDER_DATA,
            &mut ram,
        )?;
        app::views(&complex, &s, &mut out, |k, view| {
            if let Some(g) = got.get_mut(k) {
                g.extend_from_slice(view);
            }
        })
    });
    assert_eq!(n, 0, "the firmware path allocated");
    checksum.expect("firmware run");

    // The same views from the owned complex of the same scene, and from the reference.
    let owned = build_by_sweep(&s).expect("build");
    assert_eq!(owned.cylinders(), &scene_data::CYLINDER_DATA[..]);
    let all = SubScene::new(s, (0..s.len() as u32).map(vcx::ObjectId));
    let mut compared = 0;
    for (k, &(x, y)) in scene_data::VIEWPOINTS.iter().enumerate() {
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
    assert_eq!(compared, FIRMWARE_VIEWPOINTS);
}

/// The counter sees allocations (a positive control: otherwise the zero counts above would
/// prove nothing), and the sizes `ARCHITECTURE.md` quotes (`--nocapture`).
#[test]
fn the_counter_sees_allocations() {
    use core::mem::size_of;
    let _g = lock();
    let scene = app::scene().expect("embedded scene validates");
    let s = scene.as_ref();
    let owned = build_by_sweep(&s).expect("build");
    let &(x, y) = scene_data::VIEWPOINTS.first().expect("a viewpoint");
    let q = QueryPoint::from_raw(x, y).expect("in range");
    let (n, v) = allocations(|| view(&owned, &s, q));
    assert!(n > 0 && v.is_ok(), "the owned view allocates its Vec: {n}");
    println!(
        "host sizes: ViewInterval {} B, Angle {} B, Cylinder {} B, Vertex {} B; firmware scene: \
         {} objects, {} complex vertices, {} cylinders; derived state without angles {} B",
        size_of::<ViewInterval>(),
        size_of::<Angle>(),
        size_of::<Cylinder>(),
        size_of::<vcx::partition::Vertex>(),
        scene_data::OBJECTS,
        scene_data::COMPLEX_VERTICES,
        scene_data::CYLINDERS,
        size_of::<app::Ram>(),
    );
}
