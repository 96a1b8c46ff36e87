// A refractive unit square (0,0)–(1,1); the eye (1,-1) is on the extension of its right
// edge. `vcx::walk::ray_tree` at depth 1 fails with `WalkError::NoStart`; the reference
// (eyes rounded as the core rounds them) gives a tree. Every eye on the extension of the
// right edge below the square, or of the top edge right of it, fails the same way (a
// 17×17 grid of eyes around the square: 15 of them); the other extensions do not.
RayTreeInput {
    scene: SceneSpec {
        step: 16,
        place: Origin,
        objects: vec![Obj {
            material: Glass,
            reversed: false,
            rotate: 0,
            shape: Rect {
                x: 0,
                y: 0,
                w: 1,
                h: 1,
            },
        }],
    },
    depth: 1,
    viewpoints: vec![GridPoint { x: 1, y: -1 }],
}
