#!/bin/bash
# Camera rays with the groups in strips of 4 groups (k-order, STRIP_GROUPS=4) against main's
# rows of groups: six meshes at three resolutions in bin64, and the other layouts at 1080p;
# three rounds, alternated.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
S=.gpu/scenes
one() { # name options
  local env=(); [ -n "$2" ] && env=(CLTRACE_KERNEL_DIR=$PWD/.gpu/k-order "CLTRACE_BUILD_OPTIONS=$2")
  env "${env[@]}" timeout 120 /tmp/cltrace bench $S/stanford_bunny.obj.gz $S/stanford_dragon.obj.gz $S/dragon_standing.obj.gz $S/barcelona_pavilion.obj $S/utah_teapot.obj $S/spot.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 960x540,1920x1080,3840x2160 --devices gpu --repetitions 10 2>&1 | grep -E "^\| [sdbu]|rror" | grep -v "| scene" | awk -F'|' -v r=$r -v n=$1 '{print "r" r, n, $2, $4, $5, $12, $14}' | tee -a $OUT/order.txt
  env "${env[@]}" timeout 120 /tmp/cltrace bench $S/stanford_bunny.obj.gz $S/stanford_dragon.obj.gz --methods cl-bvh --layouts bin32,wide4,wide8,cwbvh --rays primary --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| [sdbu]|rror" | grep -v "| scene" | awk -F'|' -v r=$r -v n=$1 '{print "r" r, n, $2, $4, $5, $12, $14}' | tee -a $OUT/order.txt
}
for r in 1 2 3; do
  one rows ""
  one S4 "-DSTRIP_GROUPS=4"
done
