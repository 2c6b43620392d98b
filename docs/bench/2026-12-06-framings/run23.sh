#!/bin/bash
# Item 2's scenes under four camera framings on the GPU: where glass loses to Mitsuba.
# Run from the repository root with the staging folder .gpu/ carried to the device (main's binary as
# .gpu/cltrace.xz, Mitsuba's wheels unpacked as .gpu/site.tar.xz); .gpu/frames.py is gpu-framings.py here.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
mkdir -p target/release
xz -dc .gpu/cltrace.xz > target/release/cltrace; chmod +x target/release/cltrace
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz)
PYTHONPATH=/tmp/site ROUNDS=3 timeout 540 python3 .gpu/frames.py gold,glass 2>&1 | grep -v Warn | tee $OUT/frames.txt | tail -12
