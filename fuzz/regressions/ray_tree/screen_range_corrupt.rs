// An opaque unit square and a tiny screen triangle at (0, 93) (raw units), the scene
// against the lower-left corner of the coordinate range; the eye (-128, 93) lies exactly on
// the horizontal line through the screen's vertex (0, 93). The screen's range starts
// exactly at θ = 0, which the eye's perturbation puts just below 2π: the anchored walk
// behind the screen started on the turned line past θ = 0 but counted laps from 2π−, and
// `vcx::walk::ray_tree` failed with `WalkError::Corrupt`. Found by the ray-tree property
// of `tests/tests/degenerate.rs` (9 objects, minimized by hand to these two).
RayTreeInput {
    scene: SceneSpec {
        step: 0,
        place: Corner {
            east: false,
            north: false,
        },
        objects: vec![
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Rect {
                    x: 0,
                    y: 0,
                    w: 1,
                    h: 1,
                },
            },
            Obj {
                material: Screen,
                reversed: false,
                rotate: 0,
                shape: Tiny { at: (0, 93) },
            },
        ],
    },
    depth: 1,
    viewpoints: vec![GridPoint { x: -128, y: 93 }],
}
