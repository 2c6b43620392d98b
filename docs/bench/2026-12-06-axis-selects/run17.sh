#!/bin/bash
# Issue 19 item 2: main against Mitsuba cuda_ad_rgb, and kernel variants (select test, path
# state in local memory, culled pops) on compare.py's three scenes, 1920x1080, 256 spp.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
[ -e /work/main ] || { mkdir -p /work; ln -s $REPO /work/main; }
mkdir -p /work/main/target/release
xz -dc .gpu/cltrace.xz > /work/main/target/release/cltrace; chmod +x /work/main/target/release/cltrace
B=/work/main/target/release/cltrace; G=/work/main/.gpu
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz)
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
$B devices 2>&1 | tee -a $OUT/gpu.txt
PYTHONPATH=/tmp/site timeout 260 python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace $B --devices gpu \
  --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 2 --out /tmp/sp 2>&1 | tail -14 | tee $OUT/mitsuba.md
[ -e /tmp/sp/glass/scene.toml ] || PYTHONPATH=/tmp/site python3 scripts/mitsuba/compare.py scenes --out /tmp/sp --size 1920x1080 --spp 256 --scenes cornell,gold,glass >/dev/null
for kc in ":" "$G/k-sel:" "$G/k-lstate:" "$G/k-lstate:-cl-nv-maxrregcount=48" "$G/k-lstate:-cl-nv-maxrregcount=80" "$G/k-lstate-sel:" "$G/k-cull:"; do
  k=${kc%%:*}; c=${kc#*:}
  if [ -n "$k" ]; then export CLTRACE_KERNEL_DIR=$k; else unset CLTRACE_KERNEL_DIR; fi
  CLTRACE_BUILD_OPTIONS="$c -cl-nv-verbose" CLTRACE_BUILD_LOG=1 CLTRACE_KERNEL_CACHE=off timeout 60 $B render /tmp/sp/glass/scene.toml -q --device gpu --max-bounces 8 --spp 1 -o /tmp/x.pfm 2>&1 | grep -iE "registers|spill|error" | sed "s#^#[${kc#$G/}] #" | head -4 | tee -a $OUT/regs.txt
done
unset CLTRACE_KERNEL_DIR
for s in glass gold cornell; do
  timeout 60 $B render /tmp/sp/$s/scene.toml -q --device gpu --max-bounces 8 --spp 16 -o /tmp/eqa-$s.pfm
  for k in k-sel k-lstate k-lstate-sel k-cull; do
    CLTRACE_KERNEL_DIR=$G/$k timeout 60 $B render /tmp/sp/$s/scene.toml -q --device gpu --max-bounces 8 --spp 16 -o /tmp/eqb-$s.pfm
    cmp -s /tmp/eqa-$s.pfm /tmp/eqb-$s.pfm && echo "same image $s $k" | tee -a $OUT/eq.txt || echo "DIFFERENT $s $k" | tee -a $OUT/eq.txt
  done
done
timeout 300 python3 $G/matrix.py /tmp/sp 3 "E=X=0;K=$G/k-sel;K=$G/k-lstate;K=$G/k-lstate E=CLTRACE_BUILD_OPTIONS=-cl-nv-maxrregcount=48;K=$G/k-lstate E=CLTRACE_BUILD_OPTIONS=-cl-nv-maxrregcount=80;K=$G/k-lstate-sel;K=$G/k-cull" glass,gold,cornell 2>&1 | tail -26 | tee $OUT/m.txt
