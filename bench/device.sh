#!/usr/bin/env bash
# Issue 29's measurements on a node with 16 or more cores, as one prepared call: the daylit
# office of bench/realscenes.sh (gensky sun and sky through glazing, two ies2rad panels,
# desks, OBJ chairs, wood and plaster patterns) at `-ab 2 -aa .15 -ad 512 -as 128`, run by
# bench/scaling.sh for P = 1, 2, 4, 8, 16 (tpict -n 1 and -n P; the default plan by P
# single-thread workers with and without the scene image, and by one worker with P loops;
# the default configuration on `--tiles` plans), ending with the figures the issue asks for.
#
# Prepare (here, where Radiance and cargo are):
#   bash bench/device.sh --prepare DIR
# builds the office in DIR with the Radiance library files it reads (source.cal,
# skybright.cal), so that DIR renders without Radiance; the binaries come from
# target/release. Then, on the node (no cargo, no Radiance needed):
#   BIN=target/release bash bench/device.sh DIR [OUTDIR]
# which writes OUTDIR/scaling.txt (default DIR/out), the assembled pictures, costs.json and
# startup.txt for `cargo bench --bench tilesim -- OUTDIR/costs.json --sweep --startup S`,
# and OUTDIR/lookups.txt: the irradiance cache's lookups timed on 1, 2, 4, 8 and 16 threads
# at once (bench/lookups.rs on the office's own ambient file, which --prepare renders), what
# threads of one worker cost each other in the cache that processes do not (with
# --separate: a cache each, as processes have); OUTDIR/vistable.txt: the same for the
# shadow-reuse table (bench/vistable.rs); and
# OUTDIR/bands.txt: tpict at the default -ps 4 on 1 and on P threads (P = the cores, at
# most 16), where the band queue of src/render/schedule.rs decides how busy threads stay.
# Environment: RES (default "-x 1536 -y 1536": 1536x1064, 14.5 CPU-s a frame on one core
# here; about 4 minutes for everything on 16 cores), WORKERS (default "1 2 4 8 16", cut to
# the cores), TILES_LIST and PMAX_REPEAT (bench/scaling.sh).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)

if [ "${1:-}" = --prepare ]; then
    [ -n "${2:-}" ] || { echo "usage: bash bench/device.sh --prepare DIR" >&2; exit 2; }
    mkdir -p "$2"
    dir=$(cd "$2" && pwd)
    KEEP="$dir" BUILD_ONLY=1 SCENES=office bash "$ROOT/bench/realscenes.sh"
    for f in source.cal skybright.cal; do
        found=""
        IFS=: read -ra paths <<< "${RAYPATH:-}"
        for p in "${paths[@]}"; do
            if [ -n "$p" ] && [ -f "$p/$f" ]; then
                found="$p/$f"
                break
            fi
        done
        [ -n "$found" ] || { echo "bench/device.sh: $f not found along RAYPATH" >&2; exit 1; }
        cp "$found" "$dir/"
    done
    # The cache-contention probe: bench/lookups.rs's binary and an ambient file of the office.
    # The shadow-reuse table's probe: bench/vistable.rs's binary.
    (cd "$ROOT" && cargo build --release --quiet --bench lookups --bench vistable)
    for b in lookups vistable; do
        f=$(ls -t "$ROOT"/target/release/deps/$b-* 2>/dev/null | grep -v '\.d$' | head -1)
        [ -n "$f" ] || { echo "bench/device.sh: the $b bench binary was not found" >&2; exit 1; }
        strip -o "$dir/$b" "$f" 2>/dev/null || cp "$f" "$dir/$b"
    done
    (cd "$dir" && RAYPATH="$dir:${RAYPATH:-.}" "$ROOT/target/release/tpict" $(cat office.view) \
        -x 256 -y 256 -ab 2 -aa .15 -ad 512 -as 128 -ar 64 -dt .07 -ps 1 -af office.amb \
        office.rad >/dev/null)
    echo "bench/device.sh: prepared $dir (office.rad, office.view and what they read, lookups, vistable, office.amb)"
    exit 0
fi

[ -n "${1:-}" ] && [ -f "$1/office.rad" ] || {
    echo "usage: BIN=DIR bash bench/device.sh SCENEDIR [OUTDIR] (prepare SCENEDIR with --prepare)" >&2
    exit 2
}
dir=$(cd "$1" && pwd)
OUT=${2:-$dir/out}
mkdir -p "$OUT"
BIN=$(cd "${BIN:-$ROOT/target/release}" && pwd)
{
    echo "bench/device.sh on $(hostname): $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
    cd "$dir"
    RAYPATH="$dir:${RAYPATH:-.}" NO_BUILD=1 NO_SIM=1 BIN="$BIN" SCENE="$dir/office.rad" \
        VIEW="$(cat "$dir/office.view")" RES="${RES:--x 1536 -y 1536}" \
        OPTS="-ab 2 -aa .15 -ad 512 -as 128 -ar 64 -dt .07 -ps 1" \
        bash "$ROOT/bench/scaling.sh" "$OUT"
} 2>&1 | tee "$OUT/scaling.txt"
if [ -x "$dir/lookups" ] && [ -f "$dir/office.amb" ]; then
    {
        echo "lookups on the office's ambient file, T threads at once (ns a lookup, wall / lookups each):"
        for t in 1 2 4 8 16; do
            [ "$t" -le "$(nproc)" ] || continue
            "$dir/lookups" "$dir/office.amb" --threads "$t" --lookups 1000000
            "$dir/lookups" "$dir/office.amb" --threads "$t" --lookups 1000000 --separate
        done
    } 2>&1 | tee "$OUT/lookups.txt"
fi
if [ -x "$dir/vistable" ]; then
    {
        echo "shadow-reuse queries, T threads at once, one table or a table each (ns a query):"
        for t in 1 2 4 8 16; do
            [ "$t" -le "$(nproc)" ] || continue
            "$dir/vistable" --threads "$t" --queries 1000000
            "$dir/vistable" --threads "$t" --queries 1000000 --separate
        done
    } 2>&1 | tee "$OUT/vistable.txt"
fi
{
    P=$(nproc)
    [ "$P" -le 16 ] || P=16
    echo "tpict -ps 4 (the default), office -ab 2 -aa .15 -ad 512 -as 128, 768x532: wall s"
    for n in 1 "$P"; do
        t0=$(date +%s.%N)
        (cd "$dir" && RAYPATH="$dir:${RAYPATH:-.}" "$BIN/tpict" $(cat office.view) -x 768 -y 768 \
            -ab 2 -aa .15 -ad 512 -as 128 -ar 64 -dt .07 -n "$n" office.rad >"$OUT/bands-n$n.hdr")
        t1=$(date +%s.%N)
        echo "-n $n: $(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }') s"
    done
} 2>&1 | tee "$OUT/bands.txt"
