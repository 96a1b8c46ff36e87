// An opaque triangle (0,2),(1,2),(0,3) and a refractive rectangle (0,4)–(2,5); the eye is
// 2⁻³⁰ units from the rectangle's corner (2,5), outside it. `vcx::walk::ray_tree` at
// depth 1 has the right intervals, branches and boundary vertices, but the start angle of
// the deeper boundary (the triangle seen through the rectangle, mapped back to a primary
// angle in `f64`) is 4.222431627731671 rad against the reference's 4.222431653686247:
// 2.6·10⁻⁸ rad off, where `tests/tests/ray_trees.rs` (and this check) allow 10⁻⁹.
RayTreeInput {
    scene: SceneSpec {
        step: 16,
        place: Origin,
        objects: vec![
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Hull {
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
    viewpoints: vec![NearVertex {
        v: 5,
        dx: 1,
        dy: -1,
        shift: 2,
    }],
}
