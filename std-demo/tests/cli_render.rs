//! `vcx render`, run as the built binary: the PNG has the requested size, and its columns
//! agree with the exact view computed here through the library — a column fully covered
//! by one object shows that object's colour (its palette entry times a brightness) at the
//! horizon, a column seeing nothing shows the floor there, and a column split between
//! branches is a blend. Bad input gives exit status 2 and one `error: ` line.

use std::path::{Path, PathBuf};
use std::process::Command;

use vcx::partition::build_by_sweep;
use vcx::render::{Camera, CoverageTable};
use vcx::walk::{ray_tree, view};
use vcx::QueryPoint;

const VCX: &str = env!("CARGO_BIN_EXE_vcx");

/// The palette of opaque objects, by id modulo 8 (as documented in `vcx render`).
const PALETTE: [[u8; 3]; 8] = [
    [230, 110, 90],
    [110, 190, 110],
    [110, 140, 230],
    [230, 200, 90],
    [190, 110, 210],
    [90, 200, 210],
    [230, 150, 60],
    [180, 180, 180],
];
const FLOOR: [u8; 3] = [58, 52, 46];

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

fn out_file(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vcx-cli-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Decodes an RGB PNG: (width, height, pixels).
fn decode(path: &Path) -> (usize, usize, Vec<u8>) {
    let d = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut r = d.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width as usize, info.height as usize, buf)
}

