#!/bin/bash
# Items 2, 3 and 4 on the card lent (the items name the H200): three rounds of cltrace bench
# (bin64, primary and diffuse-16) alternated with tinybvh's Aila-Laine kernel on the same rays
# (harness outside the project), then compare.py speed against Mitsuba 3 cuda_ad_rgb if the
# call's time allows (else run48.sh in the next call).
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz) &
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1
echo "raydump done at ${SECONDS}s"
for r in $(seq 1 ${ROUNDS:-3}); do
  timeout 100 /tmp/cltrace bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 \
    --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford|^\| scene|rror" | sed "s/^/[cltrace r$r] /" | tee -a $OUT/bench.txt
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 100 /tmp/harness /tmp/data/$m tiles scan d16 2>&1 | grep -E "tinybvh gpu|Device|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s"
done
wait
if [ $SECONDS -lt ${COMPARE_BEFORE:-330} ]; then bash .gpu/run48.sh; else echo "compare.py left for run48.sh"; fi
