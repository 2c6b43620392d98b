#!/bin/bash
# On an H200 the gate (run47.sh: items 2-4) first. Then, on any card: the upper bound of
# dropping the vertex permutation from camera rays: k-K permutes no vertex at all (a probe,
# exact only for rays whose dominant axis is z, as every camera ray of the bench's framing
# is), against main, bin64 primary rays, alternated.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/which.txt
if grep -q H200 $OUT/which.txt; then COMPARE_BEFORE=200 bash .gpu/run47.sh; fi
[ -x /tmp/cltrace ] || { xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace; }
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 20"
for r in 1 2 3 4; do
  for v in main K; do
    if [ $v = main ]; then K=""; else K="CLTRACE_KERNEL_DIR=$REPO/.gpu/k-$v"; fi
    env $K timeout 60 /tmp/cltrace bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s median %s min %s Mrays/s %s\n", t, $2, $8, $12, $13, $14}' | tee -a $OUT/probe.txt
  done
done
echo "done at ${SECONDS}s"
