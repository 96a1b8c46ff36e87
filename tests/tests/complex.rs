//! The visibility complex (cylindrical partition) against its invariants and the exact
//! reference.

use vcx::partition::build_by_sweep;
use vcx::{Material, Point, Scene};
use vcx_demo::generate::{generate, SceneKind};

fn pt(x: i32, y: i32) -> Point {
    Point::from_raw(x << 16, y << 16).unwrap()
}

fn scene(polys: &[Vec<Point>]) -> Scene {
    Scene::new(polys.iter().map(|p| (Material::Opaque, &p[..]))).unwrap()
}

fn boxes(cells: &[(i32, i32)], size: i32, gap: i32) -> Vec<Vec<Point>> {
    cells
        .iter()
        .map(|&(i, j)| {
            let (x, y) = (i * (size + gap), j * (size + gap));
            vec![
                pt(x, y),
                pt(x + size, y),
                pt(x + size, y + size),
                pt(x, y + size),
            ]
        })
        .collect()
}

#[test]
fn empty_scene_has_one_cylinder() {
    let s = scene(&[]);
    let c = build_by_sweep(&s.as_ref()).unwrap();
    assert_eq!(c.cylinders().len(), 1);
    assert_eq!(c.faces(), 1);
    c.validate(&s.as_ref()).unwrap();
}

#[test]
fn one_triangle_has_four_faces() {
    let s = scene(&[vec![pt(0, 0), pt(4, 0), pt(0, 3)]]);
    let c = build_by_sweep(&s.as_ref()).unwrap();
    c.validate(&s.as_ref()).unwrap();
    assert_eq!(c.free_bitangents(), 0);
    // (sky, sky) below and above the sheet, (sky, T) and (T, sky) inside it.
    assert_eq!(c.cylinders().len(), 4);
    assert_eq!(c.faces(), 4);
}

#[test]
fn two_triangles() {
    let s = scene(&[
        vec![pt(0, 0), pt(4, 0), pt(0, 3)],
        vec![pt(10, 1), pt(14, 2), pt(11, 5)],
    ]);
    let c = build_by_sweep(&s.as_ref()).unwrap();
    c.validate(&s.as_ref()).unwrap();
    assert_eq!(c.free_bitangents(), 4);
}

#[test]
fn collinear_lattice_of_boxes_validates() {
    let cells: Vec<(i32, i32)> = (0..4).flat_map(|i| (0..4).map(move |j| (i, j))).collect();
    let s = scene(&boxes(&cells, 2, 1));
    let c = build_by_sweep(&s.as_ref()).unwrap();
    c.validate(&s.as_ref()).unwrap();
    assert!(c.free_bitangents() > 0);
}

#[test]
fn generated_scenes_validate() {
    for (kind, n) in [
        (SceneKind::Grid, 16),
        (SceneKind::Grid, 64),
        (SceneKind::Hall, 8),
        (SceneKind::Mixed, 20),
    ] {
        for seed in 0..3 {
            let f = generate(kind, n, seed).unwrap();
            let s = f.scene.as_ref();
            let c = build_by_sweep(&s).unwrap();
            c.validate(&s)
                .unwrap_or_else(|e| panic!("{kind:?} {n} {seed}: {e}"));
        }
    }
}

/// Directions all around the circle, including the axes and diagonals where axis-aligned
/// scenes are degenerate (the perturbation decides there).
fn sample_directions() -> Vec<vcx::geom::sos::Angle> {
    use vcx::geom::predicates::Direction;
    let mut out = Vec::new();
    for (x, y) in [
        (1, 0),
        (1, 1),
        (0, 1),
        (-1, 1),
        (-1, 0),
        (-1, -1),
        (0, -1),
        (1, -1),
    ] {
        out.push(vcx::geom::sos::Angle::constant(
            Direction::new(x, y).unwrap(),
        ));
    }
    for k in 0..200i64 {
        let x = 1000 - (k * 7919) % 2001;
        let y = 1000 - (k * 104729) % 2001;
        if let Some(d) = Direction::new(x, y) {
            out.push(vcx::geom::sos::Angle::constant(d));
        }
    }
    out
}

#[test]
fn cylinders_crossing_any_direction_are_the_cross_section() {
    let mut scenes: Vec<Scene> = Vec::new();
    let cells: Vec<(i32, i32)> = (0..4).flat_map(|i| (0..3).map(move |j| (i, j))).collect();
    scenes.push(scene(&boxes(&cells, 2, 1)));
    scenes.push(scene(&[
        vec![pt(0, 0), pt(4, 0), pt(0, 3)],
        vec![pt(10, 1), pt(14, 2), pt(11, 5)],
    ]));
    for (kind, n, seed) in [
        (SceneKind::Grid, 25, 1),
        (SceneKind::Mixed, 15, 2),
        (SceneKind::Hall, 6, 3),
    ] {
        scenes.push(generate(kind, n, seed).unwrap().scene);
    }
    for s in &scenes {
        let s = s.as_ref();
        let c = build_by_sweep(&s).unwrap();
        c.validate(&s).unwrap();
        for a in sample_directions() {
            c.validate_at(&s, &a)
                .unwrap_or_else(|e| panic!("{e} at {a:?}"));
        }
    }
}
