#!/bin/bash
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
[ -e /work/main ] || { mkdir -p /work; ln -s $REPO /work/main; }
mkdir -p /work/main/target/release /work/main/target/tmp
xz -dc .gpu/cltrace.xz > /work/main/target/release/cltrace; chmod +x /work/main/target/release/cltrace
(tar -xJf .gpu/site.tar.xz -C /tmp) &
cd /work/main; B=/work/main/target/release/cltrace
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee $OUT/gpu.txt
for s in glass gold cornell; do
  for st in 0 2; do CLTRACE_STEAL=$st $B render .gpu/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/eq$st-$s.pfm 2>&1 | tail -2; done
  cmp /tmp/eq0-$s.pfm /tmp/eq2-$s.pfm && echo "same image $s" | tee -a $OUT/eq.txt || echo "DIFFERENT $s" | tee -a $OUT/eq.txt
done
CLTRACE_STEAL=2 CLTRACE_BUILD_OPTIONS=-cl-nv-verbose CLTRACE_BUILD_LOG=1 CLTRACE_KERNEL_CACHE=off $B render .gpu/sc/glass/scene.toml -q --device gpu --max-bounces 8 --spp 1 -o /tmp/x.pfm 2>&1 | grep -iE "registers|spill|smem" | tee -a $OUT/regs.txt
timeout 240 python3 .gpu/matrix.py .gpu/sc 4 "E=CLTRACE_STEAL=0;E=CLTRACE_STEAL=2" glass,gold,cornell 2>&1 | tail -10 | tee -a $OUT/m.txt
wait
PYTHONPATH=/tmp/site timeout 200 python3 scripts/mitsuba/compare.py speed --cltrace $B --devices gpu --variant cuda_ad_rgb --size 1920x1080 --spp 256 --max-bounces 8 --repetitions 2 --out /tmp/speed 2>&1 | tail -9 | tee -a $OUT/s.txt
