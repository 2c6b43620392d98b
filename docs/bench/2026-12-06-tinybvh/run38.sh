#!/bin/bash
# Why strips of groups help the dragon's camera rays and cost small meshes: the same with
# the outputs not written (NO_STORE: the traversal runs, the stores are skipped); three
# rounds, alternated.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
S=.gpu/scenes
one() { # name options
  env CLTRACE_KERNEL_DIR=$PWD/.gpu/k-order "CLTRACE_BUILD_OPTIONS=$2" timeout 120 /tmp/cltrace bench $S/stanford_bunny.obj.gz $S/stanford_dragon.obj.gz $S/barcelona_pavilion.obj $S/utah_teapot.obj $S/spot.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080,3840x2160 --devices gpu --repetitions 10 2>&1 | grep -E "^\| [sdbu]|rror" | grep -v "| scene" | awk -F'|' -v r=$r -v n=$1 '{print "r" r, n, $2, $4, $5, $12, $14}' | tee -a $OUT/nostore.txt
}
for r in 1 2 3; do
  one rows ""
  one S4 "-DSTRIP_GROUPS=4"
  one rows-nostore "-DNO_STORE"
  one S4-nostore "-DSTRIP_GROUPS=4 -DNO_STORE"
done
