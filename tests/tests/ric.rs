//! The randomized incremental construction against the canonical partition of the
//! rotational sweep, after every insertion, for several seeds.

use vcx::partition::{build_by_sweep, History};
use vcx::{Material, ObjectId, Point, Scene, SceneRef, SubScene};
use vcx_demo::generate::{generate, SceneKind};
use vcx_tests::generators::describe;

fn check_every_prefix(name: &str, scene: &SceneRef<'_>, seed: u64) {
    let mut order: Vec<ObjectId> = (0..scene.len() as u32).map(ObjectId).collect();
    // The construction's own shuffle is internal; any order must work, so use a simple one.
    let len = order.len().max(1);
    order.rotate_left((seed as usize) % len);
    if seed % 2 == 1 {
        order.reverse();
    }
    let mut h = History::new();
    for (i, &n) in order.iter().enumerate() {
        h.insert(scene, n)
            .unwrap_or_else(|e| panic!("{name} seed {seed}: inserting {n:?} (#{i}): {e}"));
        let got = h.complex(scene).unwrap();
        let sub = SubScene::new(*scene, order[..=i].iter().copied());
        let sref = sub.as_ref();
        let want = build_by_sweep(&sref).unwrap();
        let g = describe(&got, |o| o.0);
        let w = describe(&want, |o| sub.original(o).unwrap().0);
        if g != w {
            let missing: Vec<_> = w.iter().filter(|d| !g.contains(d)).collect();
            let extra: Vec<_> = g.iter().filter(|d| !w.contains(d)).collect();
            panic!(
                "{name} seed {seed} after inserting {n:?} (#{i} of {:?}):\n missing {missing:#?}\n extra {extra:#?}",
                order
            );
        }
        want.validate(&sref)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        h.validate(scene)
            .unwrap_or_else(|e| panic!("{name}: history after #{i}: {e}"));
    }
}

fn pt(x: i32, y: i32) -> Point {
    Point::from_raw(x << 16, y << 16).unwrap()
}

#[test]
fn two_triangles() {
    let polys = [
        vec![pt(0, 0), pt(4, 0), pt(0, 3)],
        vec![pt(10, 1), pt(14, 2), pt(11, 5)],
    ];
    let s = Scene::new(polys.iter().map(|p| (Material::Opaque, &p[..]))).unwrap();
    for seed in 0..2 {
        check_every_prefix("two triangles", &s.as_ref(), seed);
    }
}

#[test]
fn small_grids() {
    for (n, seed) in [(4, 1), (9, 2), (16, 3)] {
        let f = generate(SceneKind::Grid, n, seed).unwrap();
        for order_seed in 0..4 {
            check_every_prefix(&format!("grid {n}"), &f.scene.as_ref(), order_seed);
        }
    }
}

fn boxes(cells: &[(i32, i32)], size: i32, gap: i32) -> Vec<Vec<Point>> {
    cells
        .iter()
        .map(|&(i, j)| {
            let (x, y) = (i * (size + gap), j * (size + gap));
            vec![
                pt(x, y),
                pt(x + size, y),
                pt(x + size, y + size),
                pt(x, y + size),
            ]
        })
        .collect()
}

#[test]
fn lattices_and_other_families() {
    let cells: Vec<(i32, i32)> = (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).collect();
    let polys = boxes(&cells, 2, 1);
    let s = Scene::new(polys.iter().map(|p| (Material::Opaque, &p[..]))).unwrap();
    for seed in 0..4 {
        check_every_prefix("lattice 3x3", &s.as_ref(), seed);
    }
    for (kind, n, seed) in [
        (SceneKind::Mixed, 12, 5),
        (SceneKind::Hall, 5, 6),
        (SceneKind::Grid, 36, 7),
    ] {
        let f = generate(kind, n, seed).unwrap();
        for order_seed in 0..2 {
            check_every_prefix(&format!("{kind:?} {n}"), &f.scene.as_ref(), order_seed);
        }
    }
}

