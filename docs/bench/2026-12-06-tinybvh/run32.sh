#!/bin/bash
# Item 4: bin64 primary rays under several work-group shapes, four rounds with the shapes
# alternated, tinybvh's primary rays before and after on the same card.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1
tiny() { (cd .gpu/tinybvh && for m in bunny dragon; do timeout 100 /tmp/harness /tmp/data/$m tiles scan 2>&1 | grep -E "tinybvh gpu" | sed "s/^/[tinybvh $1] /"; done) | tee -a $OUT/tinybvh.txt; }
tiny before
for r in 1 2 3 4; do for wg in ${SHAPES:-16x8 8x8 16x4 32x2 16x16 32x16 64x4 128x1}; do
  timeout 60 /tmp/cltrace bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 10 --work-group $wg 2>&1 | grep -E "^\| stanford" | awk -F'|' -v r=$r -v wg=$wg '{print "r" r, wg, $2, $12, $13, $14}' | tee -a $OUT/shapes.txt
done; done
tiny after
