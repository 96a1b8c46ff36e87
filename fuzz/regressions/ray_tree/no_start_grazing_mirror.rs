// A mirror rectangle (0,0)–(4,56) (step 18: 4 units per cell), an opaque sliver above it
// and a small opaque object; the eye is 2⁻³² units right of the extension of the mirror's
// right edge, 56 below (`NearVertex` of the sliver). The mirror's bottom edge is seen from
// the direction of its corner (4,0) over ≈ 10⁻¹⁸ rad (up to the sliver's vertex): mapped
// to the reflected eye, the far end's hit point lies 3·10⁻⁷ grid steps inside the edge —
// below `f64` resolution — so both range ends become the direction of (4,0) and the
// anchored walk finds no start (`WalkError::NoStart`); the reference gives the branch
// [mirror, object 2] there. Fixed: a range whose two ends land on one direction is one
// piece seen just before its end. Found by the ray-tree property of
// `tests/tests/degenerate.rs` (`PROPTEST_CASES=2000`).
RayTreeInput {
    scene: SceneSpec {
        step: 18,
        place: Origin,
        objects: vec![
            Obj {
                material: Mirror,
                reversed: false,
                rotate: 0,
                shape: Rect {
                    x: 0,
                    y: 0,
                    w: 1,
                    h: 14,
                },
            },
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Sliver {
                    a: (119, 120),
                    b: (0, 15),
                    left: false,
                },
            },
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 106,
                shape: Translated {
                    of: 48,
                    dir: S,
                    gap: Unit,
                },
            },
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Rect {
                    x: 0,
                    y: 24,
                    w: 1,
                    h: 1,
                },
            },
        ],
    },
    depth: 1,
    viewpoints: vec![NearVertex {
        v: 100,
        dx: 1,
        dy: 0,
        shift: 0,
    }],
}
