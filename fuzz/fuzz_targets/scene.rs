//! Degenerate polygons on a coarse grid into scene validation: an error or a valid scene.
//! Coordinates are snapped to a coarse grid on purpose so that collinear vertices, shared
//! supporting lines, touching objects and parallel edges are common.
#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use vcx::{Material, Point, Scene};

#[derive(Arbitrary, Debug)]
struct Input {
    objects: Vec<Vec<(i8, i8)>>,
    scale_shift: u8,
}

fuzz_target!(|input: Input| {
    let shift = u32::from(input.scale_shift % 24);
    let polys: Vec<Vec<Point>> = input
        .objects
        .iter()
        .take(32)
        .map(|o| {
            o.iter()
                .take(16)
                .filter_map(|&(x, y)| Point::from_raw(i32::from(x) << shift, i32::from(y) << shift))
                .collect()
        })
        .collect();
    if let Ok(scene) = Scene::new(polys.iter().map(|p| (Material::Opaque, &p[..]))) {
        for o in scene.as_ref().objects() {
            let poly = scene.as_ref().polygon(o);
            for i in 0..poly.len() {
                let (a, b, c) = (
                    poly[i],
                    poly[(i + 1) % poly.len()],
                    poly[(i + 2) % poly.len()],
                );
                assert_eq!(vcx::geom::predicates::orient(a, b, c), vcx::Sign::Positive);
            }
        }
    }
});
