#!/usr/bin/env bash
# What a batch job costs against the single render it replaces (docs/benchmarks.md, "Job
# cost"): for each resolution and -ab, the CPU (user+sys, all processes) and rays of
#   - one `tpict -n 1` render;
#   - the default plan for 16 workers (`tplan --workers 16`) rendered by 1 worker (`--threads 1`);
#   - the same plan rendered by 16 workers at once (1 thread each, time-sharing the cores);
# and tassemble's CPU (writing the picture, which tpict's CPU includes), the workers' summed
# T_idle with N workers (time-sharing the cores inflates it), and the per-tile overhead: the
# CPU of one worker on a plan of 32x32 tiles minus that on a plan of one tile, per extra
# tile, at -ab 0 (every pixel costs the same in both plans: the tiles lie on the -ps grid,
# so the rays are equal).
# Ratios are the job's median CPU (workers only) over tpict's. Every figure is the median of
# REPEAT runs, with the spread (min-max) in brackets.
# Scene: tests/scenes/daffodil (58 surfaces: genrev/genworm flowers in a room, two panels).
# Usage: bash bench/jobcost.sh   (environment: RES="1024 512", AB="0 1", REPEAT=3, WORKERS=16,
#        NO_BUILD=1 to skip the build; binaries from $CARGO_TARGET_DIR or target/)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
RES=${RES:-"1024 512"}
AB=${AB:-"0 1"}
REPEAT=${REPEAT:-3}
WORKERS=${WORKERS:-16}
[[ -n "${NO_BUILD:-}" ]] || (cd "$ROOT" && cargo build --release --quiet --bins)
B=${CARGO_TARGET_DIR:-$ROOT/target}/release
D=$ROOT/tests/scenes/daffodil
SCENE=("$D/daffodil.flat.rad" "$D/room.flat.rad")
VIEW=(-vp 50 60 40 -vd 0 -0.707107 -0.707107 -vu 0 1 0 -vh 20 -vv 20 -av .2 .2 .2)
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# cputime N CMD...: run N copies of CMD at once ("{i}" in an argument becomes 1..N; stdout
# to /dev/null, stderr to $TMP/err) and print their summed user+sys CPU seconds, from
# wait4's rusage (microseconds; /usr/bin/time rounds each process to 10 ms)
cputime() {
    python3 - "$TMP/err" "$@" <<'PY'
import os, subprocess, sys
err, n, cmd = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
with open(os.devnull, "wb") as null, open(err, "ab") as e:
    procs = [subprocess.Popen([a.replace("{i}", str(i + 1)) for a in cmd], stdout=null, stderr=e)
             for i in range(n)]
    total = 0.0
    for p in procs:
        _, status, ru = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
        if p.returncode != 0:
            sys.exit(f"{cmd[0]} failed ({p.returncode}); see {err}")
        total += ru.ru_utime + ru.ru_stime
print(f"{total:.4f}")
PY
}
# stats FIGURES...: "median [min-max]"
stats() { printf '%s\n' "$@" | sort -g | awk -v f="${FMT:-%.3f}" '{v[NR] = $1} END {printf f " [" f "-" f "]", v[int((NR + 1) / 2)], v[1], v[NR]}'; }
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
# job_rays JOB: rays summed over the tile results
job_rays() { "$B/tstat" "$1" --json | python3 -c 'import json,sys; print(json.load(sys.stdin)["aggregate"]["rays"])'; }
job_idle() { "$B/tstat" "$1" --json | python3 -c 'import json,sys; print(round(json.load(sys.stdin)["aggregate"]["t_idle"], 3))'; }
plan() { "$B/tplan" "$@" 2>&1 >/dev/null | sed -n 's/.* \([0-9]*\) tiles,.*/\1/p'; }

# run_workers JOB N: N workers at once (one thread each); prints their summed CPU seconds
run_workers() { cputime "$2" "$B/tpiece" "$1" --worker-id "w{i}" --threads 1 -q; }

printf '%-6s %-3s %-22s %-10s %-22s %-22s %-7s %-7s %-10s %-6s %-22s %s\n' res ab "tpict CPU s" "rays" \
    "1 worker CPU s" "${WORKERS} workers CPU s" "ratio1" "ratioN" "rays/tpict" tiles "tassemble CPU s" "ΣT_idle s (N workers)"
for res in $RES; do
    for ab in $AB; do
        one=() w1=() wn=() idle=() asm=()
        for r in $(seq 1 "$REPEAT"); do
            one+=("$(cputime 1 "$B/tpict" -n 1 "${VIEW[@]}" -x "$res" -y "$res" -ab "$ab" \
                --stats "$TMP/st.json" "${SCENE[@]}")")
            rays=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["total_rays"])' "$TMP/st.json")
            rm -rf "$TMP/job"
            tiles=$(plan --workers "$WORKERS" -o "$TMP/job" -- "${VIEW[@]}" -x "$res" -y "$res" -ab "$ab" "${SCENE[@]}")
            w1+=("$(run_workers "$TMP/job" 1)")
            jrays=$(job_rays "$TMP/job")
            rm -rf "$TMP/job"
            plan --workers "$WORKERS" -o "$TMP/job" -- "${VIEW[@]}" -x "$res" -y "$res" -ab "$ab" "${SCENE[@]}" >/dev/null
            wn+=("$(run_workers "$TMP/job" "$WORKERS")")
            idle+=("$(job_idle "$TMP/job")")
            asm+=("$(cputime 1 "$B/tassemble" "$TMP/job" --force -o "$TMP/out.hdr")")
        done
        m1=$(median "${one[@]}")
        printf '%-6s %-3s %-22s %-10s %-22s %-22s %-7s %-7s %-10s %-6s %-22s %s\n' "${res}²" "$ab" "$(stats "${one[@]}")" "$rays" \
            "$(stats "${w1[@]}")" "$(stats "${wn[@]}")" \
            "$(awk -v a="$(median "${w1[@]}")" -v b="$m1" 'BEGIN {printf "%.3f", a / b}')" \
            "$(awk -v a="$(median "${wn[@]}")" -v b="$m1" 'BEGIN {printf "%.3f", a / b}')" \
            "$(awk -v a="$jrays" -v b="$rays" 'BEGIN {printf "%.4f", a / b}')" "$tiles" "$(stats "${asm[@]}")" \
            "$(stats "${idle[@]}")"
    done
done

# The per-tile overhead at -ab 0, 1024x1024: 32x32 tiles against one tile, one worker.
many=() single=()
for r in $(seq 1 "$REPEAT"); do
    rm -rf "$TMP/job"
    n=$(plan --tile-size 32x32 -o "$TMP/job" -- "${VIEW[@]}" -x 1024 -y 1024 -ab 0 "${SCENE[@]}")
    many+=("$(run_workers "$TMP/job" 1)")
    rm -rf "$TMP/job"
    plan --tiles 1 -o "$TMP/job" -- "${VIEW[@]}" -x 1024 -y 1024 -ab 0 "${SCENE[@]}" >/dev/null
    single+=("$(run_workers "$TMP/job" 1)")
done
per=()
for i in "${!many[@]}"; do
    per+=("$(awk -v a="${many[$i]}" -v b="${single[$i]}" -v n="$n" 'BEGIN {printf "%.6f", (a - b) / (n - 1)}')")
done
echo "per-tile overhead (-ab 0, 1024², $n tiles of 32x32 vs 1 tile, 1 worker): $(FMT=%.5f stats "${per[@]}") s per tile;" \
    "CPU $(stats "${many[@]}") s vs $(stats "${single[@]}") s"
