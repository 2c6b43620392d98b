#!/bin/bash
# run55.sh split: the shear fused alone (k-S), the depth fused alone (k-T), both (k-F) and
# main's kernels alternated, cltrace bench (bin64, primary and diffuse-16, both meshes), 3 rounds.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 20"
for r in 1 2 3; do
  for v in main F S T; do
    if [ $v = main ]; then K=""; else K="CLTRACE_KERNEL_DIR=$REPO/.gpu/k-$v"; fi
    env $K timeout 60 /tmp/cltrace bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s median %s Mrays/s %s\n", t, $2, $8, $12, $14}' | tee -a $OUT/bench.txt
  done
done
echo "done at ${SECONDS}s"
