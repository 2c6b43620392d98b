#!/bin/bash
# Streaming (nontemporal) stores of the camera rays' outputs (k-order, NT_STORES), in rows
# and in strips of 4 groups: does keeping the stores out of the cache give the dragon the
# strips' gain? Three rounds, alternated.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
S=.gpu/scenes
env CLTRACE_KERNEL_DIR=$PWD/.gpu/k-order CLTRACE_BUILD_OPTIONS="-DNT_STORES" /tmp/cltrace render $S/stanford_bunny.obj.gz -q --device gpu --width 64 --height 32 -o /tmp/nt.png 2>&1 | head -5 | tee $OUT/nt-build.txt
one() { # name options
  env CLTRACE_KERNEL_DIR=$PWD/.gpu/k-order "CLTRACE_BUILD_OPTIONS=$2" timeout 120 /tmp/cltrace bench $S/stanford_bunny.obj.gz $S/stanford_dragon.obj.gz $S/utah_teapot.obj $S/spot.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| [sdbu]|rror" | grep -v "| scene" | awk -F'|' -v r=$r -v n=$1 '{print "r" r, n, $2, $4, $5, $12, $14}' | tee -a $OUT/nt.txt
}
for r in 1 2 3; do
  one rows ""
  one rows-nt "-DNT_STORES"
  one S4 "-DSTRIP_GROUPS=4"
  one S4-nt "-DSTRIP_GROUPS=4 -DNT_STORES"
done
