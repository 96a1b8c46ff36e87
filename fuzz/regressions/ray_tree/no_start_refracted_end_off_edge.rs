// A screen and a small glass square (−75, −75)–(−69, −69) (step 0); the eye lies on the
// x-axis ≈ 65 800 units away, so the glass spans ≈ 10⁻⁹ rad. At depth 2 the range behind
// the glass's exit edge starts at a direction computed in `f64` (`map_end`) whose hit
// point lies within the rounding of the edge's endpoint: the rounded line from the exit
// eye misses the glass, and `vcx::walk::ray_tree` failed with `WalkError::NoStart`; the
// reference gives the branch [glass] there. Fixed: a mapped direction whose line does not
// cross the edge strictly (exact test) is that endpoint. Found by the unseeded `ray_tree`
// fuzz smoke run of `.ci/run` (`cargo +nightly fuzz run ray_tree`).
RayTreeInput {
    scene: SceneSpec {
        step: 0,
        place: Origin,
        objects: vec![
            Obj {
                material: Screen,
                reversed: false,
                rotate: 5,
                shape: Rect {
                    x: -1,
                    y: -17,
                    w: 16,
                    h: 16,
                },
            },
            Obj {
                material: Glass,
                reversed: true,
                rotate: 181,
                shape: Rect {
                    x: -75,
                    y: -75,
                    w: 6,
                    h: 6,
                },
            },
        ],
    },
    depth: 2,
    viewpoints: vec![Raw {
        x: 282621716269823,
        y: 0,
    }],
}
