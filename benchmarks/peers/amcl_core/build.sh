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
set -euo pipefail
AMCL=${1:?the amcl package folder of a navigation checkout}
OUT=${2:?output folder}
HERE=$(cd "$(dirname "$0")" && pwd)
SRC="$AMCL/src/amcl"
mkdir -p "$OUT"
cd "$OUT"
FLAGS=(-O2 -DNDEBUG -DHAVE_DRAND48 -I"$AMCL/include" -I"$AMCL/src/include")
for f in map/map.c map/map_range.c pf/pf.c pf/pf_kdtree.c pf/pf_pdf.c pf/pf_vector.c pf/eig3.c; do
  cc "${FLAGS[@]}" -c "$SRC/$f" -o "$(basename "${f%.c}").o"
done
for f in map/map_cspace.cpp sensors/amcl_sensor.cpp sensors/amcl_laser.cpp sensors/amcl_odom.cpp; do
  c++ "${FLAGS[@]}" -c "$SRC/$f" -o "$(basename "${f%.cpp}").o"
done
c++ "${FLAGS[@]}" "$HERE/driver.cpp" ./*.o -o amcl_driver -lm
echo "built $OUT/amcl_driver"
