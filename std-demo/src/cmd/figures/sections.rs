//! The sections of BENCHMARKS.md measured by `vcx bench views` and `vcx build -o` /
//! `vcx inspect`: views, ray trees, frames and device format sizes. Each calls the
//! commands' own measuring functions ([`bench::measure_views`], [`build::encode_vcx`],
//! [`inspect::describe`]) on generated scenes, in-process.

use core::fmt::Write as _;
use std::path::Path;

use vcx::partition::BuildOptions;
use vcx_demo::generate::{generate, SceneKind};

use super::{
    bench, build, inspect, internal, ratio_text, series, thousands, Failure, Output, Plot,
    Progress, Sizes, Table, Target, SEED,
};
use crate::input::Input;

/// The example scenes `std-demo/scenes/hall.json` and `mixed.json`: `vcx gen` of these
/// (the same as run time against error).
const EXAMPLES: [(SceneKind, u32); 2] = super::ERROR_SCENES;

/// The seed `vcx build` uses by default (`--seed 0`) for the randomized construction.
const BUILD_SEED: u64 = 0;

/// A generated scene as `vcx bench views` loads it from its JSON file.
fn json_input(kind: SceneKind, n: u32) -> Result<Input, Failure> {
    let file = generate(kind, n, SEED).map_err(|e| internal(e.to_string()))?;
    Ok(Input { file, stored: None })
}

/// `vcx build SCENE -o F.vcx` with the default randomized construction (seed 0): the
/// validated build and the bytes of the file without the history part (version 3: the
/// cylinders replayed), with every cylinder (`--explicit-cylinders`, version 1) and with
/// the history part.
struct Encoded {
    seconds: f64,
    without: Vec<u8>,
    explicit: Vec<u8>,
    with: Vec<u8>,
}

/// `vcx build SCENE` with the default randomized construction (seed 0), validated.
fn build_ric(scene: &vcx::SceneRef<'_>, path: &Path) -> Result<build::Built, Failure> {
    let options = BuildOptions {
        seed: BUILD_SEED,
        ..Default::default()
    };
    build::build_with(path, scene, build::Method::Ric, &options)
}

fn encode(input: &Input, name: &str) -> Result<Encoded, Failure> {
    let scene = input.file.scene.as_ref();
    let path = Path::new(name);
    let built = build_ric(&scene, path)?;
    Ok(Encoded {
        seconds: built.seconds,
        without: build::encode_vcx(path, &scene, &built, false, BUILD_SEED, false)?,
        explicit: build::encode_vcx(path, &scene, &built, false, BUILD_SEED, true)?,
        with: build::encode_vcx(path, &scene, &built, true, BUILD_SEED, false)?,
    })
}

/// Bytes of RAM a primary walk of a loaded file needs besides the stack: the arenas
/// `format::decode_into` fills (vertices and cylinders), the derived state
/// `Complex::from_slices` rebuilds (without vertex angles), and a view's output buffer —
/// `size_of` on this machine.
fn walk_ram(bytes: &[u8]) -> Result<usize, Failure> {
    use core::mem::{size_of, size_of_val};
    use vcx::partition::BorderSizes;
    let loaded = vcx::format::decode(bytes).map_err(|e| internal(e.to_string()))?;
    let (n, c) = (loaded.scene.as_ref().len(), loaded.complex.cylinders());
    let v = loaded.complex.vertices();
    let derived = BorderSizes {
        angles: 0,
        ..BorderSizes::exact(n, v.len(), c)
    };
    Ok(size_of_val(c)
        + size_of_val(v)
        + derived.bytes()
        + vcx::walk::view_capacity(n) * size_of::<vcx::walk::ViewInterval>())
}

fn join<T: ToString>(v: &[T]) -> String {
    v.iter().map(T::to_string).collect::<Vec<_>>().join(",")
}