#[test]
fn seeded_builds_are_canonical() {
    let f = generate(SceneKind::Grid, 49, 9).unwrap();
    let s = f.scene.as_ref();
    let want = describe(&build_by_sweep(&s).unwrap(), |o| o.0);
    for seed in 0..20 {
        let h = History::build(
            &s,
            &vcx::partition::BuildOptions {
                seed,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(
            describe(&h.complex(&s).unwrap(), |o| o.0),
            want,
            "seed {seed}"
        );
        let st = h.stats();
        println!("seed {seed}: {st:?}");
        // The cylinders at θ = 0 come first, so that a walk's start scan stops there.
        let c = h.complex(&s).unwrap();
        let zero = |c: &vcx::partition::Cylinder| c.left == vcx::partition::Wall::Zero;
        let k = c.cylinders().iter().take_while(|c| zero(c)).count();
        assert!(
            k > 0 && c.cylinders()[k..].iter().all(|c| !zero(c)),
            "seed {seed}"
        );
    }
}

#[test]
fn history_locate_agrees_with_the_complex() {
    use vcx::geom::predicates::Direction;
    use vcx::partition::Location;
    use vcx::QueryPoint;
    let mut state = 12345u64;
    let mut rnd = |m: i64| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) as i64).rem_euclid(m)
    };
    let mut checked = 0;
    for (kind, n, seed) in [
        (SceneKind::Grid, 64, 1),
        (SceneKind::Mixed, 20, 2),
        (SceneKind::Hall, 8, 3),
    ] {
        let f = generate(kind, n, seed).unwrap();
        let s = f.scene.as_ref();
        let h = History::build(
            &s,
            &vcx::partition::BuildOptions {
                seed,
                ..Default::default()
            },
        )
        .unwrap();
        let uncompacted = History::build(
            &s,
            &vcx::partition::BuildOptions {
                seed,
                compaction: false,
                ..Default::default()
            },
        )
        .unwrap();
        let c = build_by_sweep(&s).unwrap();
        let v = s.vertices();
        for _ in 0..3000 {
            let a = v[rnd(v.len() as i64) as usize];
            let b = v[rnd(v.len() as i64) as usize];
            let (q, d) = if rnd(2) == 0 && a != b {
                let t = rnd(5) - 2;
                (
                    QueryPoint::from_raw(
                        (a.x() as i64 + t * (b.x() as i64 - a.x() as i64)) << 16,
                        (a.y() as i64 + t * (b.y() as i64 - a.y() as i64)) << 16,
                    ),
                    Direction::new(b.x() as i64 - a.x() as i64, b.y() as i64 - a.y() as i64),
                )
            } else {
                (
                    QueryPoint::from_raw((rnd(80 << 16)) << 16, (rnd(80 << 16)) << 16),
                    Direction::new(rnd(2001) - 1000, rnd(2001) - 1000),
                )
            };
            let (Some(q), Some(d)) = (q, d) else { continue };
            if let Some(Location::Free { cylinder }) = c.locate(&s, q, d) {
                let want = c.cylinder(cylinder).unwrap();
                let (_, got) = h
                    .locate(&s, q, d)
                    .unwrap_or_else(|| panic!("{kind:?}: no cylinder for {q:?} {d:?}"));
                assert_eq!(
                    (got.floor, got.ceiling),
                    (want.floor, want.ceiling),
                    "{kind:?} {q:?} {d:?}"
                );
                // Without compaction: the same live cylinder (ids differ).
                let (_, u) = uncompacted
                    .locate(&s, q, d)
                    .unwrap_or_else(|| panic!("{kind:?}: uncompacted: none for {q:?} {d:?}"));
                assert!(same_trapezoid(u, got), "{kind:?} uncompacted {q:?} {d:?}");
                checked += 1;
            }
        }
        println!("{kind:?}: {:?}", h.stats());
    }
    assert!(checked > 5000);
}

