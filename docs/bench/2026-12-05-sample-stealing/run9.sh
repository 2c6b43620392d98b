#!/bin/bash
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
[ -e /work/main ] || { mkdir -p /work; ln -s $REPO /work/main; }
mkdir -p /work/main/target/release /work/main/target/tmp
xz -dc .gpu/cltrace.xz > /work/main/target/release/cltrace; chmod +x /work/main/target/release/cltrace
cd /work/main; B=/work/main/target/release/cltrace
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee $OUT/gpu.txt
for s in glass gold cornell; do
  $B render .gpu/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/eqa-$s.pfm
  CLTRACE_SUSPEND=8 $B render .gpu/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/eqb-$s.pfm
  cmp /tmp/eqa-$s.pfm /tmp/eqb-$s.pfm && echo "same image $s" | tee -a $OUT/eq.txt || echo "DIFFERENT $s" | tee -a $OUT/eq.txt
done
timeout 300 python3 .gpu/matrix.py .gpu/sc 3 "E=X=0;E=CLTRACE_SUSPEND=4;E=CLTRACE_SUSPEND=8;E=CLTRACE_SUSPEND=16;E=CLTRACE_SUSPEND=32" glass,gold,cornell 2>&1 | tail -19 | tee -a $OUT/m.txt