/// `vcx bench views` on the grid scene against n, from the sweep's complex and from the
/// `.vcx` file without history.
pub(super) fn views(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(3 * s.views_n.len());
    let points = bench::Points::Random(s.views_random, SEED);
    let mut rows = Vec::new();
    let (mut json_us, mut vcx_us, mut events) = (vec![], vec![], vec![]);
    let mut measured = Vec::new();
    // Per n: time per view from the file with history over the file without.
    let mut history = Vec::new();
    for &n in &s.views_n {
        p.step(&format!("grid n={n} views"));
        let input = json_input(SceneKind::Grid, n)?;
        let m = bench::measure_views(&input, &points, 0, s.views_repeat, None)?;
        p.step(&format!("grid n={n} .vcx views"));
        let name = format!("grid-{n}.vcx");
        let e = encode(&input, &name)?;
        let loaded = crate::input::from_bytes(Path::new(&name), &e.without)?;
        let f = bench::measure_views(&loaded, &points, 0, s.views_repeat, None)?;
        p.step(&format!("grid n={n} .vcx with history views"));
        let loaded = crate::input::from_bytes(Path::new(&name), &e.with)?;
        let h = bench::measure_views(&loaded, &points, 0, s.views_repeat, None)?;
        let x = f64::from(n);
        json_us.push((x, m.seconds * 1e6));
        vcx_us.push((x, f.seconds * 1e6));
        events.push((x, m.events));
        rows.push(vec![
            n.to_string(),
            thousands(m.cylinders),
            m.views.to_string(),
            format!("{:.1}", m.seconds * 1e6),
            format!("{:.0}", 1.0 / m.seconds),
            format!("{:.1}", m.events),
            format!("{:.1}", m.intervals),
            format!("{:.2}", m.seconds * 1e6 / m.events.max(1.0)),
            format!("{:.1}", f.seconds * 1e6),
            format!("{:.1}", f.intervals),
            format!("{:.1}", h.seconds * 1e6),
        ]);
        history.push(h.seconds / f.seconds);
        measured.push((n, m, f));
    }
    let mut notes = String::new();
    if let (Some(a), Some(b)) = (measured.first(), measured.last()) {
        if b.0 > a.0 {
            let _ = write!(
                notes,
                "The cost follows what is seen: from n = {} to n = {} ({}× the objects) a view \
                 enters {}× the cylinders and takes {}× the time ({:.2} → {:.2} µs per event). ",
                a.0,
                b.0,
                ratio_text(f64::from(b.0) / f64::from(a.0)),
                ratio_text(b.1.events / a.1.events),
                ratio_text(b.1.seconds / a.1.seconds),
                a.1.seconds * 1e6 / a.1.events.max(1.0),
                b.1.seconds * 1e6 / b.1.events.max(1.0),
            );
        }
    }
    let same = measured
        .iter()
        .all(|(_, m, f)| m.intervals == f.intervals && m.views == f.views);
    let lo = history.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = history.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let _ = write!(
        notes,
        "The `.vcx` files hold the randomized construction's complex (seed {BUILD_SEED}), the \
         JSON scene is built by the sweep: the same canonical partition, so the same intervals \
         ({}). A primary view starts at θ = 0 without the history: with it the time per view \
         is {lo:.2}–{hi:.2}× that without (a device that only needs primary views can leave \
         the history out; \"Device format sizes\" gives its bytes).",
        if same {
            "equal in every row"
        } else {
            "**they differ in some row: a bug**"
        }
    );
    const LIMIT_US: f64 = 5.0;
    let target = Target {
        what: "full 360° view, grid n = 1024 (Views)".into(),
        target: format!("≤ {LIMIT_US} µs"),
        measured: String::new(),
        met: None,
    };
    let target = match measured.iter().find(|m| m.0 == 1024) {
        Some((_, m, _)) => {
            let us = m.seconds * 1e6;
            let _ = write!(
                notes,
                "\n\nTarget of the walking issue: a full view of the n = 1024 grid in ≤ \
                 {LIMIT_US} µs — {}.",
                if us <= LIMIT_US {
                    format!("**met** ({us:.1} µs)")
                } else {
                    format!(
                        "**missed by {}×** ({us:.1} µs; the walk costs {:.2} µs per event)",
                        ratio_text(us / LIMIT_US),
                        us / m.events.max(1.0)
                    )
                }
            );
            Target {
                measured: format!("{us:.1} µs"),
                met: Some(us <= LIMIT_US),
                ..target
            }
        }
        None => Target {
            measured: "n = 1024 not in this run's sizes".into(),
            ..target
        },
    };
    Ok(Output {
        caption: format!(
            "Scene `vcx gen grid N --seed {SEED}`; {} random free viewpoints in its bounding \
             box (seed {SEED}); each viewpoint's time is the best of {} runs, the table gives \
             the median over the viewpoints. Events: cylinders entered by the walk. Alone: `vcx \
             gen grid N --seed {SEED} -o g.json; vcx bench views g.json --random {} --repeat {}` \
             (complex by the sweep), `vcx build g.json --history never -o g.vcx; vcx bench \
             views g.vcx --random {} --repeat {}` (the `.vcx` columns) and the same with \
             `--history always`, for N = {}.",
            s.views_random,
            s.views_repeat,
            s.views_random,
            s.views_repeat,
            s.views_random,
            s.views_repeat,
            join(&s.views_n),
        ),
        table: Table {
            header: vec![
                "n",
                "cylinders",
                "views",
                "µs per view",
                "views per second",
                "events per view",
                "intervals per view",
                "µs per event",
                "µs per view, `.vcx` without history",
                "intervals per view, `.vcx`",
                "µs per view, `.vcx` with history",
            ],
            rows,
        },
        notes,
        plots: vec![Plot {
            file: "views_grid.svg".into(),
            title: "Full 360° view from random free points (grid scene)".into(),
            x_label: "objects n",
            y_label: "µs per view / events per view",
            log_x: true,
            log_y: true,
            series: vec![
                series("µs per view (sweep's complex)", json_us),
                series("µs per view (.vcx without history)", vcx_us),
                series("events per view", events),
            ],
        }],
        targets: vec![target],
    })
}

