#!/bin/bash
# Load, build and render times and peak memory of instanced scenes, tpict against
# oconv + rpict (docs/benchmarks.md, "Instances and meshes").
#
#   bench/instances.sh [WORKDIR]
#
# Makes (with awk, oconv and obj2mesh):
#   piece.oct  50,000 surfaces (polygons and spheres), unfrozen
#   city.rad   a floor, a light and 16×16 = 256 instances of piece.oct (12.8 million
#              surfaces once expanded)
#   grid.rtm   a 710×710 height field of 1,008,200 triangles with normals and (u,v)
#   terrain.rad  4 instances of the mesh (one file, built once)
# and times: oconv and obj2mesh (Radiance's build), tpict and rpict at 64×64 (the scene's
# load and build dominate), at 512×512 -ab 0, and at -ab 1 (-aa .2 -ad 256 -as 64 -ar 32;
# the city at 128×128, the terrain at 256×256); tpict on one thread (-n 1) like rpict.
# Each is run REPS times (default 3): the median CPU (user + system seconds) with its range,
# and the largest peak memory (/usr/bin/time's maximum resident set size). Render CPU is a
# run's CPU minus the same renderer's 64×64 run.
# Radiance is found as the tests find it (bench/common.sh); tpict is built unless
# NO_BUILD=1 or TPICT=path.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
NAME=instances
source "$ROOT/bench/common.sh"
W=${1:-/tmp/tessera-bench-instances}
mkdir -p "$W"
cd "$W"

if [ ! -f piece.oct ]; then
  awk 'BEGIN {
    srand(7);
    print "void plastic pm 0 0 5 .6 .5 .4 .02 .05";
    print "void plastic pb 0 0 5 .2 .3 .6 0 0";
    for (i = 0; i < 25000; i++) {
      x = rand() * 4; y = rand() * 4; z = rand() * 2; s = 0.01 + rand() * 0.04;
      printf "pm polygon q%d 0 0 12 %g %g %g %g %g %g %g %g %g %g %g %g\n", i,
        x, y, z, x + s, y, z, x + s, y + s, z + s, x, y + s, z + s;
      printf "pb sphere s%d 0 0 4 %g %g %g %g\n", i, 4 - x, 4 - y, z, s / 2;
    }
  }' > piece.rad
  oconv piece.rad > piece.oct
fi
if [ ! -f city.rad ]; then
  {
    echo "void light sun 0 0 3 1e3 1e3 1e3"
    echo "sun source s 0 0 4 .3 .4 1 2"
    echo "void plastic ground 0 0 5 .4 .4 .4 0 0"
    echo "ground polygon floor 0 0 12 -1 -1 0 81 -1 0 81 81 0 -1 81 0"
    for i in $(seq 0 15); do for j in $(seq 0 15); do
      echo "void instance p$i.$j 7 piece.oct -rz $(( (i * 37 + j * 11) % 360 )) -t $((i * 5 + 2)) $((j * 5 + 2)) 0 0 0"
    done; done
  } > city.rad
  oconv city.rad > city.oct
fi
if [ ! -f grid.rtm ]; then
  awk 'BEGIN {
    n = 710;
    for (j = 0; j <= n; j++) for (i = 0; i <= n; i++) {
      x = i / n * 10; y = j / n * 10; z = 0.5 * sin(x * 1.3) * cos(y * 0.9);
      nx = -0.5 * 1.3 * cos(x * 1.3) * cos(y * 0.9); ny = 0.5 * 0.9 * sin(x * 1.3) * sin(y * 0.9);
      printf "v %g %g %g\nvn %g %g 1\nvt %g %g\n", x, y, z, -nx, -ny, i / n, j / n;
    }
    print "usemtl terrain";
    for (j = 0; j < n; j++) for (i = 0; i < n; i++) {
      a = j * (n + 1) + i + 1; b = a + 1; c = a + n + 2; d = a + n + 1;
      printf "f %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, b, b, b, c, c, c;
      printf "f %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, c, c, c, d, d, d;
    }
  }' > grid.obj
  echo "void plastic terrain 0 0 5 .5 .6 .4 0 0" > grid.mat
  obj2mesh -a grid.mat grid.obj grid.rtm
fi
cat > terrain.rad <<'T'
void light sun 0 0 3 1e3 1e3 1e3
sun source s 0 0 4 .3 .4 1 2
void mesh t1 1 grid.rtm 0 0
void mesh t2 5 grid.rtm -t 10 0 0 0 0
void mesh t3 5 grid.rtm -t 0 10 0 0 0
void mesh t4 5 grid.rtm -t 10 10 0 0 0
T
oconv terrain.rad > terrain.oct

