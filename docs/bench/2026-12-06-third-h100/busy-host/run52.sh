#!/bin/bash
# Does a busy CPU slow cltrace bench's camera rays? The gate's round 1 runs while site.tar.xz
# unpacks in the background. Alternates quiet rounds with rounds beside two xz decompressions.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
B() { timeout 100 /tmp/cltrace bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 \
  --rays primary --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford|rror" | sed "s/^/[$1] /" | tee -a $OUT/bench.txt; }
for r in 1 2 3 4; do
  B "quiet r$r"
  (for k in 1 2 3 4 5 6; do xz -dc .gpu/site.tar.xz > /dev/null; done) & P1=$!
  (for k in 1 2 3 4 5 6; do xz -dc .gpu/site.tar.xz > /dev/null; done) & P2=$!
  sleep 0.5
  B "busy r$r"
  kill $P1 $P2 2>/dev/null; pkill -f "xz -dc" ; wait 2>/dev/null
done