/// A history survives `to_parts` → `from_parts` (what a file stores) with the same
/// locations, and corrupt arenas — ids out of range, a cycle, a dangling node, a repeated
/// object in the order — are refused with an error, never a panic.
#[test]
fn history_parts_round_trip_and_corruption() {
    use vcx::geom::predicates::Direction;
    use vcx::partition::{BuildOptions, CylinderId, HistoryParts};
    use vcx::QueryPoint;
    let f = generate(SceneKind::Mixed, 12, 4).unwrap();
    let s = f.scene.as_ref();
    let h = History::build(&s, &BuildOptions::default()).unwrap();
    let parts = h.to_parts();
    let back = History::from_parts(&s, parts.clone()).unwrap();
    assert_eq!(back.to_parts(), parts);
    assert_eq!(back.stats(), h.stats());
    for k in 0..400i64 {
        let q = QueryPoint::from_raw((k * 7919 % 60) << 32, (k * 104_729 % 60) << 32).unwrap();
        let d = Direction::new(k % 13 - 6, k % 7 - 3).unwrap_or(Direction::new(1, 0).unwrap());
        let a = h.locate(&s, q, d).map(|(i, c)| (i, *c));
        let b = back.locate(&s, q, d).map(|(i, c)| (i, *c));
        assert_eq!(a, b, "{q:?} {d:?}");
    }
    let corrupt = |what: &str, f: &dyn Fn(&mut HistoryParts)| {
        let mut p = parts.clone();
        f(&mut p);
        let r = History::from_parts(&s, p);
        assert!(r.is_err(), "{what}: accepted");
        println!("{what}: {}", r.err().unwrap());
    };
    let dead = parts.children.iter().position(|c| c.1 > 0).unwrap();
    let (start, _) = parts.children[dead];
    corrupt("link to an older node (cycle)", &|p| {
        p.links[start as usize] = CylinderId::from_index(0).unwrap();
    });
    corrupt("link out of range", &|p| {
        p.links[start as usize] = CylinderId::from_index(u32::MAX as usize - 1).unwrap();
    });
    corrupt("child range out of range", &|p| {
        p.children[dead].0 = u32::MAX
    });
    corrupt("node never reached", &|p| {
        let last = p.nodes.len() - 1;
        p.nodes.push(p.nodes[last]);
        p.children.push((0, 0));
    });
    corrupt("repeated object", &|p| p.order[1] = p.order[0]);
    corrupt("floor out of range", &|p| {
        p.nodes[3].floor = Some(ObjectId(999))
    });
    corrupt("vertex of the wrong object", &|p| {
        p.vertices[0].bitangent.first = s.vertices().len() + 5
    });
    corrupt("a live leaf made dead", &|p| {
        let leaf = p.children.iter().position(|c| c.1 == 0).unwrap();
        p.children[leaf] = (start, 1);
    });
    corrupt("empty", &|p| *p = HistoryParts::default());
}

/// The border index is derived state: a history stored after some insertions and loaded
/// again (`from_parts` rebuilds the index with live entries only, while the running
/// construction keeps destroyed ones until it compacts a list) continues with the same
/// nodes, links and vertices, bit for bit, as the uninterrupted construction.
#[test]
fn construction_continues_identically_after_a_round_trip() {
    use vcx::partition::BuildOptions;
    for (kind, n, seed) in [(SceneKind::Grid, 64, 2), (SceneKind::Mixed, 40, 5)] {
        let f = generate(kind, n, seed).unwrap();
        let s = f.scene.as_ref();
        let options = BuildOptions {
            seed,
            ..BuildOptions::default()
        };
        let full = History::build(&s, &options).unwrap();
        let want = full.to_parts();
        let order = full.order().to_vec();
        for cut in [1, order.len() / 3, order.len() - 1] {
            let mut h = History::new();
            for &o in &order[..cut] {
                h.insert(&s, o).unwrap();
            }
            let mut h = History::from_parts(&s, h.to_parts()).unwrap();
            for &o in &order[cut..] {
                h.insert(&s, o).unwrap();
            }
            assert!(
                h.to_parts() == want,
                "{kind:?} n={n}: differs after a cut at {cut}"
            );
            h.validate(&s).unwrap();
        }
    }
}

