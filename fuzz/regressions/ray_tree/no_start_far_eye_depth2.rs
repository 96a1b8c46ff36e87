// Two opaque rectangles and a tiny glass triangle at (204, 136) (step 2); the eye lies on
// the x-axis ≈ 26 700 units away, so the scene spans ≈ 10⁻⁶ rad. At depth 2
// `vcx::walk::ray_tree` fails with `WalkError::NoStart`; the reference gives a tree. Found
// by the `ray_tree` fuzz target (`cargo +nightly fuzz run ray_tree -- -max_total_time=300`,
// after ≈ 44 000 runs) once the first four ray-tree regressions were fixed. Fixed with
// `no_start_grazing_mirror.rs` (both ends of a deeper range placed on one direction).
RayTreeInput {
    scene: SceneSpec {
        step: 2,
        place: Origin,
        objects: vec![
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 1,
                shape: Rect {
                    x: -19,
                    y: 5,
                    w: 13,
                    h: 9,
                },
            },
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Rect {
                    x: -40,
                    y: 0,
                    w: 11,
                    h: 11,
                },
            },
            Obj {
                material: Glass,
                reversed: true,
                rotate: 0,
                shape: Tiny { at: (102, 68) },
            },
        ],
    },
    depth: 2,
    viewpoints: vec![Raw {
        x: 114796473090047,
        y: 0,
    }],
}
