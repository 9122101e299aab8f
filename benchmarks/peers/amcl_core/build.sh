#!/usr/bin/env bash
# Build the peer of benchmarks/bench_amcl.py: the unmodified ROS 1 noetic amcl core
# (ros-planning/navigation, noetic-devel, amcl/src/amcl and amcl/include) with driver.cpp,
# which reads bench_amcl's problem file and mirrors amcl_node.cpp's scan handling.
# The core is not part of symloc: fetch it yourself, e.g. from a clone of
# https://github.com/ros-planning/navigation (branch noetic-devel).
#
# usage: benchmarks/peers/amcl_core/build.sh NAVIGATION/amcl OUT_DIR
#   then: python benchmarks/bench_amcl.py --carmen ../shared/data/carmen --large \
#         --peer OUT_DIR/amcl_driver
#
# FAIR=1 builds bench_amcl's --peer-fair instead: the same core with fair_resampler.patch
# applied to a copy of its source in OUT_DIR/amcl-fair (pf.c's resampler finds each sample by
# binary search in the cumulative weights instead of its linear scan: the same samples, in
# O(N log N)), e.g. build.sh NAVIGATION/amcl OUT_FAIR; bench_amcl.py --peer-fair
# OUT_FAIR/amcl_driver. OUT_DIR/SOURCE.txt says what was built (bench_amcl's results file
# quotes it).
set -euo pipefail
AMCL=${1:?the amcl package folder of a navigation checkout}
OUT=${2:?output folder}
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
AMCL=$(cd "$AMCL" && pwd)
VERSION=$(sed -n 's:.*<version>\(.*\)</version>.*:\1:p' "$AMCL/package.xml" 2>/dev/null | head -n 1)
cd "$OUT"
if [ "${FAIR:-0}" = 1 ]; then
  rm -rf amcl-fair
  mkdir amcl-fair
  cp -r "$AMCL/include" "$AMCL/src" amcl-fair/
  patch -p1 -d amcl-fair < "$HERE/fair_resampler.patch"
  AMCL="$PWD/amcl-fair"
fi
SRC="$AMCL/src/amcl"
FLAGS=(-O2 -DNDEBUG -DHAVE_DRAND48 -I"$AMCL/include" -I"$AMCL/src/include")
for f in map/map.c map/map_range.c pf/pf.c pf/pf_kdtree.c pf/pf_pdf.c pf/pf_vector.c pf/eig3.c; do
  cc "${FLAGS[@]}" -c "$SRC/$f" -o "$(basename "${f%.c}").o"
done
for f in map/map_cspace.cpp sensors/amcl_sensor.cpp sensors/amcl_laser.cpp sensors/amcl_odom.cpp; do
  c++ "${FLAGS[@]}" -c "$SRC/$f" -o "$(basename "${f%.cpp}").o"
done
c++ "${FLAGS[@]}" "$HERE/driver.cpp" ./*.o -o amcl_driver -lm
# what was built, for bench_amcl's results file
WHAT="ROS 1 amcl ${VERSION:-version unknown} core"
[ "${FAIR:-0}" = 1 ] && WHAT="$WHAT with fair_resampler.patch"
echo "$WHAT (benchmarks/peers/amcl_core/build.sh)" > SOURCE.txt
echo "built $OUT/amcl_driver"
