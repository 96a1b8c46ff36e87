// Two opaque boxes and a glass triangle (step 0) seen from ≈ 4.3·10⁹ raw units left; the
// range from just past one box's vertex direction round to it, ≈ 1.3·10⁻¹⁷ rad short of
// the full circle. `ray_tree_range` was right; the test's `generators::restricted` took the
// end's position from the `f64` difference of two equal radians, 0 instead of ≈ 2π, and
// dropped the last interval. Found by the `ray_tree` fuzz target (1200 s, ≈ 31 800 runs).
RayTreeInput {
    scene: SceneSpec {
        step: 0,
        place: Origin,
        objects: vec![
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Rect {
                    x: 63,
                    y: -1,
                    w: 11,
                    h: 16,
                },
            },
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Rect {
                    x: -46,
                    y: -1,
                    w: 16,
                    h: 1,
                },
            },
            Obj {
                material: Glass,
                reversed: true,
                rotate: 255,
                shape: Hull {
                    points: vec![(-1, -1), (41, 3), (-1, -35)],
                },
            },
        ],
    },
    depth: 2,
    viewpoints: vec![Raw {
        x: -281479273914915,
        y: 65535,
    }],
}
