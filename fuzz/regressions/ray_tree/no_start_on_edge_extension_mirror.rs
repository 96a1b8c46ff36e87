// The same for a mirror: a mirror unit square (0,0)–(1,1), the eye (-1,1) on the extension
// of its top edge. `vcx::walk::ray_tree` at depth 1 fails with `WalkError::NoStart`; the
// reference gives a tree. For the mirror the failing eyes are on the extensions of the top
// edge left of the square and of the right edge above it (15 of a 17×17 grid).
RayTreeInput {
    scene: SceneSpec {
        step: 16,
        place: Origin,
        objects: vec![Obj {
            material: Mirror,
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
    viewpoints: vec![GridPoint { x: -1, y: 1 }],
}
