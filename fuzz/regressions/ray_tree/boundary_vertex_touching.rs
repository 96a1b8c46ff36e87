RayTreeInput {
    scene: SceneSpec {
        step: 21,
        place: Origin,
        objects: vec![
            Obj {
                material: Glass,
                reversed: false,
                rotate: 0,
                shape: Tiny { at: (79, -99) },
            },
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Translated {
                    of: 0,
                    dir: N,
                    gap: Touch,
                },
            },
            Obj {
                material: Opaque,
                reversed: true,
                rotate: 29,
                shape: Hull {
                    points: vec![(0, 0), (0, 0)],
                },
            },
            Obj {
                material: Glass,
                reversed: false,
                rotate: 0,
                shape: Sliver {
                    a: (-128, -118),
                    b: (0, 0),
                    left: false,
                },
            },
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Translated {
                    of: 126,
                    dir: E,
                    gap: Touch,
                },
            },
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Hull {
                    points: vec![(-128, 0), (0, 0), (0, 0), (0, 0), (0, 0), (0, 0)],
                },
            },
        ],
    },
    depth: 1,
    viewpoints: vec![OnLine {
        a: 99,
        b: 126,
        t: -128,
    }],
}
