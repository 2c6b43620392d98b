#!/bin/bash
# SIMD efficiency of the path kernel's traversal and loop turns (k-M: activemask counts in
# place of the radiance; .gpu/simd.py reads them) on compare.py's three scenes, 1920x1080,
# 256 spp, --max-bounces 8, bin64; the head's binary (cltrace-head.xz, 93d1383).
set -u
REPO=$PWD; PY=${PY:-python3}; OUT=${OUT:-/tmp/out}; mkdir -p $OUT; SIZE=${SIZE:-1920x1080}; DEV=${DEV:-gpu}
nvidia-smi 2>/dev/null --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee -a $OUT/gpu.txt
CL=${CL:-/tmp/cltrace}; [ $CL = /tmp/cltrace ] && { xz -dc .gpu/cltrace-head.xz > /tmp/cltrace; chmod +x /tmp/cltrace; }
[ -d /tmp/sc/glass ] || $PY scripts/mitsuba/compare.py scenes --out /tmp/sc --size $SIZE --spp 256 --scenes cornell,gold,glass > $OUT/scenes.txt 2>&1
for s in cornell gold glass; do
  CLTRACE_KERNEL_DIR=$REPO/.gpu/k-M timeout 120 $CL render /tmp/sc/$s/scene.toml -q --device $DEV --layout bin64 --max-bounces 8 -o /tmp/m-$s.pfm --json /tmp/m-$s.json > /tmp/mlog-$s.txt 2>&1 || tail -20 /tmp/mlog-$s.txt | tee -a $OUT/simd.txt
  python3 .gpu/simd.py /tmp/m-$s.pfm /tmp/m-$s.json $s | tee -a $OUT/simd.txt
done
echo "all done at ${SECONDS}s" | tee -a $OUT/simd.txt
