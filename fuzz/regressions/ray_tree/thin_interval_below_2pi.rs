// Found by the ray-tree property of `tests/tests/degenerate.rs` (`PROPTEST_CASES=2000`),
// proptest-minimized, not reduced by hand. Scene against the lower-left corner of the
// coordinate range. At depth 1 `vcx::walk::ray_tree` drops an interval of object 2
// (a glass triangle once built) that the reference has just below θ = 2π (start and end both print as
// 6.283185307179432, boundary vertex (0, 2)): one interval fewer. Cause: the glass
// piece ≈ 3·10⁻²⁷ rad wide between (0, 2) and (2, 2) maps through the glass's entry edge to
// two range ends on one `f64` direction, which `split` dropped as empty. Fixed by
// `map_range` (collapsed ranges are one direction, split onto one edge).
RayTreeInput { scene: SceneSpec { step: 20, place: Corner { east: false, north: false }, objects: vec![Obj { material: Opaque, reversed: false, rotate: 0, shape: Tiny { at: (30, -31) } }, Obj { material: Opaque, reversed: false, rotate: 0, shape: Hull { points: vec![] } }, Obj { material: Opaque, reversed: false, rotate: 9, shape: Sliver { a: (0, -52), b: (-128, -10), left: false } }, Obj { material: Glass, reversed: false, rotate: 0, shape: Translated { of: 120, dir: E, gap: Unit } }, Obj { material: Opaque, reversed: false, rotate: 0, shape: Written { points: vec![(0, 0), (0, 1), (1, 0)] } }, Obj { material: Opaque, reversed: false, rotate: 0, shape: Hull { points: vec![(0, 0), (0, 0), (0, 0), (0, 0)] } }] }, depth: 1, viewpoints: vec![NearVertex { v: 209, dx: 0, dy: 1, shift: 0 }] }