/// `vcx bench views SCENE --depth D` on the hall of mirrors and the mixed scene.
pub(super) fn ray_trees(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(EXAMPLES.len() * (s.tree_depth + 1));
    let points = bench::Points::Random(s.tree_random, SEED);
    let mut rows = Vec::new();
    let (mut time, mut intervals) = (Vec::new(), Vec::new());
    let mut notes = Vec::new();
    for (kind, n) in EXAMPLES {
        let name = kind.name();
        let input = json_input(kind, n)?;
        let (mut t, mut k) = (Vec::new(), Vec::new());
        for depth in 0..=s.tree_depth {
            p.step(&format!("{name} depth={depth}"));
            let m = bench::measure_views(&input, &points, depth, s.tree_repeat, None)?;
            t.push((depth as f64, m.seconds * 1e6));
            k.push((depth as f64, m.intervals));
            rows.push(vec![
                format!("{name}.json"),
                depth.to_string(),
                thousands(m.cylinders),
                m.views.to_string(),
                format!("{:.1}", m.seconds * 1e6),
                format!("{:.0}", 1.0 / m.seconds),
                format!("{:.1}", m.intervals),
            ]);
        }
        if let (Some(a), Some(b)) = (t.first(), t.last()) {
            if let (Some(ka), Some(kb)) = (k.first(), k.last()) {
                notes.push(format!(
                    "{name}: from depth 0 to {} the time per tree grows {}× ({:.1} → {:.1} µs) \
                     for {}× the intervals",
                    s.tree_depth,
                    ratio_text(b.1 / a.1),
                    a.1,
                    b.1,
                    ratio_text(kb.1 / ka.1.max(1e-9)),
                ));
            }
        }
        time.push(series(&format!("{name}.json"), t));
        intervals.push(series(&format!("{name}.json"), k));
    }
    Ok(Output {
        caption: format!(
            "Scenes `std-demo/scenes/hall.json` and `mixed.json` (= `vcx gen hall 12 --seed \
             {SEED}` and `vcx gen mixed 30 --seed {SEED}`); complex by the sweep, over every \
             object at depth > 0 (screens included), without the screens at depth 0. A tree is \
             the full-circle ray tree (`vcx::walk::ray_tree`) from each of {r} random free \
             viewpoints (seed {SEED}), best of {p} runs, median over the viewpoints. Alone: \
             `vcx bench views std-demo/scenes/hall.json --depth D --random {r} --repeat {p}`, \
             the same for `mixed.json`, D = 0 … {d}.",
            r = s.tree_random,
            p = s.tree_repeat,
            d = s.tree_depth,
        ),
        table: Table {
            header: vec![
                "<scene",
                "depth",
                "cylinders",
                "views",
                "µs per full view",
                "views per second",
                "intervals per view",
            ],
            rows,
        },
        notes: format!("{}.", notes.join("; ")),
        plots: vec![
            Plot {
                file: "ray_trees_time.svg".into(),
                title: "Full-circle ray tree: time against depth".into(),
                x_label: "ray-tree depth",
                y_label: "µs per tree",
                log_x: false,
                log_y: true,
                series: time,
            },
            Plot {
                file: "ray_trees_intervals.svg".into(),
                title: "Full-circle ray tree: intervals against depth".into(),
                x_label: "ray-tree depth",
                y_label: "intervals per tree",
                log_x: false,
                log_y: false,
                series: intervals,
            },
        ],
        targets: Vec::new(),
    })
}

/// Columns and field of view of a frame (`vcx bench views --fov 90 --width 800`).
const FRAME: bench::FrameSpec = bench::FrameSpec {
    heading: 0.0,
    fov: 90.0,
    width: 800,
};

