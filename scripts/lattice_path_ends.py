#!/usr/bin/env python3
"""Where another slicer's paths differ from the lattice's struts (BENCHMARKS.md, "Against
other slicers"): why PrusaSlicer can print fewer paths than weft's proven minimum.

Input: a weft G-code of the design (any method: every strut is one extruding move, so its
moves are the lattice's struts) and the other slicer's G-code of the `weft export-stl` STL.
The other G-code is moved onto weft's coordinates (bounding-box centres, then the median
offset of its path vertices to the nearest strut, per layer, three times).

Per layer it reports:
  - the strut graph: nodes, odd nodes (free ends are degree 1), and the proven minimum
    number of paths, sum over connected pieces of max(1, odd nodes / 2) (what `euler` makes);
  - coverage: each strut is sampled every 0.01 mm; a sample is printed when it lies within
    TOL (0.05 mm) of an extruding segment of the other G-code. Struts with no printed sample
    are *dropped*; struts with unprinted samples are *shortened* (unprinted length at each end,
    and whether that end is a free end or a joint);
  - *off-lattice* extrusion: extruding length farther than TOL from every strut (a bead
    joining struts the design does not join, or a bead displaced off its strut);
  - the other slicer's path ends: the nearest lattice node and its degree;
  - the same minimum for the struts the other slicer printed (dropped struts removed): if it
    equals the other slicer's path count, dropping explains the difference.

Usage: lattice_path_ends.py WEFT.gcode OTHER.gcode [--tol 0.05] [--list]
"""
import math
import sys
from collections import defaultdict

sys.path.insert(0, __file__.rsplit("/", 1)[0])
import gcode_paths  # noqa: E402

STEP = 0.01


def seg_dist(p, a, b):
    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy
    t = 0.0 if L2 == 0 else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / L2))
    qx, qy = ax + t * dx, ay + t * dy
    return math.hypot(p[0] - qx, p[1] - qy), (qx, qy)


class Grid:
    """Segments bucketed by the cells their bounding boxes touch."""

    def __init__(self, segs, cell=0.25):
        self.cell, self.segs, self.cells = cell, segs, defaultdict(list)
        for i, (a, b) in enumerate(segs):
            for cx in range(int(math.floor(min(a[0], b[0]) / cell)), int(math.floor(max(a[0], b[0]) / cell)) + 1):
                for cy in range(int(math.floor(min(a[1], b[1]) / cell)), int(math.floor(max(a[1], b[1]) / cell)) + 1):
                    self.cells[(cx, cy)].append(i)

    def nearest(self, p, r):
        c = self.cell
        best, bi, bq = float("inf"), -1, None
        k = int(math.ceil(r / c))
        cx, cy = int(math.floor(p[0] / c)), int(math.floor(p[1] / c))
        for dx in range(-k, k + 1):
            for dy in range(-k, k + 1):
                for i in self.cells.get((cx + dx, cy + dy), ()):
                    d, q = seg_dist(p, *self.segs[i])
                    if d < best:
                        best, bi, bq = d, i, q
        return best, bi, bq


def nodes_of(struts, tol=0.005):
    """Node ids of the strut ends, merging ends closer than tol."""
    pts, key, ids = [], {}, []
    for s in struts:
        e = []
        for p in s:
            cx, cy = round(p[0] / tol), round(p[1] / tol)
            found = None
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    j = key.get((cx + dx, cy + dy))
                    if j is not None and math.hypot(pts[j][0] - p[0], pts[j][1] - p[1]) <= tol:
                        found = j
            if found is None:
                found = len(pts)
                pts.append(p)
                key[(cx, cy)] = found
            e.append(found)
        ids.append(tuple(e))
    return pts, ids


