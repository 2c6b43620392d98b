#!/bin/bash
# Item 4: the order in which the primary kernel's groups cover the image. A kernel copy
# (.gpu/k-remap, GROUP_STRIP=S) lays the groups, in the order they start, over strips S
# groups wide, each top to bottom, instead of rows of groups across the whole image; four
# rounds, alternated. On an H200, run30.sh first (items 2-4 against their peers).
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
if grep -q H200 $OUT/gpu.txt; then bash .gpu/run30.sh; fi
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
one() { # name group options
  local env=(); [ -n "$3" ] && env=(CLTRACE_KERNEL_DIR=$PWD/.gpu/k-remap "CLTRACE_BUILD_OPTIONS=$3")
  env "${env[@]}" timeout 60 /tmp/cltrace bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 10 --work-group $2 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v r=$r -v n=$1 '{print "r" r, n, $2, $12, $13, $14}' | tee -a $OUT/strips.txt
}
for r in 1 2 3 4; do
  one 16x8 16x8 ""
  one 16x8/strip4 16x8 "-DGROUP_STRIP=4"
  one 16x8/strip8 16x8 "-DGROUP_STRIP=8"
  one 16x8/strip15 16x8 "-DGROUP_STRIP=15"
  one 16x8/strip30 16x8 "-DGROUP_STRIP=30"
  one 32x4 32x4 ""
  one 32x4/strip4 32x4 "-DGROUP_STRIP=4"
  one 32x4/strip15 32x4 "-DGROUP_STRIP=15"
done