/// `vcx bench views SCENE --depth D` with and without `--fov 90 --width 800`.
pub(super) fn frames(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    let cases = [
        (SceneKind::Hall, 12, 5usize),
        (SceneKind::Mixed, 30, 5),
        (SceneKind::Grid, s.frames_grid_n, 0),
    ];
    p.start(2 * cases.len());
    let points = bench::Points::Random(s.tree_random, SEED);
    let mut rows = Vec::new();
    let mut extra = Vec::new();
    let mut target = None;
    for (kind, n, depth) in cases {
        let name = kind.name();
        let input = json_input(kind, n)?;
        p.step(&format!("{name} sweep"));
        let sweep = bench::measure_views(&input, &points, depth, s.tree_repeat, None)?;
        p.step(&format!("{name} frame"));
        let frame = bench::measure_views(&input, &points, depth, s.tree_repeat, Some(FRAME))?;
        let label = match kind {
            SceneKind::Grid => format!("grid n = {n} (`vcx gen grid {n} --seed {SEED}`)"),
            _ => format!("{name}.json"),
        };
        rows.push(vec![
            label,
            depth.to_string(),
            format!("{:.1}", sweep.seconds * 1e6),
            format!("{:.1}", frame.seconds * 1e6),
            format!("{:.0}", 1.0 / frame.seconds),
            format!("{:.1}", frame.intervals),
        ]);
        extra.push((
            depth,
            frame.seconds / sweep.seconds,
            (frame.seconds - sweep.seconds) * 1e6,
        ));
        if kind == SceneKind::Hall {
            target = Some(1.0 / frame.seconds);
        }
    }
    const FPS: f64 = 10_000.0;
    let trees: Vec<String> = extra
        .iter()
        .filter(|e| e.0 > 0)
        .map(|e| format!("{:.2}×", e.1))
        .collect();
    let views: Vec<String> = extra
        .iter()
        .filter(|e| e.0 == 0)
        .map(|e| format!("{:.0} µs", e.2))
        .collect();
    let mut notes = format!(
        "A ray-tree frame walks the tree over the field of view only, in lock step and \
         without allocating, as a device does (`walk::frame_tree_into` into a reused scratch \
         and buffer: `walk::ray_tree_range` without the boundary vertices, which a frame does \
         not draw; the primary walk starts at the field of view, found from the objects on its \
         first line without the history): frame / full-circle tree = {} for the \
         depth-5 scenes, per-column work included. A view frame walks the full view and adds \
         the frame's own work ({} columns: one branch followed per column in `f64`, and the \
         exact coverage): {}.",
        trees.join(", "),
        FRAME.width,
        views.join(", "),
    );
    let fps = target.unwrap_or(f64::NAN);
    let _ = write!(
        notes,
        " Target of the walking issue: ≥ {} depth-5 hall-of-mirrors frames per second — {}.",
        thousands(FPS as usize),
        if fps >= FPS {
            format!("**met** ({fps:.0})")
        } else {
            format!("**not met** ({fps:.0}, {}× short)", ratio_text(FPS / fps))
        }
    );
    Ok(Output {
        caption: format!(
            "Per scene the full 360° sweep (view or ray tree) and a frame: the sweep (a ray tree \
             over the field of view only), then per-column hits (`render::centre_hits`: each column's \
             centre interval and the distance along its branch) and the exact coverage of every column (`render::coverage`), \
             {w} columns, {f}° field of view, heading 0; {r} random free viewpoints (seed \
             {SEED}), best of {p} runs each, median; the two columns measured back to back. \
             Alone: `vcx bench views SCENE [--depth D] --random {r} --repeat {p}` and the same \
             with `--fov {f} --width {w}`.",
            w = FRAME.width,
            f = FRAME.fov,
            r = s.tree_random,
            p = s.tree_repeat,
        ),
        table: Table {
            header: vec![
                "<scene",
                "depth",
                "µs per full sweep",
                "µs per frame",
                "frames per second",
                "intervals",
            ],
            rows,
        },
        notes,
        plots: Vec::new(),
        targets: vec![Target {
            what: "depth-5 hall-of-mirrors frames, 800 columns (Frames)".into(),
            target: format!("≥ {} per second", thousands(FPS as usize)),
            measured: format!("{fps:.0} per second"),
            met: Some(fps >= FPS),
        }],
    })
}

