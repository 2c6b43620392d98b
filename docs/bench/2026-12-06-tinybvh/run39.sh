#!/bin/bash
# Strips of groups with the grid's size a compile-time constant (NGX, NGY: 1080p in 16x8
# groups), to tell the index arithmetic's cost from the order's; three rounds, alternated.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
S=.gpu/scenes
one() { # name options
  env CLTRACE_KERNEL_DIR=$PWD/.gpu/k-order "CLTRACE_BUILD_OPTIONS=$2" timeout 120 /tmp/cltrace bench $S/stanford_bunny.obj.gz $S/stanford_dragon.obj.gz $S/barcelona_pavilion.obj $S/utah_teapot.obj $S/spot.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| [sdbu]|rror" | grep -v "| scene" | awk -F'|' -v r=$r -v n=$1 '{print "r" r, n, $2, $4, $5, $12, $14}' | tee -a $OUT/const.txt
}
for r in 1 2 3; do
  one rows ""
  one S4 "-DSTRIP_GROUPS=4"
  one S4const "-DSTRIP_GROUPS=4 -DNGX=120 -DNGY=135"
  one S8const "-DSTRIP_GROUPS=8 -DNGX=120 -DNGY=135"
  one S2const "-DSTRIP_GROUPS=2 -DNGX=120 -DNGY=135"
done
