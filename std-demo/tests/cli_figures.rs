//! `vcx bench figures --quick` at the tiny sizes of `VCX_FIGURES_TINY=1`, run as the built
//! binary: `BENCHMARKS.md` and every plot in `figures/` are written, the markdown has the
//! header (date, machine, command, load average), the targets table, every section with its
//! table and links every plot, and the tables agree where two measurements must (the
//! randomized construction and the sweep build the same canonical partition; the quadtree
//! and the BVH cast the same rays through the same optics, so their errors agree; the exact
//! predicates fail on no stress family) and with the separate commands (the sizes section's
//! bytes are the lengths of the files `vcx build -o` writes; the views section's complex is
//! the one `vcx build --stats-json` reports). Nothing is asserted on time.

use std::collections::BTreeSet;
use std::process::Command;

use vcx_demo::stress::{Family, SCALES};

const VCX: &str = env!("CARGO_BIN_EXE_vcx");

/// The sections of BENCHMARKS.md, in order (the start of each `## ` heading).
const SECTIONS: [&str; 15] = [
    "Targets",
    "Construction",
    "Views",
    "Ray trees",
    "Frames",
    "Device format sizes",
    "Device format sizes with a region",
    "Regions where ray trees leave the box",
    "Run time against error",
    "Numerical stability",
    "Fig. 11",
    "Figs. 12–13",
    "Figs. 14–15",
    "Fig. 16",
    "Figs. 17–19",
];

/// The plots: the Figs. 9–19, views, ray trees, sizes, run time against error and
/// stability.
const PLOTS: [&str; 20] = [
    "fig09_size.svg",
    "fig10_build_time.svg",
    "views_grid.svg",
    "ray_trees_time.svg",
    "ray_trees_intervals.svg",
    "sizes_grid.svg",
    "regions_grid.svg",
    "fig11_frame_rate.svg",
    "fig12_hall_time.svg",
    "fig13_hall_complexity.svg",
    "fig14_mixed_frame_rate.svg",
    "fig15_mixed_complexity.svg",
    "fig16_active_set.svg",
    "fig17_screens_size.svg",
    "fig18_screens_build_time.svg",
    "fig19_screens_frame_rate.svg",
    "error_hall.svg",
    "error_mixed.svg",
    "stability_build_time.svg",
    "stability_walk_time.svg",
];

/// The rows of the markdown table following the heading that starts with `title`, the
/// header first.
fn table_after<'m>(md: &'m str, title: &str) -> Vec<Vec<&'m str>> {
    let section = md
        .split("\n## ")
        .find(|s| s.starts_with(title))
        .unwrap_or_else(|| panic!("no section {title:?}"));
    section
        .lines()
        .take_while(|l| !l.starts_with("## "))
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .filter(|l| !l.starts_with("|---"))
        .map(|l| l.trim_matches('|').split('|').map(str::trim).collect())
        .collect()
}

