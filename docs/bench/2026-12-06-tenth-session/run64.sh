#!/bin/bash
# The bench's camera rays as a closest-hit query (hit records alone, no colour image:
# cltrace-new.xz) against main's binary (cltrace.xz, Lambert colours stored too), alternated,
# with tinybvh's Aila-Laine kernel on the same rays in each round. On an H200 first the
# same against it is what item 4 asks.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace-main; xz -dc .gpu/cltrace-new.xz > /tmp/cltrace-new; chmod +x /tmp/cltrace-*
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --resolutions 1920x1080 --devices gpu --repetitions 20"
for r in 1 2 3 4 5; do
  for v in main new; do
    R=primary; [ $r = 1 ] && R=primary,diffuse-16
    timeout 60 /tmp/cltrace-$v bench $B $D $C --rays $R 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s median %s min %s Mrays/s %s\n", t, $2, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 60 /tmp/harness /tmp/data/$m tiles scan 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s"
done
