#!/bin/bash
# run52.sh's question for both tracers: cltrace bench and tinybvh's harness, camera rays,
# quiet rounds alternated with rounds beside two xz decompressions.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/cltrace /tmp/harness /tmp/raydump
mkdir -p /tmp/data; /tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny > $OUT/raydump.txt 2>&1
B() { timeout 100 /tmp/cltrace bench .gpu/scenes/stanford_bunny.obj.gz --methods cl-bvh --layouts bin64 \
  --rays primary --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford|rror" | sed "s/^/[cltrace $1] /" | tee -a $OUT/bench.txt
  (cd .gpu/tinybvh && timeout 100 /tmp/harness /tmp/data/bunny tiles 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh $1] /") | tee -a $OUT/tinybvh.txt; }
for r in 1 2 3 4; do
  B "quiet r$r"
  (for k in 1 2 3 4 5 6; do xz -dc .gpu/site.tar.xz > /dev/null; done) & P1=$!
  (for k in 1 2 3 4 5 6; do xz -dc .gpu/site.tar.xz > /dev/null; done) & P2=$!
  sleep 0.5
  B "busy r$r"
  kill $P1 $P2 2>/dev/null; pkill -f "xz -dc"; wait 2>/dev/null
done
