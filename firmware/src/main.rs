//! Firmware-style link test for `vcx`: validates a scene into static fixed-capacity storage
//! and evaluates the exact and perturbed predicates, with no std and no heap.
#![no_std]
#![no_main]

use core::hint::black_box;

use cortex_m_rt::entry;
use panic_halt as _;
use vcx::geom::sos::{self, RankedPoint};
use vcx::scene::FixedScene;
use vcx::{Material, Point, Sign};

const fn pt(x: i32, y: i32) -> Point {
    match Point::from_raw(x << 16, y << 16) {
        Some(p) => p,
        None => panic!("example coordinates are in range"),
    }
}

static TRIANGLE: [Point; 3] = [pt(0, 0), pt(4, 0), pt(0, 4)];
static SQUARE: [Point; 4] = [pt(10, 10), pt(14, 10), pt(14, 14), pt(10, 14)];

#[entry]
fn main() -> ! {
    let objects = [
        (Material::Opaque, &TRIANGLE[..]),
        (Material::Mirror, &SQUARE[..]),
    ];
    let scene = FixedScene::<16, 4>::new(black_box(objects));
    let mut checksum = 0i32;
    if let Ok(scene) = &scene {
        let s = scene.as_ref();
        let v = s.vertices();
        if let (Some(a), Some(b), Some(c)) = (v.first(), v.get(1), v.get(4)) {
            let sign = sos::orient(
                RankedPoint::vertex(*a, 0),
                RankedPoint::vertex(*b, 1),
                RankedPoint::vertex(*c, 4),
            );
            checksum = sign.to_i8() as i32 + s.len() as i32;
        }
    }
    black_box(checksum == Sign::Positive.to_i8() as i32 + 2);
    loop {
        black_box(&checksum);
    }
}
