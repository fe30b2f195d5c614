#!/usr/bin/env python3
"""Plot error against CPU time for bench/ambient.sh results and compute time ratios.

Reads every runs*.tsv in the results folder (default docs/benchmarks/ambient), writes
  error-vs-cpu-<scene>-ab<N>.png   one log-log chart per scene and -ab level
  ratios.tsv / ratios.md           rpict CPU time / tpict CPU time at matched error
Each renderer's Pareto front (runs no cheaper run beats in error) is interpolated
piecewise-linearly in log(error)-log(time); a ratio is given only where the error level
lies inside both fronts (no extrapolation).

Usage: python3 bench/plot_ambient.py [RESULTS_DIR] [--err err_avgref]
  --err own   each renderer against its own reference (err_rpictref for rpict's runs,
              err_tpictref for tpict's): leaves out the references' own difference
Installs matplotlib and numpy into a venv ($TESSERA_VENV, default
~/.cache/tessera-bench-venv) when the running Python lacks them.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fronts import pareto, time_at  # noqa: E402
from plotenv import ensure_deps  # noqa: E402

ensure_deps("plot_ambient", ["matplotlib", "numpy"])

import csv  # noqa: E402
import glob  # noqa: E402

import matplotlib  # noqa: E402
import matplotlib.ticker  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# Error levels of the ratio table (AMB_LEVELS="0.02 0.05" to choose others).
LEVELS = [float(x) for x in os.environ.get("AMB_LEVELS", "0.015 0.02 0.03 0.05 0.1 0.2").split()]
COLORS = {"rpict": "tab:blue", "tpict": "tab:orange"}


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    errcol = "err_avgref"
    if "--err" in sys.argv:
        errcol = sys.argv[sys.argv.index("--err") + 1]
        args = [a for a in args if a != errcol]
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = args[0] if args else os.path.join(root, "docs", "benchmarks", "ambient")
    rows = []
    for f in sorted(glob.glob(os.path.join(out, "runs*.tsv"))):
        with open(f) as fh:
            rows += list(csv.DictReader(fh, delimiter="\t"))
    if not rows:
        sys.exit(f"plot_ambient: no runs*.tsv in {out}")
    refnoise = {}
    for f in sorted(glob.glob(os.path.join(out, "references*.tsv"))):
        with open(f) as fh:
            for r in csv.DictReader(fh, delimiter="\t"):
                # Two independent references differ by sqrt(2) sigma; their average has
                # sigma / sqrt(2): about half their relative RMS difference.
                refnoise[(r["scene"], r["ab"])] = float(r["relrms_tpict_vs_rpict"]) / 2
    groups = {}
    for r in rows:
        groups.setdefault((r["scene"], r["ab"]), []).append(r)

    ratio_rows = []
    overlap_rows = []
    per_run_rows = []
    for (scene, ab), rs in sorted(groups.items()):
        fig, ax = plt.subplots(figsize=(5.2, 4.0), dpi=80)
        fronts = {}
        for ren in ("rpict", "tpict"):
            col = f"err_{ren}ref" if errcol == "own" else errcol
            pts = [(float(r["cpu_s"]), float(r[col]), f'{r["aa"]}/{r["ad"]}/{r["as"]}')
                   for r in rs if r["renderer"] == ren and float(r["cpu_s"]) > 0]
            if not pts:
                continue
            front = pareto(pts)
            fronts[ren] = front
            ax.scatter([p[0] for p in pts], [p[1] for p in pts], s=14, alpha=0.45,
                       color=COLORS[ren])
            ax.plot([p[0] for p in front], [p[1] for p in front], "-o", ms=4,
                    color=COLORS[ren], label=f"{ren} (Pareto front)")
        if (scene, ab) in refnoise:
            ax.axhline(refnoise[(scene, ab)], color="gray", ls="--", lw=1,
                       label="half the references' RMS difference")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel("CPU seconds (user+sys, 1 thread)")
        ax.set_ylabel("relative RMS error")
        ax.set_title(f"{scene}, -ab {ab}: error vs CPU time")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        png = os.path.join(out, f"error-vs-cpu-{scene}-ab{ab}.png")
        fig.savefig(png, dpi=80)
        plt.close(fig)
        print(f"plot_ambient: wrote {png}", file=sys.stderr)
        rf, tf = fronts.get("rpict", []), fronts.get("tpict", [])
        for lev in LEVELS:
            tr, tt = time_at(rf, lev), time_at(tf, lev)
            ratio_rows.append((scene, ab, lev, tr, tt, tr / tt if tr and tt else None))
        # Over the whole overlap of the two fronts' error ranges: 25 log-spaced levels.
        if rf and tf:
            hi = min(rf[0][1], tf[0][1])
            lo = max(rf[-1][1], tf[-1][1])
            if hi > lo:
                pairs = [(time_at(rf, e), time_at(tf, e)) for e in np.geomspace(lo, hi, 25)]
                dense = [a / b for a, b in pairs if a and b]
                if dense:
                    overlap_rows.append((scene, ab, lo, hi, min(dense), float(np.median(dense)),
                                         max(dense)))
        # Per rpict run (any setting of the grid, as a user might pick it): its CPU time over
        # the time tpict's front needs for its error (tpict's cheapest run when that is
        # already better).
        if rf and tf:
            per = []
            for r in rs:
                if r["renderer"] != "rpict":
                    continue
                col = "err_rpictref" if errcol == "own" else errcol
                e, t = float(r[col]), float(r["cpu_s"])
                tt = tf[0][0] if e > tf[0][1] else time_at(tf, e)
                if tt:
                    per.append(t / tt)
            if per:
                per_run_rows.append((scene, ab, len(per), min(per), float(np.median(per)),
                                     max(per), sum(x >= 4 for x in per) / len(per)))
        # At rpict's best (lowest) error on its front.
        if rf:
            lev = rf[-1][1]
            tr, tt = rf[-1][0], time_at(tf, lev)
            ratio_rows.append((scene, ab, f"rpict best {lev:.3f}", tr, tt, tr / tt if tt else None))

    fmt = lambda v: "—" if v is None else (f"{v:.2f}" if isinstance(v, float) else str(v))  # noqa: E731
    with open(os.path.join(out, "ratios.tsv"), "w") as fh:
        fh.write("scene\tab\terror\trpict_cpu_s\ttpict_cpu_s\trpict_over_tpict\n")
        for r in ratio_rows:
            fh.write("\t".join(fmt(v) for v in r) + "\n")
    # Markdown: one row per scene/ab, one column per error level.
    md = ["| scene | -ab | " + " | ".join(f"err {l:g}" for l in LEVELS) + " | at rpict's best error |",
          "|---|---|" + "---|" * (len(LEVELS) + 1)]
    for (scene, ab) in sorted(groups):
        cells = [fmt(r[5]) for r in ratio_rows if r[0] == scene and r[1] == ab and not isinstance(r[2], str)]
        best = [r for r in ratio_rows if r[0] == scene and r[1] == ab and isinstance(r[2], str)]
        b = f"{fmt(best[0][5])} ({best[0][2].split()[-1]})" if best else "—"
        md.append(f"| {scene} | {ab} | " + " | ".join(cells) + f" | {b} |")
    ratios = [r[5] for r in ratio_rows if r[5] and not isinstance(r[2], str)]
    if ratios:
        md.append("")
        md.append(f"Geometric mean over {len(ratios)} matched levels: "
                  f"{float(np.exp(np.mean(np.log(ratios)))):.2f} (min {min(ratios):.2f}, max {max(ratios):.2f}).")
    if overlap_rows:
        md += ["", "Over the overlap of both fronts (25 log-spaced error levels):", "",
               "| scene | -ab | errors | min | median | max |", "|---|---|---|---|---|---|"]
        for (scene, ab, lo, hi, mn, med, mx) in overlap_rows:
            md.append(f"| {scene} | {ab} | {lo:.3f}–{hi:.3f} | {mn:.2f} | {med:.2f} | {mx:.2f} |")
    if per_run_rows:
        md += ["", "Per rpict run (its CPU time over the time tpict's front needs for its error):", "",
               "| scene | -ab | rpict runs | min | median | max | share ≥ 4 |",
               "|---|---|---|---|---|---|---|"]
        for (scene, ab, n, mn, med, mx, share) in per_run_rows:
            md.append(f"| {scene} | {ab} | {n} | {mn:.2f} | {med:.2f} | {mx:.2f} | {share:.0%} |")
    with open(os.path.join(out, "ratios.md"), "w") as fh:
        fh.write("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
