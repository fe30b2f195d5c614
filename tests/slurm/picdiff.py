#!/usr/bin/env python3
"""Compare two Radiance pictures with the tolerance of Tessera's tests (tests/common/mod.rs).

    picdiff.py TEST.hdr REFERENCE.hdr [--size WxH]

Both pictures must have the same resolution. Each is reduced with
`pfilt -1 -r 1 -x W -y H -pa 1` (default: half the resolution, as the tests reduce
256x256 to 128x128) and read back with `pvalue -o -h -H -d`. Per pixel, the channel mean and
the largest channel give relative differences (a-b)^2 / (1/4 (a^2 + 2|ab| + b^2)), the
denominator floored at 0.007^2 (radcompare -rel). Passes when relative RMS <= 0.10, max
<= 1.5 and the mean luminance differs by <= 2%. Exit 0 = pass, 1 = fail, 2 = usage/tool error.
Needs getinfo, pfilt and pvalue on PATH (Radiance); no numpy.
"""

import math
import subprocess
import sys

REL = 0.007
LIMIT_RMS = 0.10
LIMIT_MAX = 1.50
LIMIT_MEAN = 0.02


def fail_usage(msg):
    print(f"picdiff: error: {msg}", file=sys.stderr)
    sys.exit(2)


def run(cmd, stdin=None):
    try:
        p = subprocess.run(cmd, input=stdin, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    except FileNotFoundError:
        fail_usage(f"{cmd[0]} not found on PATH (Radiance's binaries are needed)")
    if p.returncode != 0:
        fail_usage(f"{' '.join(cmd)} failed: {p.stderr.decode(errors='replace').strip()}")
    return p.stdout


def resolution(path):
    """(width, height) from `getinfo -d`: 'file: -Y 110 +X 160'."""
    words = run(["getinfo", "-d", path]).decode().split()
    dims = {}
    for flag, val in zip(words, words[1:]):
        if flag[-1:] in ("X", "Y") and flag[:1] in ("+", "-") and val.isdigit():
            dims[flag[-1]] = int(val)
    if "X" not in dims or "Y" not in dims:
        fail_usage(f"cannot read the resolution of {path}: {' '.join(words)}")
    return dims["X"], dims["Y"]


def reduced_pixels(path, w, h):
    small = run(["pfilt", "-1", "-r", "1", "-x", str(w), "-y", str(h), "-pa", "1", path])
    text = run(["pvalue", "-o", "-h", "-H", "-d"], stdin=small).decode()
    vals = [float(v) for v in text.split()]
    if len(vals) % 3:
        fail_usage(f"pvalue gave {len(vals)} numbers for {path}, not RGB triples")
    return [tuple(vals[i : i + 3]) for i in range(0, len(vals), 3)]


def lum(p):
    return 0.265074126 * p[0] + 0.670114631 * p[1] + 0.064811243 * p[2]


def compare(a, b, rel):
    def rd2(x, y):
        den = max(0.25 * (x * x + 2.0 * abs(x * y) + y * y), rel * rel)
        return (x - y) * (x - y) / den

    total = 0.0
    n = 0
    worst = 0.0
    for p, q in zip(a, b):
        for d2 in (rd2(sum(p) / 3.0, sum(q) / 3.0), rd2(max(p), max(q))):
            total += d2
            n += 1
            worst = max(worst, math.sqrt(d2))
    la = sum(lum(p) for p in a) / len(a)
    lb = sum(lum(q) for q in b) / len(b)
    return math.sqrt(total / n), worst, abs(la - lb) / max(abs(lb), 1e-12), la, lb


def main(argv):
    args = list(argv)
    size = None
    if "--size" in args:
        i = args.index("--size")
        if i + 1 >= len(args):
            fail_usage("--size needs WxH")
        try:
            w, h = (int(v) for v in args[i + 1].lower().split("x"))
        except ValueError:
            fail_usage(f"--size needs WxH, not {args[i + 1]}")
        size = (w, h)
        del args[i : i + 2]
    if len(args) != 2:
        fail_usage("usage: picdiff.py TEST.hdr REFERENCE.hdr [--size WxH]")
    test, ref = args
    rt, rr = resolution(test), resolution(ref)
    if rt != rr:
        print(f"picdiff: FAIL: resolution differs: {test} is {rt[0]}x{rt[1]}, {ref} is {rr[0]}x{rr[1]}")
        return 1
    w, h = size or (max(1, rt[0] // 2), max(1, rt[1] // 2))
    a = reduced_pixels(test, w, h)
    b = reduced_pixels(ref, w, h)
    if len(a) != len(b) or not a:
        fail_usage(f"reduced pictures differ in size ({len(a)} and {len(b)} pixels)")
    rms, worst, mean, la, lb = compare(a, b, REL)
    ok = rms <= LIMIT_RMS and worst <= LIMIT_MAX and mean <= LIMIT_MEAN
    print(
        f"picdiff: {rt[0]}x{rt[1]} reduced to {w}x{h}: relative RMS {rms:.4f} (limit {LIMIT_RMS}),"
        f" max {worst:.3f} (limit {LIMIT_MAX}), mean luminance {la:.5g} vs {lb:.5g}:"
        f" {100 * mean:.2f}% (limit {100 * LIMIT_MEAN:.0f}%) -> {'pass' if ok else 'FAIL'}"
    )
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
