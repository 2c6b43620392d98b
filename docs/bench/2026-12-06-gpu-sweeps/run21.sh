#!/bin/bash
# Register caps and work-group shapes of the path programs on compare.py's scenes.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
[ -e /work/main ] || { mkdir -p /work; ln -s $REPO /work/main; }
mkdir -p /work/main/target/release
xz -dc .gpu/cltrace.xz > /work/main/target/release/cltrace; chmod +x /work/main/target/release/cltrace
B=/work/main/target/release/cltrace
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
rm -rf /tmp/sp; cp -r .gpu/sp /tmp/sp
for c in "" "-cl-nv-maxrregcount=72" "-cl-nv-maxrregcount=80" "-cl-nv-maxrregcount=96"; do for s in glass gold; do
  CLTRACE_BUILD_OPTIONS="$c -cl-nv-verbose" CLTRACE_BUILD_LOG=1 CLTRACE_KERNEL_CACHE=off timeout 60 $B render /tmp/sp/$s/scene.toml -q --device gpu --max-bounces 8 --spp 1 -o /tmp/x.pfm 2>&1 | grep -iE "registers|spill|error" | grep -v "0 bytes stack" | sed "s#^#[$s $c] #" | head -3 | tee -a $OUT/regs.txt
done; done
BIN=$B timeout 200 python3 .gpu/matrix.py /tmp/sp 3 "E=X=0;E=CLTRACE_BUILD_OPTIONS=-cl-nv-maxrregcount=72;E=CLTRACE_BUILD_OPTIONS=-cl-nv-maxrregcount=80;E=CLTRACE_BUILD_OPTIONS=-cl-nv-maxrregcount=96" glass,gold,cornell 2>&1 | tee $OUT/caps.txt
for r in 1 2; do for wg in 16x8 8x8 32x4 8x16 32x2 16x16; do
  timeout 60 $B bench /tmp/sp/glass/scene.toml /tmp/sp/gold/scene.toml /tmp/sp/cornell/scene.toml --methods cl-bvh --layouts bin64 --rays path --path-spp 64 --path-bounces 8 \
    --resolutions 1920x1080 --devices gpu --work-group $wg 2>&1 | grep -E "^\| " | grep path | cut -d'|' -f2,7- | sed "s/^/[$wg r$r] /" | tee -a $OUT/wg.txt
done; done
