#!/bin/bash
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
[ -e /work/main ] || { mkdir -p /work; ln -s $REPO /work/main; }
mkdir -p /work/main/target/release /work/main/target/tmp
xz -dc .gpu/cltrace.xz > /work/main/target/release/cltrace; chmod +x /work/main/target/release/cltrace
cd /work/main; B=/work/main/target/release/cltrace
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee $OUT/gpu.txt
for kc in ":" "/work/main/.gpu/k-lstate:" "/work/main/.gpu/k-lstate:-cl-nv-maxrregcount=48" "/work/main/.gpu/k-lstate:-cl-nv-maxrregcount=80"; do
  k=${kc%%:*}; c=${kc#*:}
  if [ -n "$k" ]; then export CLTRACE_KERNEL_DIR=$k; else unset CLTRACE_KERNEL_DIR; fi
  CLTRACE_BUILD_OPTIONS="$c -cl-nv-verbose" CLTRACE_BUILD_LOG=1 CLTRACE_KERNEL_CACHE=off $B render .gpu/sc/glass/scene.toml -q --device gpu --max-bounces 8 --spp 1 -o /tmp/x.pfm 2>&1 | grep -iE "registers|spill|smem|error" | sed "s#^#[$kc] #" | tee -a $OUT/regs.txt
done
unset CLTRACE_KERNEL_DIR
for s in glass gold cornell; do
  $B render .gpu/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/eqa-$s.pfm
  CLTRACE_KERNEL_DIR=/work/main/.gpu/k-lstate $B render .gpu/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/eqb-$s.pfm
  cmp /tmp/eqa-$s.pfm /tmp/eqb-$s.pfm && echo "same image $s" | tee -a $OUT/eq.txt || echo "DIFFERENT $s" | tee -a $OUT/eq.txt
done
timeout 240 python3 .gpu/matrix.py .gpu/sc 3 "E=X=0;K=/work/main/.gpu/k-lstate;K=/work/main/.gpu/k-lstate E=CLTRACE_BUILD_OPTIONS=-cl-nv-maxrregcount=48;K=/work/main/.gpu/k-lstate E=CLTRACE_BUILD_OPTIONS=-cl-nv-maxrregcount=80" glass,gold,cornell 2>&1 | tail -16 | tee -a $OUT/m.txt
