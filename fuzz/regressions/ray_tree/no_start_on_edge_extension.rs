// One refractive rectangle (0,4)–(2,5); the eye (2,0) is on the extension of its right
// edge. `vcx::walk::ray_tree` at depth 1 fails with `WalkError::NoStart`; the reference
// (eyes rounded as the core rounds them) gives two intervals. Eyes (2,1) and (2,-18) fail
// the same way, (1,0), (3,0) and (-1,0) do not.
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
                y: 4,
                w: 2,
                h: 1,
            },
        }],
    },
    depth: 1,
    viewpoints: vec![GridPoint { x: 2, y: 0 }],
}