#[test]
fn quick_tiny_run_writes_every_table_and_plot() {
    let dir = std::env::temp_dir().join(format!("vcx-cli-figures-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(VCX)
        .args(["bench", "figures", "--quick", "--out"])
        .arg(&dir)
        .env("VCX_FIGURES_TINY", "1")
        // No naive binary: its columns must stay empty (checked below).
        .env_remove("VCX_FIGURES_NAIVE")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "status {:?}: {stderr}", out.status);
    // The progress bar went to stderr.
    assert!(stderr.contains("] "), "{stderr}");

    let md = std::fs::read_to_string(dir.join("BENCHMARKS.md")).unwrap();
    assert!(md.starts_with("# Benchmarks\n"), "{md}");
    // The header: command, date, machine, load average, wall time.
    assert!(
        md.contains("`VCX_FIGURES_TINY=1 vcx bench figures --quick --out"),
        "{md}"
    );
    for key in [
        "| date | ",
        "| CPU | ",
        "| logical cores | ",
        "| memory | ",
        "| compiler | rustc",
        "| build profile | ",
        "| load average (1, 5, 15 min) | at the start ",
        "| wall time | ",
    ] {
        assert!(md.contains(key), "no {key:?} in the header: {md}");
    }

    // Every section, in order, each with its table.
    let headings: Vec<&str> = md.lines().filter(|l| l.starts_with("## ")).collect();
    assert_eq!(headings.len(), SECTIONS.len(), "{headings:?}");
    for (h, want) in headings.iter().zip(SECTIONS) {
        assert!(
            h.starts_with(&format!("## {want}")),
            "{h:?} is not {want:?}"
        );
        assert!(table_after(&md, want).len() > 1, "{want}: no table rows");
    }
    // Every target row has a verdict; the exact predicates meet theirs.
    let targets = table_after(&md, "Targets").split_off(1);
    assert!(targets.len() >= 9, "{targets:?}");
    for t in &targets {
        assert!(
            ["met", "**not met**", "not measured"].contains(&t[3]),
            "{t:?}"
        );
    }
    let exact = targets
        .iter()
        .find(|t| t[0].starts_with("exact predicates on every stress family"))
        .unwrap();
    assert_eq!(exact[3], "met", "{exact:?}");
    // The device-format issue's walk RAM is reported, whatever its verdict.
    let tree = targets
        .iter()
        .find(|t| t[0].starts_with("depth-5 ray-tree walk without a heap"))
        .unwrap();
    assert!(
        tree[2].ends_with("with refraction and screens)"),
        "{tree:?}"
    );

    // Every plot exists, is a non-empty SVG, and is linked from the markdown; no others.
    let mut linked = BTreeSet::new();
    for line in md.lines().filter(|l| l.starts_with("![")) {
        let file = line
            .rsplit_once("](")
            .and_then(|(_, f)| f.strip_suffix(')'))
            .unwrap();
        linked.insert(file.to_string());
    }
    let expected: BTreeSet<String> = PLOTS.iter().map(|s| format!("figures/{s}")).collect();
    assert_eq!(linked, expected);
    for plot in PLOTS {
        let svg = std::fs::read_to_string(dir.join("figures").join(plot)).unwrap();
        assert!(svg.contains("<svg") && svg.contains("</svg>"), "{plot}");
        // A curve was drawn (a polyline per series).
        assert!(svg.contains("<polyline"), "{plot}: no curve");
    }

    // Figs. 9–10: both constructions give the same complex at every n.
    let rows = table_after(&md, "Construction").split_off(1);
    assert_eq!(rows.len(), 4, "{rows:?}"); // tiny: n = 4, 16; ric and sweep
    for pair in rows.chunks(2) {
        let [ric, sweep] = pair else {
            panic!("{pair:?}")
        };
        assert_eq!((ric[1], sweep[1]), ("ric", "sweep"));
        assert_eq!(ric[0], sweep[0]);
        assert_eq!(ric[4..7], sweep[4..7], "cylinders and vertices differ");
    }
    // Figs. 17–19: the number of screens placed is the number asked for (tiny: 0, 1, 3).
    let rows = table_after(&md, "Figs. 17–19").split_off(1);
    let screens: Vec<&str> = rows.iter().map(|r| r[0]).collect();
    assert_eq!(screens, ["0", "1", "3"]);
    // Every frame table measured frames.
    for title in ["Fig. 11", "Figs. 12–13", "Figs. 14–15", "Fig. 16"] {
        let mut rows = table_after(&md, title);
        let header = rows.remove(0);
        let col = header.iter().position(|h| *h == "frames").unwrap();
        assert!(!rows.is_empty(), "{title}");
        for row in rows {
            let frames: usize = row[col].parse().unwrap();
            assert!(frames > 0, "{title}: {row:?}");
        }
    }
    check_error(&md);
    check_stability(&md);
    check_against_commands(&md, &dir);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `12.345 %` → 12.345.
fn percent(cell: &str) -> f64 {
    cell.strip_suffix(" %").unwrap().parse().unwrap()
}

/// Run time against error: per scene the complex (error 0) and both casters at the tiny
/// samples 1 and 4, with equal errors (the same rays through the same optics and narrow
/// phase give the same branches).
fn check_error(md: &str) {
    let mut rows = table_after(md, "Run time against error");
    let header = rows.remove(0);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (scene, method, samples) = (col("scene"), col("method"), col("samples"));
    let (frames, error, wrong) = (col("frames"), col("mean abs error"), col("wrong dominant"));
    let key = |r: &Vec<&str>| {
        (
            r[scene].to_string(),
            r[method].to_string(),
            r[samples].to_string(),
        )
    };
    let keys: Vec<_> = rows.iter().map(key).collect();
    let mut expected = Vec::new();
    for s in ["hall", "mixed"] {
        expected.push((s.to_string(), "complex".to_string(), "exact".to_string()));
        for m in ["quadtree", "bvh"] {
            for k in ["1", "4"] {
                expected.push((s.to_string(), m.to_string(), k.to_string()));
            }
        }
    }
    assert_eq!(keys, expected);
    for r in &rows {
        assert!(r[frames].parse::<usize>().unwrap() > 0, "{r:?}");
        for c in [error, wrong] {
            let v = percent(r[c]);
            assert!((0.0..=100.0).contains(&v), "{r:?}");
        }
        if r[method] == "complex" {
            assert_eq!((percent(r[error]), percent(r[wrong])), (0.0, 0.0), "{r:?}");
        }
    }
    for q in rows.iter().filter(|r| r[method] == "quadtree") {
        let b = rows
            .iter()
            .find(|r| r[method] == "bvh" && r[scene] == q[scene] && r[samples] == q[samples])
            .unwrap();
        assert_eq!((q[error], q[wrong]), (b[error], b[wrong]), "{q:?} {b:?}");
    }
    // Sampling is not exact: one ray per column misses some branch of the hall of mirrors.
    let hall_1 = rows.iter().find(|r| key(r) == expected[1]).unwrap();
    assert!(percent(hall_1[error]) > 0.0, "{hall_1:?}");
}

/// Stability: every family, one instance per scale (tiny), and the exact predicates fail on
/// no build and no view.
fn check_stability(md: &str) {
    let mut rows = table_after(md, "Numerical stability");
    let header = rows.remove(0);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let families: Vec<&str> = rows.iter().map(|r| r[col("family")]).collect();
    assert_eq!(families, Family::ALL.map(Family::name));
    for r in &rows {
        assert_eq!(r[col("instances")], SCALES.len().to_string(), "{r:?}");
        assert!(r[col("views")].parse::<usize>().unwrap() > 0, "{r:?}");
        assert_eq!(r[col("exact builds failing")], "0", "{r:?}");
        assert_eq!(r[col("exact views failing")], "0", "{r:?}");
        // No naive binary was given: its columns are empty, not invented.
        assert_eq!(r[col("naive views differing from exact")], "—", "{r:?}");
    }
}

/// Runs `vcx` with `args`, expecting success; returns stdout.
fn vcx(args: &[&str]) -> String {
    let out = Command::new(VCX).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "vcx {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// `1,234` → 1234.
fn number(cell: &str) -> u64 {
    cell.replace(',', "").parse().unwrap()
}

/// The sections measured in-process against the separate commands: the sizes table's bytes
/// are the lengths of the files `vcx build --history never|always -o` writes (tiny grid
/// n = 16 and the example scenes, which must be what `vcx gen` makes), with `vcx inspect
/// --json`'s history counts; the views table's cylinders are `vcx build --stats-json
/// --method sweep`'s, and the `.vcx` file gives the same intervals as the sweep's complex.
fn check_against_commands(md: &str, dir: &std::path::Path) {
    let scenes = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");
    let grid = dir.join("g16.json");
    let grid = grid.to_str().unwrap();
    vcx(&["gen", "grid", "16", "--seed", "1", "-o", grid]);
    let mut rows = table_after(md, "Device format sizes");
    let header = rows.remove(0);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let cases = [
        ("16", grid.to_string()),
        ("hall.json", format!("{scenes}/hall.json")),
        ("mixed.json", format!("{scenes}/mixed.json")),
    ];
    for (label, scene) in cases {
        let row = rows.iter().find(|r| r[0] == label).unwrap();
        let (a, b) = (dir.join("a.vcx"), dir.join("b.vcx"));
        let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
        vcx(&["build", &scene, "--history", "never", "-o", a]);
        vcx(&["build", &scene, "--history", "always", "-o", b]);
        let len = |f: &str| std::fs::metadata(f).unwrap().len();
        assert_eq!(number(row[col("file without history")]), len(a), "{row:?}");
        assert_eq!(number(row[col("file with history")]), len(b), "{row:?}");
        let v: serde_json::Value = serde_json::from_str(&vcx(&["inspect", b, "--json"])).unwrap();
        let h = &v["parts"]["history"];
        assert_eq!(
            number(row[col("history part")]),
            h["bytes"].as_u64().unwrap()
        );
        assert_eq!(
            number(row[col("history nodes")]),
            h["nodes"].as_u64().unwrap()
        );
        assert_eq!(number(row[col("links")]), h["links"].as_u64().unwrap());
        assert_eq!(number(row[col("depth")]), h["depth"].as_u64().unwrap());
        let c = &v["parts"]["complex"]["cylinders"];
        assert_eq!(number(row[col("cylinders")]), c.as_u64().unwrap());
    }

    let mut rows = table_after(md, "Views");
    let header = rows.remove(0);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let row = rows.iter().find(|r| r[0] == "16").unwrap();
    let stats: serde_json::Value =
        serde_json::from_str(&vcx(&["build", grid, "--method", "sweep", "--stats-json"])).unwrap();
    assert_eq!(
        number(row[col("cylinders")]),
        stats["cylinders"].as_u64().unwrap()
    );
    for r in &rows {
        assert_eq!(
            r[col("intervals per view")],
            r[col("intervals per view, `.vcx`")],
            "{r:?}"
        );
    }
}
