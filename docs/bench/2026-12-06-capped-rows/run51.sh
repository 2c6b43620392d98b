#!/bin/bash
# Item 4 alone, if the card is an H200: one round of cltrace bench (bin64, primary and
# diffuse-16) and tinybvh's harness on the same rays. Another card: out at once.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/which.txt
grep -q H200 $OUT/which.txt || exit 0
xz -dc .gpu/cltrace.xz > /tmp/cltrace; xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/cltrace /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1
echo "raydump done at ${SECONDS}s"
timeout 60 /tmp/cltrace bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 \
  --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford|^\| scene|rror" | tee -a $OUT/bench.txt
(cd .gpu/tinybvh && for m in bunny dragon; do timeout 50 /tmp/harness /tmp/data/$m tiles scan d16 2>&1 | grep -E "tinybvh gpu|Device|rror"; done) | tee -a $OUT/tinybvh.txt
