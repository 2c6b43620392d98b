#!/bin/bash
# Items 3 and 4 in one run: cltrace bench (bin64) and tinybvh's Aila-Laine kernel (BVH_GPU after
# BuildHQ, through a harness outside the project) on the same rays, three alternated rounds;
# cltrace times 10 frames a run, as the harness times 10 launches (run25.sh timed bench's default 5).
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) 2>&1 | tee $OUT/raydump.txt
for r in 1 2 3; do
  timeout 150 /tmp/cltrace bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 \
    --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford|^\| scene" | sed "s/^/[cltrace r$r] /" | tee -a $OUT/bench.txt
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 150 /tmp/harness /tmp/data/$m tiles scan d16 2>&1 | grep -E "tinybvh gpu|triangles|Device" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
done
