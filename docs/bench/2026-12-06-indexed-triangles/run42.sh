#!/bin/bash
# Experiment exp/indexed: bin64's leaf tests read three position indices a triangle and the
# unique positions (float4) instead of the 48-byte triangles: the traversal's footprint
# (dragon 72.5 MB -> about 48 MB, under the 50 MB L2). Main against it, alternated rounds:
# four meshes, primary and diffuse-16, then hillsides of 10 thousand to 10 million triangles.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; xz -dc .gpu/exp-indexed.xz > /tmp/cltrace-x; chmod +x /tmp/cltrace /tmp/cltrace-x
S=.gpu/scenes
MESHES="$S/stanford_bunny.obj.gz $S/stanford_dragon.obj.gz $S/utah_teapot.obj $S/spot.obj.gz"
main() { timeout 200 /tmp/cltrace "$@"; }
exp() { env CLTRACE_EXP_INDEXED=1 CLTRACE_KERNEL_DIR=$PWD/.gpu/k-indexed timeout 200 /tmp/cltrace-x "$@"; }
for r in 1 2 3; do
  for v in main exp; do
    $v bench $MESHES --methods cl-bvh --layouts bin64 --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| [a-z]|rror|experiment" | sed "s/^/r$r $v /" | tee -a $OUT/bench.txt
  done
done
for r in 1 2; do
  for v in main exp; do
    $v bench --scaling --scaling-to 10M --methods cl-bvh --layouts bin64 --rays primary,diffuse-16 --devices gpu --repetitions 10 2>&1 | grep -E "^\| hill|rror" | sed "s/^/r$r $v /" | tee -a $OUT/hills.txt
  done
done
