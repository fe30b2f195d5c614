#!/usr/bin/env python3
"""Plot simulated efficiency against the worker count from bench/tilesim.rs results.

Reads the file `cargo bench --bench tilesim -- COSTS.json --json RESULTS.json` wrote and
draws one line per plan (shrinking, grid, and shrink-lpt / bands when simulated):
efficiency (speed-up / P) against P on a log2 axis, with the issue's targets (95 % at 16
workers, 90 % at 64) marked.

Usage: python3 bench/plot_tilesim.py RESULTS.json [OUT.png]
(OUT.png defaults to RESULTS.png next to the input.)
Installs matplotlib into a venv ($TESSERA_VENV, default ~/.cache/tessera-bench-venv) when
the running Python lacks it.
"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plotenv import ensure_deps  # noqa: E402

ensure_deps("plot_tilesim", ["matplotlib"])

import matplotlib  # noqa: E402
import matplotlib.ticker  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {
    "shrinking": ("tab:orange", "-o", "shrinking plan (plan_tiles)"),
    "grid": ("tab:blue", "-s", "equal tiles, reading order"),
    "shrink-lpt": ("tab:green", ":^", "shrinking tiles by decreasing cost (oracle)"),
    "bands": ("tab:purple", "--D", "band plan {bands}"),
}
TARGETS = [(16, 0.95), (64, 0.90)]


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        sys.exit(__doc__)
    src = sys.argv[1]
    out = sys.argv[2] if len(sys.argv) > 2 else os.path.splitext(src)[0] + ".png"
    with open(src) as fh:
        data = json.load(fh)
    series = {}
    for r in data["results"]:
        series.setdefault(r["plan"], []).append((r["workers"], r["efficiency"], r["tiles"]))
    if not series:
        sys.exit(f"plot_tilesim: no results in {src}")

    fig, ax = plt.subplots(figsize=(6.0, 4.2), dpi=80)
    for plan, pts in series.items():
        pts.sort()
        color, fmt, label = STYLE.get(plan, (None, "-x", plan))
        label = label.format(bands=data.get("bands") or "")
        ax.plot([p[0] for p in pts], [100 * p[1] for p in pts], fmt, ms=4, color=color,
                label=label)
    for i, (p, e) in enumerate(TARGETS):
        ax.plot([p], [100 * e], "k_", ms=14, mew=2,
                label="target (issue)" if i == 0 else None)
    ax.set_xscale("log", base=2)
    ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("workers P (tiles per worker: %d)" % data["tiles_per_worker"])
    ax.set_ylabel("simulated efficiency, % (speed-up / P)")
    ymin = min(100 * p[1] for pts in series.values() for p in pts)
    ax.set_ylim(max(0, min(ymin, 85) - 3), 100.5)
    name = os.path.basename(data.get("input", src))
    sync = data.get("sync_cost", 0)
    ax.set_title(f"{name}: {data['width']}x{data['height']}, T1 = {data['work_seconds']:.0f} CPU-s"
                 + (f", sync {sync:g} s/tile" if sync else ""), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(out, dpi=80)
    plt.close(fig)
    print(f"plot_tilesim: wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