REPS=${REPS:-3}
# measure KEY LABEL command...: run REPS times; print the median CPU (user + system) with its
# range and the largest peak resident set size; keep the median CPU in CPU_<KEY>.
measure() {
  local key=$1 label=$2; shift 2
  local cpus=() kbs=()
  for _ in $(seq "$REPS"); do
    /usr/bin/time -f "%U %S %M" -o time.txt "$@" > /dev/null 2> err.txt || { cat err.txt; exit 1; }
    read -r user sys kb < time.txt
    cpus+=("$(echo "$user + $sys" | bc)")
    kbs+=("$kb")
  done
  local sorted med lo hi mb
  sorted=$(printf "%s\n" "${cpus[@]}" | sort -g)
  med=$(echo "$sorted" | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}')
  lo=$(echo "$sorted" | head -1)
  hi=$(echo "$sorted" | tail -1)
  mb=$(( $(printf "%s\n" "${kbs[@]}" | sort -n | tail -1) / 1024 ))
  printf "%-44s CPU %6.2f s (%5.2f-%5.2f)  %5d MB\n" "$label" "$med" "$lo" "$hi" "$mb"
  printf -v "CPU_$key" "%s" "$med"
}
# render LABEL KEY BASEKEY: render CPU = CPU_KEY - CPU_BASEKEY (the same scene's load).
render() {
  printf "  render CPU %-31s %6.2f s\n" "$1" "$(echo "${!2} - ${!3}" | bc)"
}
CITY="-vp 40 -30 40 -vd 0 1 -0.8 -vh 60 -vv 60"
TERR="-vp 10 -8 12 -vd 0 1 -0.9 -vh 70 -vv 60"
AB1="-ab 1 -aa .2 -ad 256 -as 64 -ar 32"
T1="$TPICT -n 1"
echo "piece.rad: $(grep -c . piece.rad) primitives; city: 256 instances (12.8 million surfaces)"
echo "grid.rtm: 1,008,200 triangles; terrain: 4 instances of it"
echo "median of $REPS runs (range); peak memory: the largest maximum resident set size"
measure oc "oconv piece.rad" oconv piece.rad
measure occ "oconv city.rad" oconv city.rad
measure tc64 "tpict city.rad 64x64 (load+build)" $T1 $CITY -x 64 -y 64 -ab 0 city.rad
measure rc64 "rpict city.oct 64x64" rpict $CITY -x 64 -y 64 -ab 0 city.oct
measure tc0 "tpict city.rad 512x512 -ab 0" $T1 $CITY -x 512 -y 512 -ab 0 city.rad
measure rc0 "rpict city.oct 512x512 -ab 0" rpict $CITY -x 512 -y 512 -ab 0 city.oct
measure tc1 "tpict city.rad 128x128 -ab 1" $T1 $CITY -x 128 -y 128 $AB1 city.rad
measure rc1 "rpict city.oct 128x128 -ab 1" rpict $CITY -x 128 -y 128 $AB1 city.oct
measure om "obj2mesh grid.obj (1M triangles)" obj2mesh -a grid.mat grid.obj /dev/stdout
measure tt64 "tpict terrain.rad 64x64 (load+build)" $T1 $TERR -x 64 -y 64 -ab 0 terrain.rad
measure rt64 "rpict terrain.oct 64x64" rpict $TERR -x 64 -y 64 -ab 0 terrain.oct
measure tt0 "tpict terrain.rad 512x512 -ab 0" $T1 $TERR -x 512 -y 512 -ab 0 terrain.rad
measure rt0 "rpict terrain.oct 512x512 -ab 0" rpict $TERR -x 512 -y 512 -ab 0 terrain.oct
measure tt1 "tpict terrain.rad 256x256 -ab 1" $T1 $TERR -x 256 -y 256 $AB1 terrain.rad
measure rt1 "rpict terrain.oct 256x256 -ab 1" rpict $TERR -x 256 -y 256 $AB1 terrain.oct
echo "render CPU: a run's median CPU minus the same renderer's 64x64 run (the load)"
render "tpict city -ab 0" CPU_tc0 CPU_tc64
render "rpict city -ab 0" CPU_rc0 CPU_rc64
render "tpict city -ab 1" CPU_tc1 CPU_tc64
render "rpict city -ab 1" CPU_rc1 CPU_rc64
render "tpict terrain -ab 0" CPU_tt0 CPU_tt64
render "rpict terrain -ab 0" CPU_rt0 CPU_rt64
render "tpict terrain -ab 1" CPU_tt1 CPU_tt64
render "rpict terrain -ab 1" CPU_rt1 CPU_rt64