/// The bytes of `vcx build SCENE --history never|always -o F.vcx` and what `vcx inspect
/// --json` says of them.
pub(super) fn sizes(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    p.start(s.sizes_n.len() + EXAMPLES.len());
    let mut scenes: Vec<(String, SceneKind, u32)> = s
        .sizes_n
        .iter()
        .map(|&n| (n.to_string(), SceneKind::Grid, n))
        .collect();
    scenes.extend(
        EXAMPLES
            .iter()
            .map(|&(k, n)| (format!("{}.json", k.name()), k, n)),
    );
    let mut rows = Vec::new();
    let (mut without, mut with) = (Vec::new(), Vec::new());
    let mut at_256 = None;
    let mut shares = Vec::new();
    for (label, kind, n) in scenes {
        p.step(&format!("{label} encode"));
        let input = json_input(kind, n)?;
        let name = format!("{}-{n}.vcx", kind.name());
        let e = encode(&input, &name)?;
        let d0 = inspect::describe(&e.without).map_err(internal)?;
        let d1 = inspect::describe(&e.with).map_err(internal)?;
        let (h0, h1) = (&d0.header, &d1.header);
        let cylinders = h0.cylinders as usize;
        let per = |b: usize| b as f64 / cylinders.max(1) as f64;
        let nodes = h1.history_nodes as usize;
        let hist = h1.history_bytes as usize;
        rows.push(vec![
            label.clone(),
            thousands(cylinders),
            thousands(e.without.len()),
            format!("{:.2}", per(e.without.len())),
            thousands(e.explicit.len()),
            format!("{:.2}", per(e.explicit.len())),
            thousands(walk_ram(&e.without)?),
            thousands(hist),
            thousands(nodes),
            thousands(h1.history_links as usize),
            d1.depth.map_or("—".into(), |d| d.to_string()),
            format!("{:.2}", hist as f64 / nodes.max(1) as f64),
            thousands(e.with.len()),
            format!("{:.2}", per(e.with.len())),
            format!("{:.3}", e.seconds),
        ]);
        if kind == SceneKind::Grid {
            let x = f64::from(n);
            without.push((x, e.without.len() as f64));
            with.push((x, e.with.len() as f64));
            shares.push(format!(
                "{:.0} % (n = {n})",
                100.0 * hist as f64 / e.with.len().max(1) as f64
            ));
            if n == 256 {
                at_256 = Some((e.without.len(), cylinders));
            }
        }
    }
    const LIMIT: usize = 256 * 1024;
    let what = "grid n = 256, file without history (Device format sizes)".to_string();
    let target = "≤ 256 KiB (262,144 bytes)".to_string();
    let mut notes = format!(
        "Without history a file stores the vertices (two scene-vertex ids each) and only the \
         3n + 1 cylinders at θ = 0 (format version 3): the reader replays the other cylinders \
         from the vertices, three per vertex, by the rotational sweep's event loop without \
         its geometry (`partition::replay`). `--explicit-cylinders` stores every cylinder \
         (version 1, 8 ids each), as does every file with a history (the history names \
         cylinders as its construction numbered them). Bytes per stored cylinder grow with \
         n because ids grow: a varint takes one more byte past 2⁷, 2¹⁴ and 2²¹ cylinders or \
         vertices. The history part is {} of the file with history (each node stored as 8 \
         ids plus a child count). Walk RAM: the bytes a primary walk of the loaded file \
         needs besides its stack (about 4 KiB on Cortex-M, ARCHITECTURE.md) — the decoded vertices and \
         cylinders, the derived state without vertex angles, and a view's output buffer \
         (`size_of` on this machine; the formula is in ARCHITECTURE.md, \"Storage and walk \
         RAM\"): the file is small, but a device decodes every cylinder into RAM, {} bytes \
         each.",
        shares.join(", "),
        core::mem::size_of::<vcx::partition::Cylinder>()
    );
    let t = match at_256 {
        Some((b, cylinders)) => {
            let _ = write!(
                notes,
                " Target of the device-format issue: the n = 256 grid scene without history in \
                 ≤ 256 KiB of flash — {}: {} bytes ({:.2} MiB), {}× the target (it would take \
                 {:.1} bytes per cylinder at this n).",
                if b <= LIMIT { "**met**" } else { "**not met**" },
                thousands(b),
                b as f64 / 1024.0 / 1024.0,
                ratio_text(b as f64 / LIMIT as f64),
                LIMIT as f64 / cylinders.max(1) as f64,
            );
            Target {
                what,
                target,
                measured: format!("{} bytes", thousands(b)),
                met: Some(b <= LIMIT),
            }
        }
        None => Target {
            what,
            target,
            measured: "n = 256 not in this run's sizes".into(),
            met: None,
        },
    };
    // The RAM of a depth-5 ray tree walked without a heap: the scratch of its walks, splits
    // and hops (`TreeScratch<W, S, H>`: W = 5 + 1, S = H = 5 through mirrors only; W = 5 +
    // 1 + 3 screens, S = H = 2·5 with refraction), as the type is on this machine.
    const TREE_LIMIT: usize = 2 * 1024;
    let mirrors = core::mem::size_of::<vcx::walk::TreeScratch<6, 5>>();
    let all = core::mem::size_of::<vcx::walk::TreeScratch<9, 10>>();
    let _ = write!(
        notes,
        " Ray-tree RAM: a depth-5 tree walked without a heap (`walk::frame_tree_into`) \
         needs a `TreeScratch<6, 5>` through mirrors only, {} bytes, and a \
         `TreeScratch<9, 10>` with refraction and three screens, {} bytes (`size_of` on this \
         machine), besides its call stack and output buffer (ARCHITECTURE.md, \"RAM of a \
         ray tree\"). Target of the device-format issue: a depth-5 walk in under 2 KiB — {}: \
         {}× the target.",
        thousands(mirrors),
        thousands(all),
        if mirrors < TREE_LIMIT {
            "**met**"
        } else {
            "**not met**"
        },
        ratio_text(mirrors as f64 / TREE_LIMIT as f64),
    );
    let tree_target = Target {
        what: "depth-5 ray-tree walk without a heap, through mirrors (Device format sizes)".into(),
        target: "< 2 KiB (2,048 bytes)".into(),
        measured: format!(
            "{} bytes ({} with refraction and screens)",
            thousands(mirrors),
            thousands(all)
        ),
        met: Some(mirrors < TREE_LIMIT),
    };
    Ok(Output {
        caption: format!(
            "File bytes of the binary complex format (`docs/format.md`), as encoded by `vcx \
             build -o` (not read back from a file system), for the grid scene `vcx gen grid N \
             --seed {SEED}` and the example scenes, with and without the history part. Both \
             files hold the same complex: the randomized construction's, seed {BUILD_SEED} \
             (`vcx build`'s default); bytes per cylinder = file bytes / cylinders. History \
             columns as `vcx inspect --json` reports them (`parts.history`: bytes, nodes, \
             links, depth of the decoded DAG). Build seconds: the construction alone. Alone: \
             `vcx gen grid N --seed {SEED} -o g.json; vcx build g.json --history never -o \
             a.vcx; vcx build g.json --history never --explicit-cylinders -o e.vcx; vcx build \
             g.json --history always -o b.vcx; vcx inspect b.vcx --json` for N = {}.",
            join(&s.sizes_n),
        ),
        table: Table {
            header: vec![
                "<n / scene",
                "cylinders",
                "file without history",
                "bytes / cylinder",
                "every cylinder stored",
                "bytes / cylinder",
                "walk RAM",
                "history part",
                "history nodes",
                "links",
                "depth",
                "bytes / node",
                "file with history",
                "bytes / cylinder",
                "build s",
            ],
            rows,
        },
        notes,
        plots: vec![Plot {
            file: "sizes_grid.svg".into(),
            title: "Binary complex file bytes (grid scene)".into(),
            x_label: "objects n",
            y_label: "bytes",
            log_x: true,
            log_y: true,
            series: vec![
                series("without history", without),
                series("with history", with),
            ],
        }],
        targets: vec![t, tree_target],
    })
}

