#!/bin/bash
# The axis picks as selects (main + cl/intersect.cl) against main before it: cltrace bench
# primary/diffuse/diffuse-16 on the H100/H200, and path tracing on the GPU and PoCL-16.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
xz -dc .gpu/cltrace.xz > /tmp/new; xz -dc .gpu/cltrace-old.xz > /tmp/old; chmod +x /tmp/new /tmp/old
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
/tmp/new devices 2>&1 | tee -a $OUT/gpu.txt
cp -r .gpu/sp /tmp/sp
cp -r .gpu/sp512 /tmp/sp512
for r in 1 2; do for b in old new; do
  timeout 150 /tmp/$b bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64,cwbvh \
    --rays primary,diffuse,diffuse-16 --resolutions 1920x1080 --devices gpu 2>&1 | grep -E "^\|" | sed "s/^/[$b r$r] /" | tee -a $OUT/bench.txt
done; done
BIN=/tmp/old timeout 120 python3 .gpu/matrix.py /tmp/sp 3 "E=X=0" glass,gold,cornell 2>&1 | grep "^|" | sed "s/^/[old gpu] /" | tee -a $OUT/path.txt
BIN=/tmp/new timeout 120 python3 .gpu/matrix.py /tmp/sp 3 "E=X=0" glass,gold,cornell 2>&1 | grep "^|" | sed "s/^/[new gpu] /" | tee -a $OUT/path.txt
for r in 1 2; do for b in old new; do
  BIN=/tmp/$b DEV=0:0 timeout 120 python3 .gpu/matrix.py /tmp/sp512 2 "E=X=0" glass,gold,cornell 2>&1 | grep "^| [a-z]" | sed "s/^/[$b pocl16 r$r] /" | tee -a $OUT/path.txt
done; done
