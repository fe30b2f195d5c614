#!/usr/bin/env python3
"""Which tile counts are within a tolerance of the best on every cost map at once.

Input: files written by `tilesim --sweep --counts FILE` (one per cost map, the same
--frame-costs and --workers). For each frame cost and worker count it prints, per map, the
best count and the range of counts within TOL of that map's best wall time (in tiles per
worker), then the counts that are within TOL on every map: when that set is empty, no rule
that chooses the count from the frame's cost, the worker count and the picture alone can be
within TOL of the best on all the maps (docs/benchmarks.md, "Scaling and the default plan").

Usage: python3 bench/plan_counts.py [--tol 1.05] A.tsv B.tsv ...
"""
import collections
import sys


def load(path):
    walls = collections.defaultdict(dict)
    with open(path) as f:
        for n, line in enumerate(f, 1):
            parts = line.split()
            if len(parts) != 5:
                sys.exit(f"{path}:{n}: expected 5 fields, found {len(parts)}")
            cost, p, k, _planned, wall = parts
            walls[(float(cost), int(p))][int(float(k))] = float(wall)
    return walls


def main(argv):
    tol = 1.05
    if len(argv) >= 2 and argv[0] == "--tol":
        tol = float(argv[1])
        argv = argv[2:]
    if not argv:
        sys.exit(__doc__)
    maps = {path: load(path) for path in argv}
    keys = sorted(set.intersection(*(set(m) for m in maps.values())))
    empty = 0
    for cost, p in keys:
        sets, cols = [], []
        for path, m in maps.items():
            d = m[(cost, p)]
            best = min(d, key=d.get)
            ok = {k for k, w in d.items() if w <= tol * d[best]}
            sets.append(ok)
            cols.append(f"{best / p:5.1f} [{min(ok) / p:.1f}-{max(ok) / p:.1f}]")
        both = set.intersection(*sets)
        if both:
            verdict = f"{min(both) / p:.1f}-{max(both) / p:.1f} ({len(both)} counts)"
        else:
            verdict = "none"
            empty += 1
        print(f"{cost:>7g} CPU-s P={p:<3} " + " | ".join(cols) + f" || on all: {verdict}")
    print(f"{empty} of {len(keys)} cases: no count within {tol} of the best on every map")


if __name__ == "__main__":
    main(sys.argv[1:])
