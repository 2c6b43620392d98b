#!/bin/bash
# Item 4 (and 3) with the packed axes: run27.sh's rounds against tinybvh's Aila-Laine kernel,
# main with the packed axes (new) and the main before it (old) alternated with the harness,
# three rounds; then compare.py speed against Mitsuba 3 with the new binary, one round.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace-new.xz > /tmp/cltrace-new; xz -dc .gpu/cltrace.xz > /tmp/cltrace-old; chmod +x /tmp/cltrace-new /tmp/cltrace-old
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1
for r in 1 2 3; do
  for v in new old; do
    timeout 100 /tmp/cltrace-$v bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 \
      --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford" | sed "s/^/[cltrace-$v r$r] /" | tee -a $OUT/bench.txt
  done
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 100 /tmp/harness /tmp/data/$m tiles scan d16 2>&1 | grep -E "tinybvh gpu" | sed "s/^/[tinybvh r$r $m] /"; done) | tee -a $OUT/tinybvh.txt
done
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz)
PYTHONPATH=/tmp/site timeout 200 python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace /tmp/cltrace-new --devices gpu \
  --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3 --out /tmp/spm 2>&1 | grep -E "^\||rror" | tee -a $OUT/mitsuba.txt
