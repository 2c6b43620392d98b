#!/bin/bash
# On an H200 items 3 and 4 first (run47.sh, three rounds, no compare.py). Then, on any card:
# is the camera rays' spread between processes the frame's stores (25 MB a launch beside a
# 5.5 MB BVH in a 50 MB L2)? Probes, not exact: k-P1 stores no colours, k-P2 no hit records
# (their values still computed). bin64 primary rays, bunny and dragon, five alternated
# processes of each.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/which.txt
if grep -q H200 $OUT/which.txt; then COMPARE_BEFORE=0 bash .gpu/run47.sh; fi
[ -x /tmp/cltrace ] || { xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace; }
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 20"
for r in 1 2 3 4 5; do
  for v in main P1 P2; do
    if [ $v = main ]; then K=""; else K="CLTRACE_KERNEL_DIR=$REPO/.gpu/k-$v"; fi
    env $K timeout 60 /tmp/cltrace bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s median %s min %s Mrays/s %s\n", t, $2, $8, $12, $13, $14}' | tee -a $OUT/stores.txt
  done
done
echo "done at ${SECONDS}s"
