#!/usr/bin/env bash
# Build the DBoW3 peer of benchmarks/bench_vision.py: DBoW3 (rmsalinas/DBow3, src/) with
# driver.cpp, compiled with the flags of DBoW3's own CMake Release build on x86-64
# (-O3 -fomit-frame-pointer -mmmx -msse -msse2 -msse3). Needs OpenCV's core module
# (Debian: libopencv-core-dev). DBoW3 is not part of symloc: fetch it yourself, e.g. a clone
# of https://github.com/rmsalinas/DBow3.
#
# usage: benchmarks/peers/dbow3/build.sh DBOW3_CHECKOUT OUT_DIR
#   then: python benchmarks/bench_vision.py --clock cpu --dbow3 OUT_DIR/dbow3_driver
# OUT_DIR/SOURCE.txt says what was built (the benchmark's results file quotes it).
set -euo pipefail
DBOW3=${1:?a DBow3 checkout (with src/)}
OUT=${2:?output folder}
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
cd "$OUT"
FLAGS=(-O3 -DNDEBUG -fomit-frame-pointer -mmmx -msse -msse2 -msse3 -I"$DBOW3/src" -I/usr/include/opencv4)
cc "${FLAGS[@]}" -c "$DBOW3/src/quicklz.c" -o quicklz.o
for f in BowVector Database DescManip FeatureVector QueryResults ScoringObject Vocabulary; do
  c++ -std=c++11 "${FLAGS[@]}" -c "$DBOW3/src/$f.cpp" -o "$f.o"
done
c++ -std=c++11 "${FLAGS[@]}" "$HERE/driver.cpp" ./*.o -o dbow3_driver -lopencv_core
# what was built, for bench_vision's results file (DBOW3_REV names the revision of a checkout
# that is not a git clone, e.g. an exported tree)
REV=$(git -C "$DBOW3" rev-parse --short HEAD 2>/dev/null || echo "${DBOW3_REV:-revision unknown}")
echo "rmsalinas/DBow3 $REV, DBoW3's Release flags (benchmarks/peers/dbow3/build.sh)" > SOURCE.txt
echo "built $OUT/dbow3_driver"
