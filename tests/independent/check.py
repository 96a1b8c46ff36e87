#!/usr/bin/env python3
"""An independent check of the `vcx` command line, sharing no code with vcx or its tests.

Exact rational arithmetic (`fractions`), brute force, written from the README's definitions
only. On random scenes of disjoint convex polygons (opaque, mirror, refractive, screen) it
checks:

* `build --stats-json`: `free_bitangents` against a count of the free bitangent segments
  of every pair of objects (scenes in general position; a degenerate scene is not counted,
  since there the count depends on the perturbation), and `complex_vertices` = 2 × that;
* `locate --json`: the objects ahead and behind against exact ray shooting (every object,
  screens included, is an object of the complex);
* `view --depth D --json`, all around and in a field of view (`--from`, `--to`): at random
  directions, and 10⁻⁶ rad either side of printed interval ends, the path of objects
  against an exact ray tracer by virtual eyes (screens transparent; while the depth lasts,
  mirrors reflect and refractive objects refract by the tangent law of DESIGN.md, entry
  and exit);
* `build --region` on the scene, or on an all-opaque copy of it: views of `--depth` from
  inside the box (its free corners included) from the file, the same way.

Two families: `general` (random polygons on the 1/1024 grid, or `--grid 65536`: the scene
grid itself) and `lattice` (axis-aligned boxes and right triangles on the integer
lattice: collinear walls, and viewpoints on half-integer points, so on edge extensions and
bitangents). Exit status 1 on any disagreement, each printed on one line.

    python3 tests/independent/check.py --vcx target/release/vcx --scenes 20
"""
import argparse, json, math, os, random, shutil, subprocess, sys, tempfile
from fractions import Fraction as F



def cross(ax, ay, bx, by):
    return ax * by - ay * bx


def strictly_convex(pts):
    m = len(pts)
    return all(
        cross(pts[(i + 1) % m][0] - pts[i][0], pts[(i + 1) % m][1] - pts[i][1],
              pts[(i + 2) % m][0] - pts[(i + 1) % m][0], pts[(i + 2) % m][1] - pts[(i + 1) % m][1]) > 0
        for i in range(m))


def material(rng):
    """A material, and for a refractive object its index (k/64, exact in the scene's
    16 fractional bits)."""
    u = rng.random()
    if u < 0.25:
        return {"material": "mirror"}
    if u < 0.4:
        return {"material": "refractive", "eta": F(rng.randint(70, 128), 64)}
    return {"material": "screen" if u < 0.5 else "opaque"}


def general_scene(rng, n, size, grid):
    """Polygons inscribed in disjoint circles, vertices on the 1/grid grid."""
    objs, circles = [], []
    for _ in range(20000):
        if len(objs) == n:
            break
        r = rng.uniform(0.6, 3.0)
        cx, cy = rng.uniform(r, size - r), rng.uniform(r, size - r)
        if any(math.hypot(cx - x, cy - y) < r + s + 0.3 for x, y, s in circles):
            continue
        pts = []
        for a in sorted(rng.uniform(0, 2 * math.pi) for _ in range(rng.randint(3, 7))):
            p = (F(round((cx + r * math.cos(a)) * grid), grid), F(round((cy + r * math.sin(a)) * grid), grid))
            if p not in pts:
                pts.append(p)
        if len(pts) < 3 or not strictly_convex(pts):
            continue
        circles.append((cx, cy, r + 0.05))  # rounding moves a vertex by < 0.05
        objs.append(dict(material(rng), vertices=pts))
    return objs


def lattice_scene(rng, n, size, grid):
    """Boxes and right triangles on the integer lattice, at least one unit apart."""
    objs, boxes = [], []
    size = int(size)
    for _ in range(20000):
        if len(objs) == n:
            break
        w, h = rng.randint(1, 3), rng.randint(1, 3)
        x, y = rng.randint(0, size - w), rng.randint(0, size - h)
        if any(x < bx + bw + 1 and bx < x + w + 1 and y < by + bh + 1 and by < y + h + 1
               for bx, by, bw, bh in boxes):
            continue
        boxes.append((x, y, w, h))
        pts = [(F(x), F(y)), (F(x + w), F(y)), (F(x + w), F(y + h)), (F(x), F(y + h))]
        if rng.random() < 0.3:
            del pts[2]
        objs.append(dict(material(rng), vertices=pts))
    return objs