/// The box centred on the scene's bounding box with `1/k` of its area (sides / √k).
fn centred_box(scene: &vcx::SceneRef<'_>, k: u32) -> Result<vcx::partition::Region, Failure> {
    let (lo, hi) = scene.vertices().iter().fold(
        ((i32::MAX, i32::MAX), (i32::MIN, i32::MIN)),
        |(lo, hi), v| {
            (
                (lo.0.min(v.x()), lo.1.min(v.y())),
                (hi.0.max(v.x()), hi.1.max(v.y())),
            )
        },
    );
    let side = f64::from(k).sqrt();
    let half = |a: i32, b: i32| ((f64::from(b) - f64::from(a)) / (2.0 * side)) as i64;
    let (cx, cy) = (
        (i64::from(lo.0) + i64::from(hi.0)) / 2,
        (i64::from(lo.1) + i64::from(hi.1)) / 2,
    );
    let (hx, hy) = (half(lo.0, hi.0), half(lo.1, hi.1));
    let corner = |x: i64, y: i64| {
        vcx::Point::from_raw(
            i32::try_from(x).map_err(internal)?,
            i32::try_from(y).map_err(internal)?,
        )
        .ok_or_else(|| internal("box corner out of range"))
    };
    vcx::partition::Region::new(corner(cx - hx, cy - hy)?, corner(cx + hx, cy + hy)?)
        .ok_or_else(|| internal("empty box"))
}

