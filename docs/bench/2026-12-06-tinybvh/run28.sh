#!/bin/bash
# Item 4: camera rays that set up the triangle test only at their first leaf (kernel copy
# .gpu/k-lazy, passed with CLTRACE_KERNEL_DIR) against main's kernels and tinybvh's
# Aila-Laine kernel on the same rays, three alternated rounds; 10 timed frames a cltrace run.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1
bench() {
  timeout 150 /tmp/cltrace bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 \
    --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford" | sed "s/^/[$1] /" | tee -a $OUT/bench.txt
}
for r in 1 2 3; do
  bench "main r$r"
  CLTRACE_KERNEL_DIR=.gpu/k-lazy bench "lazy r$r"
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 150 /tmp/harness /tmp/data/$m tiles d16 2>&1 | grep -E "tinybvh gpu" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
done