def line_interval(poly, px, py, dx, dy):
    """The closed range of t with p + t·d in the counter-clockwise polygon (None: empty;
    an unbounded end is None), and whether the line runs along an edge."""
    lo = hi = None
    along = False
    for i in range(len(poly)):
        (ax, ay), (bx, by) = poly[i], poly[(i + 1) % len(poly)]
        f0, f1 = cross(bx - ax, by - ay, px - ax, py - ay), cross(bx - ax, by - ay, dx, dy)
        if f1 == 0:
            if f0 < 0:
                return None
            along |= f0 == 0
        elif f1 > 0:
            t = F(-f0) / f1
            lo = t if lo is None or t > lo else lo
        else:
            t = F(-f0) / f1
            hi = t if hi is None or t < hi else hi
    if lo is not None and hi is not None and lo > hi:
        return None
    return lo, hi, along


def first_hit(objs, px, py, dx, dy, skip=None, transparent=()):
    """(t, object) of the first object the open ray p + t·d (t > 0) meets, or None; and
    whether the answer is degenerate (a vertex grazed, two objects at once)."""
    best, degenerate = None, False
    for i, o in enumerate(objs):
        if i == skip or o["material"] in transparent:
            continue
        iv = line_interval(o["vertices"], px, py, dx, dy)
        if iv is None or iv[0] is None or iv[1] is None or iv[1] <= 0:
            continue
        lo, hi, along = iv
        if lo <= 0:
            raise ValueError("the ray starts in object %d" % i)
        # A vertex grazed, an edge followed (decided by the perturbation), a tie.
        degenerate |= lo == hi or along or (best is not None and lo == best[0])
        if best is None or lo < best[0]:
            best = (lo, i)
    return best, degenerate


def free_bitangents(objs):
    """Undirected free bitangent segments between two objects; None if degenerate."""
    count = 0
    for i in range(len(objs)):
        for j in range(i + 1, len(objs)):
            for a in objs[i]["vertices"]:
                for b in objs[j]["vertices"]:
                    dx, dy = b[0] - a[0], b[1] - a[1]
                    sides = []
                    for poly, v0 in ((objs[i]["vertices"], a), (objs[j]["vertices"], b)):
                        s = [cross(dx, dy, v[0] - a[0], v[1] - a[1]) for v in poly if v != v0]
                        if 0 in s:
                            return None
                        sides.append(all(x > 0 for x in s) or all(x < 0 for x in s))
                    if not all(sides):
                        continue
                    free = True
                    for k, o in enumerate(objs):
                        iv = None if k in (i, j) else line_interval(o["vertices"], a[0], a[1], dx, dy)
                        if iv is None or iv[0] > 1 or iv[1] < 0:
                            continue
                        if iv[0] == 1 or iv[1] == 0 or iv[0] == iv[1] or iv[2]:
                            return None
                        free = False
                        break
                    count += free
    return count


