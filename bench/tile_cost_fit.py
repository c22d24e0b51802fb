#!/usr/bin/env python3
"""Fits the shard plan's per-tile work model to measured per-tile costs (docs/scale-out.md).

Usage: bench/tile_cost_fit.py [--search] [--shards 4] [--tile-texels 1048576] [--weights PART=W,...]
                              NAME=PLAN_JSON,COSTS_JSON[,COSTS_JSON...] ...
  PLAN_JSON:  `shadowtiles build SCENE ... --plan-shards N --tile-costs` (each tile's planned work parts)
  COSTS_JSON: `shadowtiles build SCENE ... --json --tile-costs` of the same scene and config (one whole
              build, or every shard's output; bench/shard_balance.sh writes both)
  PART: tile (its rays: --tile-texels), triangle_refs, covered_texels, triangle_edges, visible_triangles,
        sub_cell_triangles, plane_edges, layered_cells; W in ray-equivalents per unit.
Prints, per scene, the correlation of each part with the tile's measured CPU seconds, the
least-squares fit (non-negative) over all scenes, and for each weighting (the previous model, the
current one of builder/shard_plan.cpp, the fitted one, and each --weights) the shard max/mean of
measured CPU seconds under the plan that weighting makes. --search instead ranks a grid of weightings
by their worst max/mean over the scenes at N = 4, then N = 8.
"""
import json
import sys

PARTS = ["tile", "triangle_refs", "covered_texels", "triangle_edges", "visible_triangles", "sub_cell_triangles",
         "plane_edges", "layered_cells"]
TILE_TEXELS = 1 << 20  # rays of a tile (--tile-texels): 1024² by default


def load_scene(spec):
    name, files = spec.split("=", 1)
    files = files.split(",")
    plan = json.load(open(files[0]))
    costs = {}
    for f in files[1:]:
        for c in json.load(open(f))["tile_costs"]:
            costs[c["morton"]] = c["cpu_seconds"]
    tiles = []
    for w in plan["tile_work"]:
        if w["morton"] in costs:
            row = {p: 0 for p in PARTS}
            row.update(w)
            row["tile"] = 1.0  # weighed by TILE_TEXELS (its rays) in the models below
            row["cpu"] = costs[w["morton"]]
            tiles.append(row)
    missing = len(plan["tile_work"]) - len(tiles)
    return name, plan, tiles, missing


def pearson(xs, ys):
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    sxx = sum((x - mx) ** 2 for x in xs)
    syy = sum((y - my) ** 2 for y in ys)
    return sxy / (sxx * syy) ** 0.5 if sxx > 0 and syy > 0 else 0.0


def solve(a, b):  # Gaussian elimination with partial pivoting
    n = len(b)
    m = [row[:] + [b[i]] for i, row in enumerate(a)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c]))
        m[c], m[p] = m[p], m[c]
        if abs(m[c][c]) < 1e-300:
            return None
        for r in range(n):
            if r != c:
                f = m[r][c] / m[c][c]
                for k in range(c, n + 1):
                    m[r][k] -= f * m[c][k]
    return [m[i][n] / m[i][i] for i in range(n)]


def nnls(rows, ys, parts):
    active = list(parts)
    while True:
        # Columns scaled to unit mean so the normal equations stay well conditioned.
        scale = {p: (sum(r[p] for r in rows) / len(rows)) or 1.0 for p in active}
        ata = [[sum(r[p] / scale[p] * r[q] / scale[q] for r in rows) for q in active] for p in active]
        aty = [sum(r[p] / scale[p] * y for r, y in zip(rows, ys)) for p in active]
        x = solve(ata, aty)
        coef = {p: v / scale[p] for p, v in zip(active, x)} if x else {}
        neg = [p for p in active if coef.get(p, -1) < 0]
        if not neg:
            return coef
        active.remove(min(neg, key=lambda p: coef[p]))


def plan(works, shards):  # builder/shard_plan.cpp: each tile to the shard its work midpoint falls in
    total = sum(works)
    owner, before, last = [], 0.0, 0
    for w in works:
        mid = before + w / 2
        before += w
        s = min(shards - 1, int(mid / total * shards)) if total > 0 else 0
        s = max(s, last)
        owner.append(s)
        last = s
    return owner


def imbalance(tiles, weights, shards):
    works = [sum(weights.get(p, 0) * t[p] for p in PARTS) for t in tiles]
    owner = plan(works, shards)
    sums = [0.0] * shards
    for o, t in zip(owner, tiles):
        sums[o] += t["cpu"]
    return max(sums) / (sum(sums) / shards), sums


