// An opaque triangle (0,2),(1,2),(0,3) and a refractive rectangle (0,4)–(2,5), in raw
// units (2⁻¹⁶); the eye is 1 raw unit left of x = 0 and 10 units below. The rectangle is
// seen through its bottom edge over ≈ 5·10⁻¹² rad, from the direction of the triangle's
// vertex (0,3) to that of the rectangle's vertex (0,4), then through its left edge.
// `vcx::walk::ray_tree` at depth 1 drops the bottom-edge piece: the interval seeing the
// rectangle starts at the rectangle's vertex (0,4) instead of the triangle's vertex (0,3).
// The view, the depth-0 tree and the reference (exact or rounded eyes) all start it at
// (0,3). Found by the `walk` property (then at depth 1) on a scene with 5 objects, eye
// 1024 units away.
RayTreeInput {
    scene: SceneSpec {
        step: 0,
        place: Origin,
        objects: vec![
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Written {
                    points: vec![(0, 2), (1, 2), (0, 3)],
                },
            },
            Obj {
                material: Glass,
                reversed: false,
                rotate: 0,
                shape: Rect {
                    x: 0,
                    y: 4,
                    w: 2,
                    h: 1,
                },
            },
        ],
    },
    depth: 1,
    viewpoints: vec![Raw {
        x: -65536,
        y: -42949672960,
    }],
}
