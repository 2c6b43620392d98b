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
  for st in 0 1; do CLTRACE_STEAL=$st $B render .gpu/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/eq$st-$s.pfm 2>&1 | tail -2; done
  cmp /tmp/eq0-$s.pfm /tmp/eq1-$s.pfm && echo "same image $s" | tee -a $OUT/eq.txt || echo "DIFFERENT $s" | tee -a $OUT/eq.txt
done
timeout 240 python3 .gpu/matrix.py .gpu/sc 3 "E=CLTRACE_STEAL=0;E=CLTRACE_STEAL=1;E=CLTRACE_STEAL=0 E=CLTRACE_LAUNCH_MS=400;E=CLTRACE_STEAL=1 E=CLTRACE_LAUNCH_MS=400" glass,gold,cornell 2>&1 | tail -16 | tee -a $OUT/m.txt
wait
CLTRACE_STEAL=1 PYTHONPATH=/tmp/site timeout 200 python3 scripts/mitsuba/compare.py speed --cltrace $B --devices gpu --variant cuda_ad_rgb --size 1920x1080 --spp 256 --max-bounces 8 --repetitions 2 --out /tmp/speed 2>&1 | tail -9 | tee -a $OUT/s.txt