/// The pieces undoing compaction adds to a compacted history: one per link `C → C′` where
/// `C` has several children and `C′` several parents (counted from the parts).
fn expected_pieces(p: &vcx::partition::HistoryParts) -> usize {
    let mut parents = vec![0usize; p.nodes.len()];
    for c in &p.links {
        parents[c.index()] += 1;
    }
    p.children
        .iter()
        .filter(|k| k.1 >= 2)
        .map(|&(start, len)| {
            p.links[start as usize..(start + len) as usize]
                .iter()
                .filter(|c| parents[c.index()] >= 2)
                .count()
        })
        .sum()
}

/// Whether two cylinders have the same trapezoid and layer (all but the neighbour ids).
fn same_trapezoid(a: &vcx::partition::Cylinder, b: &vcx::partition::Cylinder) -> bool {
    (a.floor, a.ceiling, a.bottom, a.top, a.left, a.right)
        == (b.floor, b.ceiling, b.bottom, b.top, b.left, b.right)
}

/// A history's nodes, children (as lists) and insertion ranges with every piece node (a
/// dead node whose one child has its record) contracted: `C → P → C′` becomes `C → C′`.
#[allow(clippy::type_complexity)]
fn contracted(
    p: &vcx::partition::HistoryParts,
) -> (
    Vec<vcx::partition::Cylinder>,
    Vec<Vec<vcx::partition::CylinderId>>,
    Vec<u32>,
) {
    use vcx::partition::CylinderId;
    let kids = |i: usize| {
        let (s, l) = p.children[i];
        &p.links[s as usize..(s + l) as usize]
    };
    let piece = |i: usize| match kids(i) {
        [only] => same_trapezoid(&p.nodes[i], &p.nodes[only.index()]),
        _ => false,
    };
    let mut id = vec![u32::MAX; p.nodes.len() + 1];
    let mut next = 0;
    for (i, slot) in id.iter_mut().enumerate().take(p.nodes.len()) {
        if !piece(i) {
            *slot = next;
            next += 1;
        }
    }
    id[p.nodes.len()] = next;
    // A start maps to the first kept node at or after it.
    let first_kept = |j: usize| (j..=p.nodes.len()).map(|k| id[k]).find(|&k| k != u32::MAX);
    let map = |c: CylinderId| CylinderId::from_index(id[c.index()] as usize).unwrap();
    let (mut nodes, mut children) = (vec![], vec![]);
    for i in (0..p.nodes.len()).filter(|&i| !piece(i)) {
        let c = p.nodes[i];
        nodes.push(vcx::partition::Cylinder {
            left_neighbour: c.left_neighbour.map(map),
            right_neighbour: c.right_neighbour.map(map),
            ..c
        });
        let through = |c: CylinderId| {
            if piece(c.index()) {
                kids(c.index())[0]
            } else {
                c
            }
        };
        children.push(kids(i).iter().map(|&c| map(through(c))).collect());
    }
    let starts = p
        .starts
        .iter()
        .map(|&s| first_kept(s as usize).unwrap())
        .collect();
    (nodes, children, starts)
}

