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
# and times: oconv and obj2mesh (Radiance's build), tpict at 64×64 (the scene's load and
# build dominate), tpict and rpict at 512×512 -ab 0; tpict on one thread (-n 1) like rpict.
# CPU = user + system seconds; peak memory is /usr/bin/time's maximum resident set size.
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

measure() { # label command...
  local label=$1; shift
  /usr/bin/time -f "%e %U %S %M" -o time.txt "$@" > /dev/null 2> err.txt || { cat err.txt; exit 1; }
  read -r wall user sys kb < time.txt
  printf "%-40s wall %6.2f s  CPU %6.2f s  %6d MB\n" "$label" "$wall" \
    "$(echo "$user + $sys" | bc)" "$((kb / 1024))"
}
CITY="-vp 40 -30 40 -vd 0 1 -0.8 -vh 60 -vv 60"
TERR="-vp 10 -8 12 -vd 0 1 -0.9 -vh 70 -vv 60"
T1="$TPICT -n 1"
echo "piece.rad: $(grep -c . piece.rad) primitives; city: 256 instances (12.8 million surfaces)"
echo "grid.rtm: 1,008,200 triangles; terrain: 4 instances of it"
measure "oconv piece.rad" oconv piece.rad
measure "oconv city.rad" oconv city.rad
measure "tpict city.rad 64x64 (load+build)" $T1 $CITY -x 64 -y 64 -ab 0 city.rad
measure "rpict city.oct 64x64" rpict $CITY -x 64 -y 64 -ab 0 city.oct
measure "tpict city.rad 512x512 -ab 0" $T1 $CITY -x 512 -y 512 -ab 0 city.rad
measure "rpict city.oct 512x512 -ab 0" rpict $CITY -x 512 -y 512 -ab 0 city.oct
measure "obj2mesh grid.obj (1M triangles)" obj2mesh -a grid.mat grid.obj /dev/stdout
measure "tpict terrain.rad 64x64 (load+build)" $T1 $TERR -x 64 -y 64 -ab 0 terrain.rad
measure "rpict terrain.oct 64x64" rpict $TERR -x 64 -y 64 -ab 0 terrain.oct
measure "tpict terrain.rad 512x512 -ab 0" $T1 $TERR -x 512 -y 512 -ab 0 terrain.rad
measure "rpict terrain.oct 512x512 -ab 0" rpict $TERR -x 512 -y 512 -ab 0 terrain.oct
