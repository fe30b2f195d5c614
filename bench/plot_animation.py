"""Table and plot of bench/animation.sh's runs: per-frame CPU and new ambient values (the
seed paper's Fig. 10/11) for each accuracy mode, frame-time max/median, total CPU and the
error along the path (MID frames) and of the last frames.
Usage: plot_animation.py OUTDIR "name:options;..." "MID FRAMES" """
import json
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plotenv import ensure_deps  # noqa: E402

ensure_deps("plot_animation", ["matplotlib"])
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out, modes = sys.argv[1], [m.split(":", 1) for m in sys.argv[2].split(";")]
mid = {int(k) for k in sys.argv[3].split()} if len(sys.argv) > 3 else set()
rows = []
fig, (ax1, ax2, ax3) = plt.subplots(3, 1, figsize=(8, 9.5), sharex=True)
for name, opts in modes:
    d = json.load(open(os.path.join(out, f"{name}.json")))
    cpu = [f["cpu_seconds"] for f in d["frames"]]
    vals = [f["new_values"] for f in d["frames"]]
    errs = [(int(a), float(b)) for a, b in
            (l.split() for l in open(os.path.join(out, f"{name}-error.txt")))]
    err_mid = [e for k, e in errs if k in mid] or [float("nan")]
    ax3.plot([k for k, _ in sorted(errs)], [100 * e for _, e in sorted(errs)], label=name)
    err_last = [e for k, e in errs if k not in mid]
    med = statistics.median(cpu)
    rows.append((name, opts, sum(cpu), max(cpu), med, max(cpu) / med, sum(vals), max(vals),
                 statistics.mean(err_mid), statistics.mean(err_last)))
    ax1.plot(cpu, label=f"{name} ({opts})")
    ax2.plot(vals, label=name)
ax1.set_ylabel("CPU seconds per frame")
ax2.set_ylabel("new ambient values per frame")
ax3.set_ylabel("error vs a high-accuracy render, %")
ax3.set_xlabel("frame")
ax1.legend()
ax1.set_title("Walkthrough of the demo scene: frame cost with constant and time-varying -aa")
fig.tight_layout()
fig.savefig(os.path.join(out, "frames.png"), dpi=90)
hdr = ("| mode | options | total CPU s | max frame s | median frame s | max/median | "
       "new values | max per frame | error along the path | last frames' error |")
lines = [hdr, "|" + "---|" * 10]
for r in rows:
    lines.append(f"| {r[0]} | `{r[1]}` | {r[2]:.2f} | {r[3]:.3f} | {r[4]:.3f} | {r[5]:.1f} | "
                 f"{r[6]} | {r[7]} | {100 * r[8]:.2f}% | {100 * r[9]:.2f}% |")
text = "\n".join(lines)
open(os.path.join(out, "table.md"), "w").write(text + "\n")
print(text)
