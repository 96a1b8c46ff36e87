// A tiny opaque triangle and square (step 0) seen from ≈ 8.6·10⁹ raw units left, on the
// extension of the square's bottom edge; the range from the triangle's vertex (−1.2·10⁻¹⁰
// rad) across θ = 0 to the square's (+1.2·10⁻¹⁰ rad). `ray_tree_range` was right; the
// test's `generators::restricted` took the start at θ = 0 for one just behind `from` (its
// 10⁻⁹ rad tie rule). Found by the `ray_tree` fuzz target (420 s, ≈ 24 000 runs).
RayTreeInput {
    scene: SceneSpec {
        step: 0,
        place: Origin,
        objects: vec![
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Sliver {
                    a: (58, 0),
                    b: (-1, -1),
                    left: true,
                },
            },
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 47,
                shape: Rect {
                    x: -58,
                    y: 0,
                    w: 1,
                    h: 1,
                },
            },
            Obj {
                material: Screen,
                reversed: true,
                rotate: 255,
                shape: Rect {
                    x: -9,
                    y: 6,
                    w: 1,
                    h: 16,
                },
            },
        ],
    },
    depth: 2,
    viewpoints: vec![Raw {
        x: -562949953355811,
        y: 0,
    }],
}
