#!/usr/bin/env python3
"""Plot bench/batch.sh results (the seed paper's Fig. 6, 7 and 8 on this machine).

Reads RESULTS_DIR/runs.tsv and writes
  workers.png   aggregate CPU time, T_spec/T_amb/T_idle and extensive ambient computations
                against the number of workers (Fig. 7/8)
  amb-flush.png CPU time and extensive ambient computations against N_A at 16 workers (Fig. 6)
  summary.md    the same numbers as tables, with ratios to one worker
Usage: python3 bench/plot_batch.py [RESULTS_DIR (default docs/benchmarks/batch)]
Installs matplotlib into a venv ($TESSERA_VENV, default ~/.cache/tessera-bench-venv) when
the running Python lacks it.
"""
import csv
import os
import sys
from collections import defaultdict

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plotenv import ensure_deps  # noqa: E402

ensure_deps("plot_batch", ["matplotlib"])
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "docs/benchmarks/batch"
rows = list(csv.DictReader(open(os.path.join(out, "runs.tsv")), delimiter="\t"))
num = ["workers", "wall_s", "cpu_s", "new_values", "shared_in", "t_spec", "t_amb", "t_idle", "t_sync"]
for r in rows:
    for k in num:
        r[k] = float(r[k])


def mean_by(rs, key):
    g = defaultdict(list)
    for r in rs:
        g[r[key]].append(r)
    res = {}
    for k, lst in g.items():
        res[k] = {f: sum(x[f] for x in lst) / len(lst) for f in num}
        res[k]["n"] = len(lst)
    return res


wk = mean_by([r for r in rows if r["name"].startswith("workers-")], "workers")
na = mean_by([r for r in rows if r["name"].startswith("na-")], "amb_flush")
lines = []
if wk:
    xs = sorted(wk)
    base = wk[xs[0]]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    a1.stackplot(xs, [wk[x]["t_spec"] for x in xs], [wk[x]["t_amb"] for x in xs],
                 [wk[x]["t_idle"] for x in xs], labels=["ΣT_spec", "ΣT_amb", "ΣT_idle"], alpha=0.7)
    a1.plot(xs, [wk[x]["cpu_s"] for x in xs], "k-o", label="Σ CPU time")
    a1.set_xscale("log", base=2)
    a1.set_xlabel("workers (time-sharing 2 cores)")
    a1.set_ylabel("seconds (aggregated over workers)")
    a1.set_title("Aggregated times (seed Fig. 7)")
    a1.legend(fontsize=8)
    a2.plot(xs, [wk[x]["new_values"] for x in xs], "r-o", label="extensive ambient computations")
    a2.set_xscale("log", base=2)
    a2.set_xlabel("workers")
    a2.set_ylabel("new ambient values")
    a2.set_ylim(0, max(wk[x]["new_values"] for x in xs) * 1.15)
    a2b = a2.twinx()
    a2b.plot(xs, [wk[x]["cpu_s"] for x in xs], "k--s", label="Σ CPU time")
    a2b.set_ylabel("Σ CPU seconds")
    a2b.set_ylim(0, max(wk[x]["cpu_s"] for x in xs) * 1.15)
    a2.set_title("Extensive computations and CPU (seed Fig. 8)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "workers.png"), dpi=110)
    lines += ["| workers | wall s | Σ CPU s | CPU ×1 | new values | ×1 | shared in | ΣT_spec | ΣT_amb | ΣT_idle | ΣT_sync |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for x in xs:
        w = wk[x]
        lines.append(f"| {int(x)} | {w['wall_s']:.1f} | {w['cpu_s']:.1f} | {w['cpu_s'] / base['cpu_s']:.3f} | "
                     f"{w['new_values']:.0f} | {w['new_values'] / base['new_values']:.3f} | {w['shared_in']:.0f} | "
                     f"{w['t_spec']:.1f} | {w['t_amb']:.1f} | {w['t_idle']:.1f} | {w['t_sync']:.2f} |")
    lines.append("")
if na:
    order = sorted(na, key=lambda k: (k == "auto", float(k) if k != "auto" else 0))
    fig, ax = plt.subplots(figsize=(6, 4.2))
    pos = list(range(len(order)))
    ax.bar([p - 0.2 for p in pos], [na[k]["new_values"] for k in order], 0.4, color="tab:red",
           label="new ambient values")
    ax.set_ylabel("extensive ambient computations")
    ax2 = ax.twinx()
    ax2.bar([p + 0.2 for p in pos], [na[k]["cpu_s"] for k in order], 0.4, color="tab:gray", label="Σ CPU s")
    ax2.set_ylabel("Σ CPU seconds")
    ax.set_xticks(pos)
    ax.set_xticklabels(order)
    ax.set_xlabel("N_A (--amb-flush)")
    ax.set_title(f"N_A sweep at {int(na[order[0]]['workers'])} workers (seed Fig. 6)")
    fig.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "amb-flush.png"), dpi=110)
    ref = wk[min(wk)] if wk else None
    lines += ["| N_A | wall s | Σ CPU s | new values | × one worker | shared in | ΣT_sync |", "|---|---|---|---|---|---|---|"]
    for k in order:
        w = na[k]
        ratio = f"{w['new_values'] / ref['new_values']:.3f}" if ref else "–"
        lines.append(f"| {k} | {w['wall_s']:.1f} | {w['cpu_s']:.1f} | {w['new_values']:.0f} | {ratio} | "
                     f"{w['shared_in']:.0f} | {w['t_sync']:.2f} |")
open(os.path.join(out, "summary.md"), "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
