// A glass sliver and a screen sliver, mirror images one raw unit apart at their lower
// tips (step 22). At depth 1, the range from the screen tip's direction: behind the glass
// the exit eye's range start, exact, lies 2.5·10⁻¹⁷ rad past the screen's tangent, and its
// rounded `i64` angle before it; the walk behind the glass counted the screen as seen
// from the start (right), the walk behind the screen located its start at the rounded
// angle, where the line misses the screen: `NoStart`. Found by the ray-tree property of
// `tests/tests/degenerate.rs` (`PROPTEST_CASES=30000`). Fixed: an event between a range
// start's rounded angle and its exact direction moves the rounded angle to the event's.
RayTreeInput {
    scene: SceneSpec {
        step: 22,
        place: Origin,
        objects: vec![
            Obj {
                material: Opaque,
                reversed: false,
                rotate: 0,
                shape: Hull {
                    points: vec![(0, -128), (-128, 86), (-128, -128)],
                },
            },
            Obj {
                material: Screen,
                reversed: false,
                rotate: 91,
                shape: Sliver {
                    a: (-5, 40),
                    b: (-6, 36),
                    left: false,
                },
            },
            Obj {
                material: Screen,
                reversed: false,
                rotate: 13,
                shape: Translated {
                    of: 126,
                    dir: N,
                    gap: Unit,
                },
            },
            Obj {
                material: Glass,
                reversed: false,
                rotate: 0,
                shape: Reflected {
                    of: 136,
                    dir: W,
                    gap: Unit,
                },
            },
        ],
    },
    depth: 1,
    viewpoints: vec![NearVertex {
        v: 199,
        dx: 0,
        dy: 1,
        shift: 40,
    }],
}