/// `vcx build --region` on the grid scene: file bytes and views from points in the box,
/// against the whole complex, for centred boxes of 1/4, 1/16 and 1/64 of the scene's area.
pub(super) fn regions(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    // The sizes up to 1024: pruning n = 4096 is as cheap, but its build dominates the run.
    let ns: Vec<u32> = s.sizes_n.iter().copied().filter(|&n| n <= 1024).collect();
    const SHARES: [u32; 3] = [4, 16, 64];
    p.start(ns.len() * SHARES.len());
    let mut rows = Vec::new();
    let mut at_256: Option<(usize, u32)> = None;
    let mut curves: Vec<(String, Vec<(f64, f64)>)> = SHARES
        .iter()
        .map(|k| (format!("box 1/{k} of the area"), Vec::new()))
        .collect();
    let (mut whole, mut whole_explicit) = (Vec::new(), Vec::new());
    for &n in &ns {
        let input = json_input(SceneKind::Grid, n)?;
        let scene = input.file.scene.as_ref();
        let name = format!("grid-{n}.vcx");
        let path = Path::new(&name);
        let built = build_ric(&scene, path)?;
        let full_bytes = build::encode_vcx(path, &scene, &built, false, BUILD_SEED, false)?;
        // The whole complex with every cylinder stored, as version 2 stores a region's.
        let explicit = build::encode_vcx(path, &scene, &built, false, BUILD_SEED, true)?.len();
        let full = crate::input::from_bytes(path, &full_bytes)?;
        whole.push((f64::from(n), full_bytes.len() as f64));
        whole_explicit.push((f64::from(n), explicit as f64));
        for (k, curve) in SHARES.iter().zip(curves.iter_mut()) {
            p.step(&format!("grid n={n} region 1/{k}"));
            let region = centred_box(&scene, *k)?;
            let pruned = build::Built {
                complex: built
                    .complex
                    .prune_to_region(&scene, region)
                    .map_err(internal)?,
                whole: Some(built.complex.clone()),
                history: None,
                seconds: built.seconds,
            };
            let bytes = build::encode_vcx(path, &scene, &pruned, false, BUILD_SEED, false)?;
            let v2 = build::encode_vcx(path, &scene, &pruned, false, BUILD_SEED, true)?.len();
            let boxed = crate::input::from_bytes(path, &bytes)?;
            let points = bench::Points::Given(bench::random_points_in(
                &scene,
                &region,
                s.views_random,
                SEED,
            ));
            let f = bench::measure_views(&full, &points, 0, s.views_repeat, None)?;
            let r = bench::measure_views(&boxed, &points, 0, s.views_repeat, None)?;
            if f.intervals != r.intervals || f.views != r.views {
                return Err(internal(format!(
                    "grid n = {n}, box 1/{k}: views from the region file differ from the whole \
                     complex's ({} against {} intervals per view)",
                    r.intervals, f.intervals
                )));
            }
            curve.1.push((f64::from(n), bytes.len() as f64));
            if n == 256 && *k == 16 {
                at_256 = Some((bytes.len(), *k));
            }
            let ((x0, y0), (x1, y1)) = (region.min().to_f64(), region.max().to_f64());
            rows.push(vec![
                n.to_string(),
                format!("1/{k}"),
                format!("{x0},{y0},{x1},{y1}"),
                thousands(full_bytes.len()),
                thousands(explicit),
                thousands(bytes.len()),
                format!(
                    "{:.1} %",
                    100.0 * bytes.len() as f64 / full_bytes.len() as f64
                ),
                thousands(v2),
                thousands(f.cylinders),
                thousands(r.cylinders),
                format!("{:.1}", f.seconds * 1e6),
                format!("{:.1}", r.seconds * 1e6),
            ]);
        }
    }
    const LIMIT: usize = 256 * 1024;
    let mut notes = String::from(
        "Views from the region file equal the whole complex's from every point (checked in \
         this run: same intervals per view; `tests/tests/region.rs` compares them interval by \
         interval, and with the exact reference). The pruning keeps a conservative superset \
         of the cylinders those views can enter (ARCHITECTURE.md, \"Regions\").",
    );
    if let Some((b, k)) = at_256 {
        let _ = write!(
            notes,
            " Size target of the device-format issue with a region: the n = 256 grid scene \
             pruned to a centred box of 1/{k} of its area takes {} bytes, {} 256 KiB \
             ({}). A region file (format version 4) is the whole complex as version 3 stores \
             it — its cylinders replayed from its vertices — plus the box and one bit per \
             cylinder, whether it is kept: a little larger than the whole file, whatever the \
             box. What it saves is RAM: the reader replays every cylinder but stores only the \
             kept ones (\"kept\", 64 bytes each, and the vertices they name). Storing the \
             kept cylinders instead (version 2, `--explicit-cylinders`; \"kept cylinders \
             stored\") costs about 16 bytes per kept cylinder.",
            thousands(b),
            if b <= LIMIT { "within" } else { "over" },
            if b <= LIMIT {
                "**met** with this box"
            } else {
                "**not met**"
            },
        );
    }
    let mut series_list = vec![
        series("whole complex, no history (replayed)", whole),
        series("whole complex, every cylinder stored", whole_explicit),
    ];
    series_list.extend(curves.into_iter().map(|(label, pts)| series(&label, pts)));
    Ok(Output {
        caption: format!(
            "`vcx build --region X0,Y0,X1,Y1` keeps only the cylinders a view from a point in \
             the box can enter (primary views here; ray trees in the next section). Grid \
             scene `vcx gen grid N --seed {SEED}`, the randomized construction (seed \
             {BUILD_SEED}) without history, pruned to centred boxes of 1/4, \
             1/16 and 1/64 of the scene's bounding-box area; file bytes as `vcx build -o` \
             encodes them (the whole complex as written by default — version 3, cylinders \
             replayed — and with `--explicit-cylinders`, every cylinder stored; the region \
             file as written by default — version 4, the whole complex replayed and a kept \
             map — and with `--explicit-cylinders`, version 2, every kept cylinder stored; \
             share: region file / whole file); µs per view: the median over {r} random free points in the box \
             (seed {SEED}) of the best of {p} runs, from the whole file and from the region \
             file, the same points. Alone: `vcx build g.json --region BOX -o r.vcx; vcx bench \
             views r.vcx` (its random points are drawn in the stored region) and `vcx bench \
             views whole.vcx --region BOX`.",
            r = s.views_random,
            p = s.views_repeat,
        ),
        table: Table {
            header: vec![
                "<n",
                "box area",
                "box",
                "whole file",
                "whole, every cylinder stored",
                "region file",
                "share",
                "region, kept cylinders stored",
                "cylinders",
                "kept",
                "µs / view whole",
                "µs / view region",
            ],
            rows,
        },
        notes,
        plots: vec![Plot {
            file: "regions_grid.svg".into(),
            title: "File bytes with --region (grid scene, no history)".into(),
            x_label: "objects n",
            y_label: "bytes",
            log_x: true,
            log_y: true,
            series: series_list,
        }],
        targets: Vec::new(),
    })
}

