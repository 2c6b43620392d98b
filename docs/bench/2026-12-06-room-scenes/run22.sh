#!/bin/bash
# Item 2 on closed rooms: the Cornell box with a rough gold and a glass sphere, against
# Mitsuba 3 cuda_ad_rgb in the same run (the open scenes: run20 of 2026-12-06-gpu-sweeps).
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
mkdir -p target/release
xz -dc .gpu/cltrace.xz > target/release/cltrace; chmod +x target/release/cltrace
B=$PWD/target/release/cltrace
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz)
PYTHONPATH=/tmp/site timeout 520 python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace $B --devices gpu \
  --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass,cornell-gold,cornell-glass --repetitions 2 --out /tmp/spm 2>&1 | tail -20 | tee $OUT/mitsuba.md