def min_paths(n_nodes, edges):
    """Sum over connected pieces (with an edge) of max(1, odd / 2)."""
    parent = list(range(n_nodes))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    deg = [0] * n_nodes
    for a, b in edges:
        deg[a] += 1
        deg[b] += 1
        parent[find(a)] = find(b)
    odd = defaultdict(int)
    pieces = set()
    for v in range(n_nodes):
        if deg[v]:
            pieces.add(find(v))
            if deg[v] % 2:
                odd[find(v)] += 1
    return sum(max(1, odd[c] // 2) for c in pieces), sum(odd.values()), deg


def bbox(segs):
    xs = [p[0] for s in segs for p in s]
    ys = [p[1] for s in segs for p in s]
    return min(xs), min(ys), max(xs), max(ys)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    tol = 0.05
    if "--tol" in sys.argv:
        tol = float(sys.argv[sys.argv.index("--tol") + 1])
        args.remove(sys.argv[sys.argv.index("--tol") + 1])
    listing = "--list" in sys.argv
    weft_layers, _ = gcode_paths.read(args[0])
    other_layers, _ = gcode_paths.read(args[1])
    if len(weft_layers) != len(other_layers):
        sys.exit(f"layers differ: {len(weft_layers)} against {len(other_layers)}")
    # One offset for the whole part (both slicers place all layers alike).
    ws = [(p[i], p[i + 1]) for l in weft_layers for p in l for i in range(len(p) - 1)]
    os_ = [(p[i], p[i + 1]) for l in other_layers for p in l for i in range(len(p) - 1)]
    wb, ob = bbox(ws), bbox(os_)
    off = ((wb[0] + wb[2] - ob[0] - ob[2]) / 2, (wb[1] + wb[3] - ob[1] - ob[3]) / 2)
    grid_all = Grid(ws)
    for _ in range(3):
        dxs, dys = [], []
        for a, b in os_[:: max(1, len(os_) // 3000)]:
            p = (a[0] + off[0], a[1] + off[1])
            d, _, q = grid_all.nearest(p, 0.5)
            if d < 0.5:
                dxs.append(q[0] - p[0])
                dys.append(q[1] - p[1])
        dxs.sort()
        dys.sort()
        off = (off[0] + dxs[len(dxs) // 2], off[1] + dys[len(dys) // 2])
    print(f"offset other → weft: ({off[0]:+.3f}, {off[1]:+.3f}) mm")

    for li, (wl, ol) in enumerate(zip(weft_layers, other_layers)):
        struts = [(p[i], p[i + 1]) for p in wl for i in range(len(p) - 1)]
        pts, ids = nodes_of(struts)
        nominal_min, nominal_odd, deg = min_paths(len(pts), ids)
        oseg = [((a[0] + off[0], a[1] + off[1]), (b[0] + off[0], b[1] + off[1]))
                for p in ol for a, b in zip(p, p[1:])]
        og = Grid(oseg)
        sg = Grid(struts)
        print(f"\nlayer {li + 1}: {len(struts)} struts ({sum(math.dist(*s) for s in struts):.2f} mm), "
              f"{len(pts)} nodes, {nominal_odd} odd ({sum(1 for d in deg if d == 1)} free ends), "
              f"proven minimum {nominal_min} paths; other slicer: {len(ol)} paths, "
              f"{sum(math.dist(*s) for s in oseg):.2f} mm extruded")
        dropped, shortened, kept = [], [], []
        for si, (a, b) in enumerate(struts):
            L = math.dist(a, b)
            n = max(2, int(L / STEP) + 1)
            printed = []
            for k in range(n):
                t = k / (n - 1)
                p = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
                printed.append(og.nearest(p, tol)[0] <= tol)
            if not any(printed):
                dropped.append(si)
                continue
            kept.append(ids[si])
            i0 = printed.index(True)
            i1 = n - 1 - printed[::-1].index(True)
            gap_a, gap_b = i0 / (n - 1) * L, (n - 1 - i1) / (n - 1) * L
            inner = sum(1 for k in range(i0, i1 + 1) if not printed[k]) / (n - 1) * L
            if gap_a > 2 * STEP or gap_b > 2 * STEP or inner > 2 * STEP:
                shortened.append((si, gap_a, gap_b, inner))
        # Dropped struts.
        dl = [math.dist(*struts[s]) for s in dropped]
        kinds = defaultdict(list)
        for s in dropped:
            da, db = deg[ids[s][0]], deg[ids[s][1]]
            kinds[f"degrees {min(da, db)}–{max(da, db)}"].append(math.dist(*struts[s]))
        print(f"  dropped: {len(dropped)} struts, {sum(dl):.3f} mm"
              + (f", lengths {min(dl):.3f}–{max(dl):.3f} mm" if dl else ""))
        for k, v in sorted(kinds.items()):
            print(f"    ends of {k}: {len(v)} struts, {sum(v):.3f} mm, "
                  f"lengths {', '.join(f'{x:.3f}' for x in sorted(v)) if len(v) <= 12 else f'{min(v):.3f}–{max(v):.3f}'}")
        if listing:
            for s in dropped:
                a, b = struts[s]
                print(f"    ({a[0]:.3f},{a[1]:.3f})–({b[0]:.3f},{b[1]:.3f}) {math.dist(a, b):.3f} mm, "
                      f"degrees {deg[ids[s][0]]},{deg[ids[s][1]]}")
        # Shortened struts: the unprinted length at free ends and at joints.
        free_gap, joint_gap, inner_gap, nfree, njoint = 0.0, 0.0, 0.0, 0, 0
        for si, ga, gb, inner in shortened:
            for g, v in ((ga, ids[si][0]), (gb, ids[si][1])):
                if g > 2 * STEP:
                    if deg[v] == 1:
                        free_gap += g
                        nfree += 1
                    else:
                        joint_gap += g
                        njoint += 1
            inner_gap += inner
        print(f"  shortened: {len(shortened)} struts; unprinted {free_gap:.3f} mm at {nfree} free ends, "
              f"{joint_gap:.3f} mm at {njoint} joints, {inner_gap:.3f} mm inside struts")
        # Off-lattice extrusion.
        off_len, off_runs = 0.0, 0
        for a, b in oseg:
            L = math.dist(a, b)
            n = max(2, int(L / STEP) + 1)
            run = False
            for k in range(n):
                t = k / (n - 1)
                p = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
                far = sg.nearest(p, tol)[0] > tol
                if far:
                    off_len += L / (n - 1) if k else 0
                    if not run:
                        off_runs += 1
                run = far
        print(f"  off-lattice extrusion: {off_len:.3f} mm in {off_runs} runs")
        # The other slicer's path ends.
        ends = defaultdict(int)
        ends_at = defaultdict(int)
        far_ends = []
        node_grid = defaultdict(list)
        for v, p in enumerate(pts):
            node_grid[(int(p[0] // 0.5), int(p[1] // 0.5))].append(v)
        for p in ol:
            for e in (p[0], p[-1]):
                e = (e[0] + off[0], e[1] + off[1])
                best, bv = float("inf"), -1
                for dx in (-1, 0, 1):
                    for dy in (-1, 0, 1):
                        for v in node_grid.get((int(e[0] // 0.5) + dx, int(e[1] // 0.5) + dy), ()):
                            d = math.dist(e, pts[v])
                            if d < best:
                                best, bv = d, v
                if best <= 0.15:
                    ends[f"degree {deg[bv]} node"] += 1
                    ends_at[bv] += 1
                else:
                    far_ends.append(best)
        print("  other slicer's path ends: " + ", ".join(f"{v} at a {k}" for k, v in sorted(ends.items()))
              + (f", {len(far_ends)} farther than 0.15 mm from any node" if far_ends else ""))
        # Odd nodes where no path of the other slicer ends: each is a place where it prints
        # something other than the lattice (a valid cover of the struts ends a path at every
        # odd node).
        strut_of = defaultdict(list)
        for si, (u, v) in enumerate(ids):
            strut_of[u].append(si)
            strut_of[v].append(si)
        gaps = {si: (ga, gb) for si, ga, gb, _ in shortened}
        unended = [v for v in range(len(pts)) if deg[v] % 2 and not ends_at[v]]
        twice = sum(1 for v in ends_at if ends_at[v] > 1)
        print(f"  odd nodes where none of its paths ends: {len(unended)}"
              f" ({', '.join(f'{sum(1 for v in unended if deg[v] == k)} of degree {k}' for k in sorted({deg[v] for v in unended}))})"
              f"; nodes where two or more end: {twice}")
        for v in unended:
            desc = []
            for si in strut_of[v]:
                a, b = struts[si]
                ga, gb = gaps.get(si, (0.0, 0.0))
                far = ids[si][1] if ids[si][0] == v else ids[si][0]
                gap_here = ga if ids[si][0] == v else gb
                desc.append(f"{math.dist(a, b):.3f} mm to a degree-{deg[far]} node"
                            + (f", {gap_here:.3f} mm unprinted here" if gap_here > 2 * STEP else "")
                            + (" (dropped)" if si in dropped else ""))
            if listing or len(unended) <= 12:
                print(f"    ({pts[v][0]:.3f},{pts[v][1]:.3f}) degree {deg[v]}: " + "; ".join(desc))
        # Classify them: a free end on a short stub (the stub's other end a joint that is also
        # unended: the bead runs through the joint and the stub is left out); two joints
        # joined by a short strut, both unended (the two joints printed as one crossing of
        # even degree); anything else.
        un = set(unended)
        stub, pair, other = [], [], []
        for v in unended:
            best = min(strut_of[v], key=lambda si: math.dist(*struts[si]))
            far = ids[best][1] if ids[best][0] == v else ids[best][0]
            L = math.dist(*struts[best])
            if deg[v] == 1 and far in un:
                stub.append(L)
            elif deg[v] == 1:
                other.append(("free end", L))
            elif far in un and deg[far] == 1:
                pass  # counted with its stub
            elif far in un:
                pair.append(L)
            else:
                other.append((f"degree {deg[v]}", L))
        if unended:
            print(f"  of these: {len(stub)} short stubs left out at a through joint (lengths "
                  f"{', '.join(f'{x:.3f}' for x in sorted(stub))} mm; total {sum(stub):.3f} mm)"
                  if stub else "  of these: no stubs left out")
            if pair:
                pl = sorted(pair)[::2]
                print(f"    {len(pair) // 2} pairs of joints joined by a short strut, printed as one crossing "
                      f"(struts {min(pl):.3f}–{max(pl):.3f} mm, median {pl[len(pl) // 2]:.3f}, total {sum(pl):.3f} mm)")
            if other:
                print(f"    {len(other)} others: " + ", ".join(f"{k} (shortest strut {L:.3f} mm)" for k, L in sorted(other, key=lambda x: x[1])[:20]))
        printed_min, printed_odd, _ = min_paths(len(pts), kept)
        print(f"  minimum for the struts it printed (dropped ones removed): {printed_min} paths "
              f"({printed_odd} odd nodes)")


if __name__ == "__main__":
    main()