/// `vcx build --region` where ray trees leave the box: the hall of mirrors and the mixed
/// scene, file bytes and ray trees from points in the box, against the whole complex, for
/// centred boxes of 1/4, 1/16 and 1/64 of the scene's area.
pub(super) fn region_trees(s: &Sizes, p: &mut Progress) -> Result<Output, Failure> {
    const SHARES: [u32; 3] = [4, 16, 64];
    const MIXED_N: u32 = 30;
    let depth = s.mixed_depth;
    let scenes = [(SceneKind::Hall, s.hall_n), (SceneKind::Mixed, MIXED_N)];
    p.start(scenes.len() * SHARES.len());
    let (mut rows, mut shares) = (Vec::new(), Vec::new());
    for (kind, n) in scenes {
        let input = json_input(kind, n)?;
        let scene = input.file.scene.as_ref();
        let name = format!("{}-{n}.vcx", kind.name());
        let path = Path::new(&name);
        let built = build_ric(&scene, path)?;
        // What `vcx build -o` writes for such a scene (with history), and without it.
        let with = build::encode_vcx(path, &scene, &built, true, BUILD_SEED, false)?;
        let without = build::encode_vcx(path, &scene, &built, false, BUILD_SEED, false)?;
        let full = crate::input::from_bytes(path, &without)?;
        for k in SHARES {
            p.step(&format!("{} region 1/{k}", kind.name()));
            let region = centred_box(&scene, k)?;
            let complex = built
                .complex
                .prune_to_region(&scene, region)
                .map_err(internal)?;
            let behind = complex
                .cylinders()
                .iter()
                .filter(|c| {
                    c.floor
                        .and_then(|f| scene.object(f))
                        .is_some_and(|o| o.material != vcx::Material::Opaque)
                })
                .count();
            let pruned = build::Built {
                complex,
                whole: Some(built.complex.clone()),
                history: None,
                seconds: built.seconds,
            };
            let bytes = build::encode_vcx(path, &scene, &pruned, false, BUILD_SEED, false)?;
            let boxed = crate::input::from_bytes(path, &bytes)?;
            let points = bench::Points::Given(bench::random_points_in(
                &scene,
                &region,
                s.views_random,
                SEED,
            ));
            let f = bench::measure_views(&full, &points, depth, s.views_repeat, None)?;
            let r = bench::measure_views(&boxed, &points, depth, s.views_repeat, None)?;
            if f.intervals != r.intervals || f.views != r.views {
                return Err(internal(format!(
                    "{} box 1/{k}: ray trees from the region file differ from the whole \
                     complex's ({} against {} intervals per tree)",
                    kind.name(),
                    r.intervals,
                    f.intervals
                )));
            }
            shares.push(r.cylinders as f64 / f.cylinders as f64);
            let ((x0, y0), (x1, y1)) = (region.min().to_f64(), region.max().to_f64());
            rows.push(vec![
                format!("{} {n}", kind.name()),
                format!("1/{k}"),
                format!("{x0},{y0},{x1},{y1}"),
                thousands(with.len()),
                thousands(without.len()),
                thousands(bytes.len()),
                thousands(f.cylinders),
                thousands(r.cylinders),
                thousands(behind),
                format!("{:.1}", f.intervals),
                format!("{:.1}", f.seconds * 1e6),
                format!("{:.1}", r.seconds * 1e6),
            ]);
        }
    }
    let (lo, hi) = shares.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| {
        (lo.min(x), hi.max(x))
    });
    let notes = format!(
        "Ray trees from the region file equal the whole complex's from every point (checked in \
         this run: same intervals per tree; `tests/tests/region.rs` compares them interval by \
         interval on these and random scenes, and with the exact reference). The region keeps \
         {:.0}–{:.0} % of the cylinders here: every cylinder behind a mirror, refractive \
         object or screen stays (\"behind\"), since the walks of ray trees behind such an \
         object start at eyes anywhere (virtual eyes leave the box), and only the others are \
         pruned as for primary views: the hall, whose walls are mirrors, keeps most of its \
         complex. What a region saves is RAM, the dropped cylinders (64 bytes each decoded); \
         its file is the file without history plus a bit per cylinder. A scene with such \
         objects is written with its history by default (`--history auto`, for the \
         sheet-anchored point location of `vcx locate`), which is most of that file; ray \
         trees do not need it, and a region file has none.",
        100.0 * lo,
        100.0 * hi
    );
    Ok(Output {
        caption: format!(
            "`vcx build --region X0,Y0,X1,Y1` on scenes with mirrors, refractive objects and \
             screens: the hall of mirrors `vcx gen hall {h} --seed {SEED}` and the mixed scene \
             `vcx gen mixed {MIXED_N} --seed {SEED}`, the randomized construction (seed \
             {BUILD_SEED}), pruned to centred boxes of 1/4, 1/16 and 1/64 of the scene's \
             bounding-box area. Bytes: the file `vcx build -o` writes by default (with \
             history), without history (version 3), and the region file (version 4, no \
             history). Cylinders: of the whole complex, kept in the region, and of those the \
             ones behind a mirror, refractive object or screen (floor of that material). \
             µs per tree: the ray tree of depth {depth} from {r} random free points in the \
             box (seed {SEED}), the median of each point's best of {rep} runs, from the whole \
             file without history and from the region file, the same points; intervals: \
             leaves per tree. Alone: `vcx build S.json --region BOX -o r.vcx; vcx bench views \
             r.vcx --depth {depth}` and `vcx bench views whole.vcx --depth {depth} --region \
             BOX`.",
            h = s.hall_n,
            r = s.views_random,
            rep = s.views_repeat,
        ),
        table: Table {
            header: vec![
                "<scene",
                "box area",
                "box",
                "file, with history",
                "file, no history",
                "region file",
                "cylinders",
                "kept",
                "behind",
                "intervals",
                "µs / tree whole",
                "µs / tree region",
            ],
            rows,
        },
        notes,
        plots: Vec::new(),
        targets: Vec::new(),
    })
}