def foot(ex, ey, a, b):
    """The foot of the point e on the line ab."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    k = F((ex - a[0]) * dx + (ey - a[1]) * dy) / (dx * dx + dy * dy)
    return a[0] + k * dx, a[1] + k * dy


def edge_at(poly, qx, qy):
    """The one edge (a, b) of the polygon through q, or None (q at a vertex)."""
    edges = [(poly[k], poly[(k + 1) % len(poly)]) for k in range(len(poly))
             if cross(poly[(k + 1) % len(poly)][0] - poly[k][0], poly[(k + 1) % len(poly)][1] - poly[k][1],
                      qx - poly[k][0], qy - poly[k][1]) == 0]
    return edges[0] if len(edges) == 1 else None


def trace(objs, px, py, dx, dy, depth):
    """The objects a ray from the eye p meets, by virtual eyes: screens are passed; while
    the depth lasts a mirror reflects the eye across the hit edge, and a refractive object
    of index η moves it by the tangent law, to F + η(E − F) at the entry edge and
    F + (E − F)/η at the exit edge (F: the eye's foot on the edge); the ray goes on from
    the hit through the new eye's direction. Anything else ends the path. None if
    degenerate (a vertex met)."""
    path, skip = [], None
    ex, ey = px, py
    for _ in range(depth + 1):
        best, degenerate = first_hit(objs, px, py, dx, dy, skip, transparent=("screen",))
        if degenerate:
            return None
        if best is None:
            return path
        t, i = best
        path.append(i)
        o = objs[i]
        if o["material"] not in ("mirror", "refractive") or len(path) > depth:
            return path
        qx, qy = px + t * dx, py + t * dy
        edge = edge_at(o["vertices"], qx, qy)
        if edge is None:
            return None
        fx, fy = foot(ex, ey, *edge)
        k = -1 if o["material"] == "mirror" else o["eta"]
        ex, ey = fx + k * (ex - fx), fy + k * (ey - fy)
        px, py, dx, dy, skip = qx, qy, qx - ex, qy - ey, i
        if o["material"] == "refractive":
            # Across the object to its exit edge, and out.
            iv = line_interval(o["vertices"], px, py, dx, dy)
            if iv is None or iv[1] is None or iv[1] <= 0 or iv[2]:
                return None
            qx, qy = px + iv[1] * dx, py + iv[1] * dy
            edge = edge_at(o["vertices"], qx, qy)
            if edge is None:
                return None
            fx, fy = foot(ex, ey, *edge)
            ex, ey = fx + (ex - fx) / o["eta"], fy + (ey - fy) / o["eta"]
            px, py, dx, dy = qx, qy, qx - ex, qy - ey
    return path


def free_point(rng, objs, args, lattice):
    size, grid = args.size, args.grid
    while True:
        if lattice:
            x, y = F(rng.randint(0, 2 * int(size)), 2), F(rng.randint(0, 2 * int(size)), 2)
        else:
            x, y = F(round(rng.uniform(0, size) * grid), grid), F(round(rng.uniform(0, size) * grid), grid)
        x, y = place(args, x, y)
        if is_free(objs, x, y):
            return x, y


def is_free(objs, x, y):
    """Whether the point is outside every object (boundaries included)."""
    ivs = [line_interval(o["vertices"], x, y, F(1), F(0)) for o in objs]
    return not any(iv is not None and (iv[0] is None or iv[0] <= 0) and (iv[1] is None or iv[1] >= 0) for iv in ivs)


def place(args, x, y):
    """A point of the scene box moved to its place: centred on `--centre`, scaled."""
    half = F(args.size) / 2
    return (x - half) * args.scale + args.centre[0], (y - half) * args.scale + args.centre[1]


def vcx(binary, *args):
    r = subprocess.run([binary, *args], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError("vcx %s: %s" % (" ".join(args), r.stderr.strip()))
    return r.stdout


def write_scene(path, objs):
    with open(path, "w") as f:
        json.dump({"objects": [dict({k: float(v) for k, v in o.items() if k == "eta"}, material=o["material"],
                                    vertices=[[float(x), float(y)] for x, y in o["vertices"]]) for o in objs]}, f)


def check_scene(args, family, seed, tmp, tally):
    rng = random.Random("%s %d" % (family, seed))
    lattice = family == "lattice"
    objs = (lattice_scene if lattice else general_scene)(rng, args.objects, args.size, args.grid)
    # Near the top of the coordinate range: --scale 1000, or --centre 16000,-16000.
    objs = [dict(o, vertices=[place(args, x, y) for x, y in o["vertices"]]) for o in objs]
    path = os.path.join(tmp, "%s-%d.json" % (family, seed))
    write_scene(path, objs)
    where = "%s scene %d (%s)" % (family, seed, path)
    bad = []
    stats = json.loads(vcx(args.vcx, "build", path, "--stats-json", "--seed", str(seed)))
    want = free_bitangents(objs)
    if want is not None:
        tally["bitangent counts"] += 1
        if stats["free_bitangents"] != want:
            bad.append("%s: free_bitangents %d, expected %d" % (where, stats["free_bitangents"], want))
    if stats["complex_vertices"] != 2 * stats["free_bitangents"]:
        bad.append("%s: complex_vertices %d is not 2 × free_bitangents" % (where, stats["complex_vertices"]))
    for _ in range(args.rays):
        x, y = free_point(rng, objs, args, lattice)
        dx, dy = rng.randint(-1000, 1000), rng.randint(-1000, 1000)
        ahead, d1 = first_hit(objs, x, y, F(dx), F(dy))
        behind, d2 = first_hit(objs, x, y, F(-dx), F(-dy))
        if (dx, dy) == (0, 0) or d1 or d2:
            continue
        out = json.loads(vcx(args.vcx, "locate", path, "--at", "%r,%r" % (float(x), float(y)),
                             "--dir", "%d,%d" % (dx, dy), "--json"))
        want = (ahead and ahead[1], behind and behind[1])
        tally["rays located"] += 1
        if (out["forward"], out["backward"]) != want:
            bad.append("%s: locate --at %r,%r --dir %d,%d: (%s, %s), expected %s"
                       % (where, float(x), float(y), dx, dy, out["forward"], out["backward"], want))
    points = [free_point(rng, objs, args, lattice) for _ in range(args.views)]
    at = os.path.join(tmp, "%s-%d.txt" % (family, seed))
    with open(at, "w") as f:
        f.writelines("%r,%r\n" % (float(x), float(y)) for x, y in points)
    # All around, then a field of view (integer degrees, perhaps across 0°).
    lo = rng.randint(0, 359)
    fov = (lo, lo + rng.randint(1, 179))
    for field in (None, fov):
        extra = [] if field is None else ["--from", str(field[0]), "--to", str(field[1] % 360)]
        views = vcx(args.vcx, "view", path, "--at-file", at, "--depth", str(args.depth), "--json", *extra)
        bad += check_views(args, rng, objs, points, views.splitlines(), field, where, tally)
    return bad + check_region(args, rng, objs, lattice, tmp, where, tally)


def check_region(args, rng, objs, lattice, tmp, where, tally):
    """`build --region`: the same scene, as it is (ray trees of `--depth`) or all opaque (a
    coin toss per scene), kept for a box of a third of the scene's side; views from inside
    the box (its corners included when free) against the exact ray tracer."""
    side = F(args.size) / 3
    x0, y0 = (F(rng.randint(0, int(2 * side))) for _ in range(2))
    (bx0, by0), (bx1, by1) = place(args, x0, y0), place(args, x0 + side, y0 + side)
    if rng.random() < 0.5:
        objs = [dict({k: v for k, v in o.items() if k != "eta"}, material="opaque") for o in objs]
        where += " (all opaque)"
    path = os.path.join(tmp, "region.json")
    write_scene(path, objs)
    box = "%r,%r,%r,%r" % (float(bx0), float(by0), float(bx1), float(by1))
    out = os.path.join(tmp, "region.vcx")
    vcx(args.vcx, "build", path, "--region", box, "-o", out)
    points = [(x, y) for x, y in ((bx0, by0), (bx1, by0), (bx1, by1), (bx0, by1)) if is_free(objs, x, y)]
    for _ in range(10000):
        if len(points) >= args.views:
            break
        x, y = free_point(rng, objs, args, lattice)
        if bx0 <= x <= bx1 and by0 <= y <= by1:
            points.append((x, y))
    at = os.path.join(tmp, "region.txt")
    with open(at, "w") as f:
        f.writelines("%r,%r\n" % (float(x), float(y)) for x, y in points)
    views = vcx(args.vcx, "view", out, "--at-file", at, "--depth", str(args.depth), "--json").splitlines()
    tally["region viewpoints"] += len(points)
    return check_views(args, rng, objs, points, views, None, where + " --region " + box, tally)


def check_views(args, rng, objs, points, views, field, where, tally):
    if len(views) != len(points):
        return ["%s: %d views for %d points" % (where, len(views), len(points))]
    bad = []
    for (x, y), line in zip(points, views):
        intervals = json.loads(line)["intervals"]
        ends = [e for iv in intervals for e in (iv["start"], iv["end"])]
        # Random directions, and both sides of some printed ends (1e-6 rad away): an end
        # out of place by more than that is seen on one side.
        near = [e + s for e in rng.sample(ends, min(len(ends), args.samples // 2)) for s in (-1e-6, 1e-6)]
        randoms = (rng.uniform(0, 2 * math.pi) if field is None else math.radians(rng.uniform(*field))
                   for _ in range(args.samples))
        for a, beside in [(a, False) for a in randoms] + [(a, True) for a in near]:
            a %= 2 * math.pi
            if field is not None and (a - math.radians(field[0])) % (2 * math.pi) > math.radians(field[1] - field[0]):
                continue  # beside an end of the field, outside it
            # Printed ends are rounded: a sample that close to one is not decided by them.
            if any(abs(math.remainder(a - e, 2 * math.pi)) < 1e-7 for e in ends):
                continue
            want = trace(objs, x, y, F(math.cos(a)), F(math.sin(a)), args.depth)
            if want is None:
                continue
            got = next((iv["path"] for iv in intervals
                        if (iv["start"] <= a < iv["end"] if iv["start"] <= iv["end"] else not iv["end"] <= a < iv["start"])), [])
            tally["view directions"] += 1
            tally["of them beside an interval end"] += beside
            tally["of them past a mirror or lens"] += len(want) > 1
            if got != want:
                bad.append("%s: view --at %r,%r --depth %d (field %s) at %.9f rad: %s, expected %s"
                           % (where, float(x), float(y), args.depth, field, a, got, want))
    return bad


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--vcx", default="target/release/vcx", help="the vcx binary")
    p.add_argument("--family", choices=["general", "lattice", "both"], default="both")
    p.add_argument("--scenes", type=int, default=10, help="scenes per family")
    p.add_argument("--seed", type=int, default=0, help="first scene seed")
    p.add_argument("--objects", type=int, default=20)
    p.add_argument("--size", type=int, default=30, help="side of the scene box, centred on the origin")
    p.add_argument("--scale", type=int, default=1, help="scale factor of every coordinate")
    p.add_argument("--centre", default="0,0", help="X,Y: integer centre of the scene box (write --centre=-X,Y for a negative X; |centre| + scale × size / 2 must stay below 16384)")
    p.add_argument("--grid", type=int, default=1024, help="the general family's grid: 1/GRID units, a power of two up to 65536 (the scene grid)")
    p.add_argument("--depth", type=int, default=4)
    p.add_argument("--rays", type=int, default=20, help="located rays per scene")
    p.add_argument("--views", type=int, default=8, help="viewpoints per scene")
    p.add_argument("--samples", type=int, default=40, help="directions per view")
    args = p.parse_args()
    args.centre = tuple(int(c) for c in args.centre.split(","))
    if 65536 % args.grid or max(map(abs, args.centre)) + args.scale * args.size / 2 >= 16384:
        p.error("--grid must divide 65536, and the scene must stay within |x|, |y| < 16384")
    families = ["general", "lattice"] if args.family == "both" else [args.family]
    tally = {"bitangent counts": 0, "rays located": 0, "view directions": 0, "of them beside an interval end": 0,
             "of them past a mirror or lens": 0, "region viewpoints": 0}
    bad = []
    tmp = tempfile.mkdtemp(prefix="vcx-independent-")
    for family in families:
        for seed in range(args.seed, args.seed + args.scenes):
            bad += check_scene(args, family, seed, tmp, tally)
    for line in bad:
        print(line)
    if bad:
        print("the scenes and viewpoints are kept in %s" % tmp)
    else:
        shutil.rmtree(tmp)
    print("independent check: %d scenes per family (%s), %s; %d disagreements"
          % (args.scenes, ", ".join(families), ", ".join("%s %d" % kv for kv in tally.items()), len(bad)))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
