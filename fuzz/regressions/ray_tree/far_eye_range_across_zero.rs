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
