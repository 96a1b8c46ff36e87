//! `vcx bench figures --quick` at the tiny sizes of `VCX_FIGURES_TINY=1`, run as the built
//! binary: every plot and the markdown are written, the markdown has one table per figure
//! section and links every plot, and the tables agree where two measurements must (the
//! randomized construction and the sweep build the same canonical partition; the quadtree
//! and the BVH cast the same rays through the same optics, so their errors agree; the exact
//! predicates fail on no stress family). Nothing is asserted on time.

use std::collections::BTreeSet;
use std::process::Command;

use vcx_demo::stress::{Family, SCALES};

const VCX: &str = env!("CARGO_BIN_EXE_vcx");

/// The plots of the Figs. 9–19, run time against error and stability.
const PLOTS: [&str; 15] = [
    "fig09_size.svg",
    "fig10_build_time.svg",
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
        .split("\n### ")
        .find(|s| s.starts_with(title))
        .unwrap_or_else(|| panic!("no section {title:?}"));
    section
        .lines()
        .filter(|l| l.starts_with('|') && !l.starts_with("|---"))
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

    let md = std::fs::read_to_string(dir.join("BENCHMARKS.generated.md")).unwrap();
    assert!(md.starts_with("# Figures (vcx bench figures)"), "{md}");
    assert!(
        md.contains("VCX_FIGURES_TINY=1 vcx bench figures --quick --out"),
        "{md}"
    );
    assert!(md.contains("Machine: "), "{md}");

    // One table per figure section.
    let sections = md.lines().filter(|l| l.starts_with("### ")).count();
    let tables = md.lines().filter(|l| l.starts_with("|---")).count();
    assert_eq!(sections, 8, "{md}");
    assert_eq!(tables, sections, "{md}");

    // Every plot exists, is a non-empty SVG, and is linked from the markdown; no others.
    let mut linked = BTreeSet::new();
    for line in md.lines().filter(|l| l.starts_with("![")) {
        let file = line
            .rsplit_once("](")
            .and_then(|(_, f)| f.strip_suffix(')'))
            .unwrap();
        linked.insert(file.to_string());
    }
    let expected: BTreeSet<String> = PLOTS.iter().map(|s| s.to_string()).collect();
    assert_eq!(linked, expected);
    for plot in PLOTS {
        let svg = std::fs::read_to_string(dir.join(plot)).unwrap();
        assert!(svg.contains("<svg") && svg.contains("</svg>"), "{plot}");
        // A curve was drawn (a polyline per series).
        assert!(svg.contains("<polyline"), "{plot}: no curve");
    }

    // Figs. 9–10: both constructions give the same complex at every n.
    let rows = table_after(&md, "Figs. 9–10").split_off(1);
    assert_eq!(rows.len(), 4, "{rows:?}"); // tiny: n = 4, 16; ric and sweep
    for pair in rows.chunks(2) {
        let [ric, sweep] = pair else {
            panic!("{pair:?}")
        };
        assert_eq!((ric[1], sweep[1]), ("ric", "sweep"));
        assert_eq!(ric[0], sweep[0]);
        assert_eq!(ric[4..6], sweep[4..6], "cylinders and vertices differ");
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
