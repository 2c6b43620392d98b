#!/bin/bash
# Item 4: is the spread of cltrace's primary-ray figure per process or per scene upload?
# Three bench processes, each measuring the bunny and the dragon four times over (every copy
# its own BVH build and device buffers), 20 timed frames each.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee $OUT/gpu.txt
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
for p in 1 2 3; do
  /tmp/cltrace bench $B $B $B $B $D $D $D $D --methods cl-bvh --layouts bin64 --rays primary \
    --resolutions 1920x1080 --devices gpu --repetitions 20 2>&1 | grep -E "^\| stanford" \
    | awk -F'|' -v p=$p '{print "process " p ":" $2, $12, $13, $14}' | tee -a $OUT/copies.txt
done
