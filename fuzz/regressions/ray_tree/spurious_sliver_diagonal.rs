// Found by the `ray_tree` fuzz target (900 s run after the collapsed-range fixes of
// `thin_interval_below_2pi.rs` and `corrupt_glass_touch`), printed by the target. Glass
// square with its corner exactly on the diagonal from the eye; an exit range end mapped in
// `f64` landed one ulp past the direction of object 1's vertex (exactly on it).
RayTreeInput { scene: SceneSpec { step: 13, place: Origin, objects: vec![Obj { material: Glass, reversed: false, rotate: 227, shape: Rect { x: 14, y: -19, w: 6, h: 5 } }, Obj { material: Opaque, reversed: true, rotate: 156, shape: Reflected { of: 255, dir: E, gap: Cell } }, Obj { material: Screen, reversed: false, rotate: 245, shape: Reflected { of: 245, dir: NW, gap: TwoUnits } }] }, depth: 2, viewpoints: vec![GridPoint { x: 0, y: 0 }] }
