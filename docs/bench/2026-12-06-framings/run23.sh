#!/bin/bash
# Item 2's scenes under four camera framings on the GPU: where glass loses to Mitsuba.
# Run from the repository root with the staging folder .gpu/ carried to the device (main's binary as
# .gpu/cltrace.xz, Mitsuba's wheels unpacked as .gpu/site.tar.xz). Its output came from an earlier copy of
# framings.py with these settings as defaults, whose table had one cltrace column.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
mkdir -p target/release
xz -dc .gpu/cltrace.xz > target/release/cltrace; chmod +x target/release/cltrace
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz)
PYTHONPATH=/tmp/site VARIANT=cuda_ad_rgb DEVICES=gpu W=1920 H=1080 SPP=256 ROUNDS=3 timeout 540 python3 docs/bench/2026-12-06-framings/framings.py gold,glass 2>&1 | grep -v Warn | tee $OUT/frames.txt | tail -12
