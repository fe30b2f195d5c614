"""Speed against error: each renderer's Pareto front and the CPU time at which it reaches
an error, shared by bench/plot_ambient.py (pictures) and bench/points.sh (sensor grids).
Plain Python (no numpy), so the shell benches can use it without a venv."""
import math


def pareto(points):
    """points: list of (cpu, err, ...). Returns the front (the runs no cheaper run beats in
    error) sorted by cpu ascending."""
    front = []
    best = float("inf")
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def time_at(front, err):
    """CPU time at which the front reaches `err` (interpolated linearly in log CPU and log
    error between the two front points around it), or None outside the front's errors."""
    if not front:
        return None
    errs = [p[1] for p in front]
    if err > errs[0] or err < errs[-1]:
        return None
    for a, b in zip(front, front[1:]):
        if b[1] <= err <= a[1]:
            if a[1] == b[1]:
                return a[0]
            t = (math.log(err) - math.log(a[1])) / (math.log(b[1]) - math.log(a[1]))
            return math.exp(math.log(a[0]) + t * (math.log(b[0]) - math.log(a[0])))
    return front[0][0] if err == errs[0] else None