/// Search path compaction as an option (§4.4): without it, 20 seeds give the same live
/// cylinders as the sweep (and as with it), the DAG passes `validate`, there is one piece
/// node per link `C → C′` with several children of `C` and several parents of `C′` (some
/// on this scene: strictly more nodes and links), and contracting the pieces gives back
/// the compacted history exactly.
#[test]
fn uncompacted_histories_contract_to_the_compacted_ones() {
    use vcx::partition::BuildOptions;
    let f = generate(SceneKind::Grid, 49, 9).unwrap();
    let s = f.scene.as_ref();
    let want = describe(&build_by_sweep(&s).unwrap(), |o| o.0);
    let mut pieces = 0;
    for seed in 0..20 {
        let build = |compaction| {
            History::build(
                &s,
                &BuildOptions {
                    seed,
                    compaction,
                    ..Default::default()
                },
            )
            .unwrap()
        };
        let (hc, hu) = (build(true), build(false));
        assert!(hc.is_compacted() && !hu.is_compacted());
        hu.validate(&s)
            .unwrap_or_else(|e| panic!("seed {seed}: uncompacted: {e}"));
        let live = hu.complex(&s).unwrap();
        assert_eq!(describe(&live, |o| o.0), want, "seed {seed}");
        assert_eq!(live.cylinders(), hc.complex(&s).unwrap().cylinders());
        let (c, u) = (hc.to_parts(), hu.to_parts());
        let k = expected_pieces(&c);
        let (sc, su) = (hc.stats(), hu.stats());
        assert_eq!(
            (su.nodes, su.links),
            (sc.nodes + k, sc.links + k),
            "seed {seed}"
        );
        assert!(su.depth >= sc.depth);
        assert_eq!(u.vertices, c.vertices);
        assert_eq!(u.order, c.order);
        let kids = |p: &vcx::partition::HistoryParts| -> Vec<Vec<vcx::partition::CylinderId>> {
            p.children
                .iter()
                .map(|&(s, l)| p.links[s as usize..(s + l) as usize].to_vec())
                .collect()
        };
        assert_eq!(
            contracted(&c),
            (c.nodes.clone(), kids(&c), c.starts.clone())
        );
        assert!(
            contracted(&u) == (c.nodes.clone(), kids(&c), c.starts.clone()),
            "seed {seed}: the contracted uncompacted history differs"
        );
        pieces += k;
        println!("seed {seed}: compacted {sc:?}, uncompacted {su:?}");
    }
    assert!(pieces > 0, "no insertion both split and merged");
}

/// Replaying a built history's insertion order into a fresh history gives the same history
/// (what `vcx bench build --growth` relies on), and its size obeys the backwards-analysis
/// bound of a randomized incremental construction: the i-th insertion changes at most
/// D·k_i/i cylinders in expectation (k_i: live cylinders after it; D: the objects defining
/// a cylinder), so the history's nodes are O(Σ k_i/i). D = 8 is generous (≈ 3.3 measured).
#[test]
fn replaying_the_order_rebuilds_the_history_within_the_backwards_analysis_bound() {
    let f = generate(SceneKind::Grid, 64, 1).unwrap();
    let s = f.scene.as_ref();
    for seed in [1, 2] {
        let options = vcx::partition::BuildOptions {
            seed,
            ..Default::default()
        };
        let built = History::build(&s, &options).unwrap();
        let mut h = History::new();
        let mut sum = 0.0;
        for (i, &id) in (1..).zip(built.order()) {
            h.insert(&s, id).unwrap();
            sum += h.live_cylinders() as f64 / f64::from(i);
        }
        let (st, want) = (h.stats(), built.stats());
        assert_eq!(st, want, "seed {seed}");
        assert_eq!(
            describe(&h.complex(&s).unwrap(), |o| o.0),
            describe(&built.complex(&s).unwrap(), |o| o.0),
            "seed {seed}"
        );
        let ratio = st.nodes as f64 / sum;
        println!("seed {seed}: {st:?}, sum k_i/i = {sum:.1}, nodes / sum = {ratio:.2}");
        assert!(ratio <= 8.0, "seed {seed}: nodes / sum k_i/i = {ratio:.2}");
    }
}
