// Found by the ray-tree property of `tests/tests/degenerate.rs` (`PROPTEST_CASES=2000`),
// proptest-minimized, not reduced by hand. Scene against the lower-left corner of the
// coordinate range. At depth 1 `vcx::walk::ray_tree` drops an interval of the opaque
// object 2 that the reference has just below θ = 2π (start and end both print as
// 6.283185307179432, boundary vertex (0, 2)): one interval fewer. Every object on that
// ray is opaque, so the primary level (`Tree::primary`, events exactly at θ = 0) is the
// suspect, not the anchored walks. Not analysed yet.
RayTreeInput { scene: SceneSpec { step: 20, place: Corner { east: false, north: false }, objects: vec![Obj { material: Opaque, reversed: false, rotate: 0, shape: Tiny { at: (30, -31) } }, Obj { material: Opaque, reversed: false, rotate: 0, shape: Hull { points: vec![] } }, Obj { material: Opaque, reversed: false, rotate: 9, shape: Sliver { a: (0, -52), b: (-128, -10), left: false } }, Obj { material: Glass, reversed: false, rotate: 0, shape: Translated { of: 120, dir: E, gap: Unit } }, Obj { material: Opaque, reversed: false, rotate: 0, shape: Written { points: vec![(0, 0), (0, 1), (1, 0)] } }, Obj { material: Opaque, reversed: false, rotate: 0, shape: Hull { points: vec![(0, 0), (0, 0), (0, 0), (0, 0)] } }] }, depth: 1, viewpoints: vec![NearVertex { v: 209, dx: 0, dy: 1, shift: 0 }] }
