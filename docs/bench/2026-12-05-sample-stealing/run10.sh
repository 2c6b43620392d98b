#!/bin/bash
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
[ -e /work/main ] || { mkdir -p /work; ln -s $REPO /work/main; }
mkdir -p /work/main/target/release /work/main/target/tmp
xz -dc .gpu/cltrace.xz > /work/main/target/release/cltrace; chmod +x /work/main/target/release/cltrace
cd /work/main; B=/work/main/target/release/cltrace
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee $OUT/gpu.txt
for su in none 16; do
  if [ $su = none ]; then unset CLTRACE_SUSPEND; else export CLTRACE_SUSPEND=$su; fi
  CLTRACE_BUILD_OPTIONS=-cl-nv-verbose CLTRACE_BUILD_LOG=1 CLTRACE_KERNEL_CACHE=off $B render .gpu/sc/glass/scene.toml -q --device gpu --max-bounces 8 --spp 1 -o /tmp/x.pfm 2>&1 | grep -iE "sample_path|registers|spill|stack frame" | head -12 | sed "s/^/$su: /" | tee -a $OUT/regs.txt
done
unset CLTRACE_SUSPEND
timeout 300 python3 .gpu/matrix.py .gpu/sc 3 "E=X=0;E=CLTRACE_SUSPEND=1000000;E=CLTRACE_SUSPEND=12;E=CLTRACE_SUSPEND=24;E=CLTRACE_SUSPEND=48" glass,gold,cornell 2>&1 | tail -19 | tee -a $OUT/m.txt
