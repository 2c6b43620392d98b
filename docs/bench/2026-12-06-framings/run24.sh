#!/bin/bash
# The glass scene's framings on the GPU with the cwbvh and wide4 layouts beside bin64's (run23).
# Run from the repository root with the staging folder .gpu/ carried to the device (main's binary as
# .gpu/cltrace.xz, Mitsuba's wheels unpacked as .gpu/site.tar.xz). Its output came from an earlier copy of
# framings.py with these settings as defaults, whose table had one cltrace column.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
mkdir -p target/release
xz -dc .gpu/cltrace.xz > target/release/cltrace; chmod +x target/release/cltrace
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz)
for L in cwbvh bin64; do
  echo "== layout $L"
  PYTHONPATH=/tmp/site VARIANT=cuda_ad_rgb DEVICES=gpu W=1920 H=1080 SPP=256 ROUNDS=2 EXTRA="--layout $L" timeout 250 python3 docs/bench/2026-12-06-framings/framings.py glass,gold 2>&1 | grep -v Warn | grep "^|"
done | tee $OUT/layouts.txt