def main():
    global TILE_TEXELS
    args = sys.argv[1:]
    if "--tile-texels" in args:
        i = args.index("--tile-texels")
        TILE_TEXELS = float(args[i + 1])
        del args[i:i + 2]
    shards, extra = 4, []
    if "--shards" in args:
        i = args.index("--shards")
        shards = int(args[i + 1])
        del args[i:i + 2]
    while "--weights" in args:
        i = args.index("--weights")
        extra.append({k: float(v) for k, v in (kv.split("=") for kv in args[i + 1].split(","))})
        del args[i:i + 2]
    scenes = [load_scene(a) for a in args]
    print("| scene | tiles | s total | " + " | ".join(f"r({p})" for p in PARTS[1:]) + " |")
    print("|---|---|---|" + "---|" * (len(PARTS) - 1))
    for name, _, tiles, missing in scenes:
        ys = [t["cpu"] for t in tiles]
        rs = [pearson([t[p] for t in tiles], ys) for p in PARTS[1:]]
        print(f"| {name} | {len(tiles)}{f' ({missing} unmeasured)' if missing else ''} | {sum(ys):.1f} | " +
              " | ".join(f"{r:.2f}" for r in rs) + " |")
    rows = [t for _, _, tiles, _ in scenes for t in tiles]
    ys = [t["cpu"] for t in rows]
    coef = nnls(rows, ys, PARTS)
    per_tile = coef.get("tile", 0)
    print("\nnon-negative least squares, CPU seconds per unit:", {p: f"{v:.3g}" for p, v in coef.items()})
    fit = [sum(coef.get(p, 0) * t[p] for p in PARTS) for t in rows]
    print(f"fit vs measured over all tiles: r = {pearson(fit, ys):.3f}")
    for name, _, tiles, _ in scenes:
        f = [sum(coef.get(p, 0) * t[p] for p in PARTS) for t in tiles]
        print(f"  {name}: r = {pearson(f, [t['cpu'] for t in tiles]):.3f}")
    previous = {"tile": TILE_TEXELS, "triangle_refs": 8.0, "covered_texels": 4.5}
    current = {"tile": TILE_TEXELS, "triangle_refs": 8.0, "covered_texels": 2.0, "triangle_edges": 1e4,
               "layered_cells": 1e3}
    weightings = [("previous (rays + 8 refs + 4.5 covered)", previous),
                  ("current (rays + 8 refs + 2 covered + 1e4 edges + 1e3 layered)", current), ("fitted", coef)]
    for w in extra:
        weightings.append((",".join(f"{k}={v:g}" for k, v in w.items()), w))
    print(f"\nshard max/mean of measured CPU seconds, N = {shards}:")
    print("| weighting | " + " | ".join(n for n, _, _, _ in scenes) + " |")
    print("|---|" + "---|" * len(scenes))
    for label, w in weightings:
        cells = []
        for _, _, tiles, _ in scenes:
            r, _ = imbalance(tiles, w, shards)
            cells.append(f"{r:.3f}")
        print(f"| {label} | " + " | ".join(cells) + " |")


def search(scenes):
    """Grid of weightings in ray-equivalents (a tile's rays = its texels), best first by the worst
    shard max/mean over the scenes at N = 4, then at N = 8."""
    import itertools
    texels = TILE_TEXELS
    results = []
    for a, b, c, e, d, l in itertools.product([8], [2, 4.5, 10], [0, 2e3, 5e3, 1e4], [0, 2e3, 5e3, 1e4],
                                              [0, 1e4, 2e4], [0, 1e3, 3e3]):
        w = {"tile": texels, "triangle_refs": a, "covered_texels": b, "triangle_edges": c, "plane_edges": e,
             "visible_triangles": d, "layered_cells": l}
        worst4 = max(imbalance(t, w, 4)[0] for _, _, t, _ in scenes)
        worst8 = max(imbalance(t, w, 8)[0] for _, _, t, _ in scenes)
        results.append((worst4, worst8, w))
    results.sort(key=lambda r: (round(r[0], 2), r[1]))
    return results


if __name__ == "__main__":
    if "--search" in sys.argv:
        sys.argv.remove("--search")
        if "--tile-texels" in sys.argv:
            i = sys.argv.index("--tile-texels")
            TILE_TEXELS = float(sys.argv[i + 1])
            del sys.argv[i:i + 2]
        found = search([load_scene(a) for a in sys.argv[1:]])
        for worst4, worst8, w in found[:30]:
            print(f"N=4 {worst4:.3f} N=8 {worst8:.3f}", {k: v for k, v in w.items() if k != "tile"})
        sys.exit(0)
    main()
