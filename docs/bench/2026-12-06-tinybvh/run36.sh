#!/bin/bash
# The order in which the image kernels' groups cover the image (.gpu/k-order: STRIP_GROUPS,
# BAND_GROUPS), against main's rows of groups: camera rays of the bunny, the dragon and the
# dragon turned upright (dragon_standing: x, y -> -y, x), and path tracing of the dragon;
# three rounds, configurations alternated.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
S=.gpu/scenes
one() { # name options
  local env=(); [ -n "$2" ] && env=(CLTRACE_KERNEL_DIR=$PWD/.gpu/k-order "CLTRACE_BUILD_OPTIONS=$2")
  env "${env[@]}" timeout 60 /tmp/cltrace bench $S/stanford_bunny.obj.gz $S/stanford_dragon.obj.gz $S/dragon_standing.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| [sd]|rror" | grep -v "| scene" | awk -F'|' -v r=$r -v n=$1 '{print "r" r, n, $2, $8, $12, $14, $15}' | tee -a $OUT/order.txt
  env "${env[@]}" timeout 90 /tmp/cltrace bench $S/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 --rays path --path-spp 8 --resolutions 1920x1080 --devices gpu --repetitions 5 2>&1 | grep -E "^\| [sd]|rror" | grep -v "| scene" | awk -F'|' -v r=$r -v n=$1 '{print "r" r, n, $2, $8, $12, $14, $15}' | tee -a $OUT/order.txt
}
for r in 1 2 3; do
  one rows ""
  one S2 "-DSTRIP_GROUPS=2"
  one S4 "-DSTRIP_GROUPS=4"
  one S8 "-DSTRIP_GROUPS=8"
  one S4B34 "-DSTRIP_GROUPS=4 -DBAND_GROUPS=34"
  one S4B68 "-DSTRIP_GROUPS=4 -DBAND_GROUPS=68"
  one S8B34 "-DSTRIP_GROUPS=8 -DBAND_GROUPS=34"
done
