#!/bin/bash
# Item 4: the work-group's shape apart from its SIMD groups' pixel tiles. A kernel copy
# (.gpu/k-remap) maps the 32 work-items of each SIMD group onto a REMAP_WX x REMAP_WY tile
# of the group's pixels; four rounds, configurations alternated; tinybvh before and after.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1
tiny() { (cd .gpu/tinybvh && for m in bunny dragon; do timeout 100 /tmp/harness /tmp/data/$m tiles scan 2>&1 | grep -E "tinybvh gpu" | sed "s/^/[tinybvh $1] /"; done) | tee -a $OUT/tinybvh.txt; }
one() { # name group remap-options
  local env=(); [ -n "$3" ] && env=(CLTRACE_KERNEL_DIR=$PWD/.gpu/k-remap "CLTRACE_BUILD_OPTIONS=$3")
  env "${env[@]}" timeout 60 /tmp/cltrace bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 10 --work-group $2 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v r=$r -v n=$1 '{print "r" r, n, $2, $12, $13, $14}' | tee -a $OUT/remap.txt
}
tiny before
for r in 1 2 3 4; do
  one 16x8 16x8 ""
  one 32x4 32x4 ""
  one 32x4/16x2 32x4 "-DREMAP_WX=16 -DREMAP_WY=2"
  one 32x8/16x2 32x8 "-DREMAP_WX=16 -DREMAP_WY=2"
  one 64x4/16x2 64x4 "-DREMAP_WX=16 -DREMAP_WY=2"
  one 64x2/16x2 64x2 "-DREMAP_WX=16 -DREMAP_WY=2"
  one 32x4/8x4 32x4 "-DREMAP_WX=8 -DREMAP_WY=4"
  one 64x4/32x1 64x4 "-DREMAP_WX=32 -DREMAP_WY=1"
done
tiny after