fn render(args: &[&str], out: &Path) {
    let o = Command::new(VCX)
        .arg("render")
        .args(args)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Whether `px` is `c` times a brightness in (0, 1], up to rounding.
fn proportional(px: [u8; 3], c: [u8; 3]) -> bool {
    let (p, c) = (px.map(f64::from), c.map(f64::from));
    let b = (p[0] * c[0] + p[1] * c[1] + p[2] * c[2]) / (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    b > 0.0 && b <= 1.0 + 1e-9 && (0..3).all(|k| (p[k] - b * c[k]).abs() <= 1.5)
}

#[test]
fn frame_has_the_size_and_the_columns_of_the_view() {
    let scene_path = example("grid.json");
    let (x, y, heading, fov) = (40.1, 43.15, 30.0f64, 100.0f64);
    let (w, h) = (321, 200);
    let out = out_file("grid.png");
    render(
        &[
            scene_path.to_str().unwrap(),
            "--at",
            &format!("{x},{y}"),
            "--heading",
            &heading.to_string(),
            "--fov",
            &fov.to_string(),
            "--width",
            &w.to_string(),
            "--height",
            &h.to_string(),
        ],
        &out,
    );
    let (gw, gh, px) = decode(&out);
    assert_eq!((gw, gh), (w, h));

    let file = vcx_demo::scene_file::load(&scene_path).unwrap();
    let s = file.scene.as_ref();
    let complex = build_by_sweep(&s).unwrap();
    let q = QueryPoint::from_f64(x, y).unwrap();
    let v = view(&complex, &s, q).unwrap();
    let camera = Camera::new(q, heading.to_radians(), fov.to_radians(), w).unwrap();
    let table = CoverageTable::exact(&camera, &v);
    let row = h / 2;
    let (mut solid, mut mixed) = (0, 0);
    for c in 0..w {
        let at = (row * w + c) * 3;
        let p = [px[at], px[at + 1], px[at + 2]];
        let col = table.column(c);
        if col.len() == 1 {
            solid += 1;
            match col[0].0.first() {
                None => assert_eq!(p, FLOOR, "column {c} sees nothing"),
                Some(o) => assert!(
                    proportional(p, PALETTE[o.0 as usize % 8]),
                    "column {c} sees object {}: pixel {p:?}",
                    o.0
                ),
            }
        } else {
            mixed += 1;
        }
    }
    assert!(solid > w / 2 && mixed > 0, "solid {solid}, mixed {mixed}");
}

#[test]
fn ray_tree_frames_have_the_size_and_see_through_mirrors() {
    let scene_path = example("hall.json");
    let (x, y) = (20.3, 20.1);
    let out = out_file("hall.png");
    render(
        &[
            scene_path.to_str().unwrap(),
            "--at",
            &format!("{x},{y}"),
            "--heading",
            "-40",
            "--fov",
            "90",
            "--width",
            "64",
            "--height",
            "48",
            "--depth",
            "3",
        ],
        &out,
    );
    let (gw, gh, px) = decode(&out);
    assert_eq!((gw, gh), (64, 48));
    let file = vcx_demo::scene_file::load(&scene_path).unwrap();
    let s = file.scene.as_ref();
    let complex = build_by_sweep(&s).unwrap();
    let q = QueryPoint::from_f64(x, y).unwrap();
    let tree = ray_tree(&complex, &s, q, 3).unwrap();
    let camera = Camera::new(q, (-40f64).to_radians(), 90f64.to_radians(), 64).unwrap();
    let table = CoverageTable::exact(&camera, &tree);
    let row = 24;
    let mut checked = 0;
    for c in 0..64 {
        let col = table.column(c);
        let at = (row * 64 + c) * 3;
        let p = [px[at], px[at + 1], px[at + 2]];
        // A single branch ending at an opaque object: that object's colour.
        if col.len() == 1 {
            if let Some(o) = col[0].0.last() {
                if s.object(*o).unwrap().material == vcx::Material::Opaque {
                    assert!(
                        proportional(p, PALETTE[o.0 as usize % 8]),
                        "column {c}: {p:?}"
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 0);
}

#[test]
fn bad_input_is_one_error_line_and_status_2() {
    let grid = example("grid.json");
    let out = out_file("bad.png");
    for args in [
        vec!["--at", "0.5", "--heading", "0", "--fov", "90"],
        vec!["--at", "40.1,43.15", "--heading", "0", "--fov", "0"],
        vec!["--at", "40.1,43.15", "--heading", "0", "--fov", "200"],
        vec!["--at", "40.1,43.15", "--width", "0"],
        vec!["--at", "40.1,43.15", "--depth", "99"],
    ] {
        let o = Command::new(VCX)
            .arg("render")
            .arg(&grid)
            .args(&args)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with("error: "), "{err}");
    }
    // A viewpoint inside an object names it.
    let file = vcx_demo::scene_file::load(&grid).unwrap();
    let s = file.scene.as_ref();
    let o0 = s.objects().first().unwrap();
    let poly = s.polygon(o0);
    let (cx, cy) = poly.iter().fold((0.0, 0.0), |a, p| {
        let (x, y) = p.to_f64();
        (a.0 + x / poly.len() as f64, a.1 + y / poly.len() as f64)
    });
    let o = Command::new(VCX)
        .arg("render")
        .arg(&grid)
        .args(["--at", &format!("{cx},{cy}"), "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("object 0"));
}

/// `vcx bench views --fov`: a frame per viewpoint (the ray tree over the field of view,
/// per-column hits, exact coverage), and a field of view out of range is an error.
#[test]
fn bench_views_frames() {
    let scene = example("hall.json");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "bench",
            "views",
            scene.to_str().unwrap(),
            "--random",
            "4",
            "--repeat",
            "1",
            "--depth",
            "2",
        ];
        args.extend_from_slice(extra);
        Command::new(VCX).args(&args).output().unwrap()
    };
    let full = run(&[]);
    let framed = run(&["--fov", "90", "--heading", "30", "--width", "64"]);
    assert!(full.status.success() && framed.status.success());
    let (a, b): (serde_json::Value, serde_json::Value) = (
        serde_json::from_slice(&full.stdout).unwrap(),
        serde_json::from_slice(&framed.stdout).unwrap(),
    );
    assert!(a.get("us_per_frame").is_none());
    assert!(b["us_per_frame"].as_f64().unwrap() > 0.0);
    assert_eq!(b["frame"]["width"], 64);
    // A frame walks the ray tree over its field of view: part of the full tree's intervals.
    let (na, nb) = (
        a["intervals_per_view"].as_f64().unwrap(),
        b["intervals_per_view"].as_f64().unwrap(),
    );
    assert!(nb >= 1.0 && nb < na, "{na} {nb}");
    let bad = run(&["--fov", "200"]);
    assert_eq!(bad.status.code(), Some(2));
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.lines().count() == 1 && err.contains("--fov"), "{err}");
}

/// `--map --dual` put two square panels right of the frame, which is unchanged; the dual
/// panel marks every interval start of the exact view on the eye's trace, at the place the
/// documented coordinates give: θ across, `u = cos θ·(y − c_y) − sin θ·(x − c_x)` up, with
/// `c` the centre of the bounding box of the scene and the eye and `1.05·r` at the top
/// (`r` the largest distance from `c` to them).
#[test]
fn panels_sit_right_of_the_frame_and_mark_the_view_on_the_trace() {
    let scene_path = example("grid.json");
    let (x, y, w, h) = (40.1, 43.15, 300usize, 240usize);
    let base = ["--at", "40.1,43.15", "--heading", "30", "--fov", "100"];
    let size = ["--width", "300", "--height", "240"];
    let (plain, panels) = (out_file("plain.png"), out_file("panels.png"));
    let args: Vec<&str> = base.iter().chain(&size).copied().collect();
    render(
        &[&[scene_path.to_str().unwrap()][..], &args].concat(),
        &plain,
    );
    let more = [&args[..], &["--map", "--dual"]].concat();
    render(
        &[&[scene_path.to_str().unwrap()][..], &more].concat(),
        &panels,
    );
    let (fw, fh, frame) = decode(&plain);
    let (pw, ph, all) = decode(&panels);
    assert_eq!((fw, fh), (w, h));
    assert_eq!((pw, ph), (w + 2 * h, h));
    for row in 0..h {
        assert_eq!(
            frame[row * w * 3..(row + 1) * w * 3],
            all[row * pw * 3..(row * pw + w) * 3],
            "row {row}"
        );
    }
    let file = vcx_demo::scene_file::load(&scene_path).unwrap();
    let s = file.scene.as_ref();
    let c = build_by_sweep(&s).unwrap();
    let q = QueryPoint::from_f64(x, y).unwrap();
    let v = view(&c, &s, q).unwrap();
    let pts: Vec<(f64, f64)> = s
        .vertices()
        .iter()
        .map(|p| p.to_f64())
        .chain([(x, y)])
        .collect();
    let (lo, hi) = pts.iter().fold(
        (
            (f64::INFINITY, f64::INFINITY),
            (f64::NEG_INFINITY, f64::NEG_INFINITY),
        ),
        |(lo, hi), p| {
            (
                (lo.0.min(p.0), lo.1.min(p.1)),
                (hi.0.max(p.0), hi.1.max(p.1)),
            )
        },
    );
    let centre = ((lo.0 + hi.0) / 2.0, (lo.1 + hi.1) / 2.0);
    let r = pts
        .iter()
        .map(|p| (p.0 - centre.0).hypot(p.1 - centre.1))
        .fold(0.0, f64::max)
        * 1.05;
    let x0 = w + h; // the dual panel follows the map
    let mut marked = 0;
    for i in &v {
        let theta = i.start.radians();
        let u = theta.cos() * (y - centre.1) - theta.sin() * (x - centre.0);
        let col = (theta / core::f64::consts::TAU * h as f64).round() as usize;
        let row = (h as f64 / 2.0 - u / r * (h as f64 / 2.0)).round() as usize;
        let at = (row.min(h - 1) * pw + x0 + col.min(h - 1)) * 3;
        marked += usize::from(all[at..at + 3] == [250, 210, 60]);
    }
    assert_eq!(marked, v.len(), "{} interval starts", v.len());
}
