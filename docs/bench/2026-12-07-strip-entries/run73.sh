#!/bin/bash
# Item 4 on whatever card came (the H200 wanted), and camera rays' work-group shape now that
# each work-group walks to its tile's entry node (GROUP_ENTRIES, bin64): the head build
# (cltrace-head.xz, 93d1383) with `bench --work-group` 16x8 (the default), 16x16, 32x8,
# 32x16 and 8x8; S1 = 16x8 with kernels from .gpu/k-S1 (the entry walk's slack computed once,
# from the root's boxes). Rounds alternated, tinybvh each round; round 1 adds bin64's diffuse-16
# and tinybvh's.
set -u
ROUNDS=${ROUNDS:-3}; SHAPES=${SHAPES:-16x8 16x16 32x8 32x16 8x8 S1}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace-head.xz > /tmp/cltrace-head; chmod +x /tmp/cltrace-head
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1 &
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 20"
for r in $(seq $ROUNDS); do
  for s in $SHAPES; do
    if [ $s = S1 ]; then X="env CLTRACE_KERNEL_DIR=$PWD/.gpu/k-S1"; W=16x8; else X=; W=$s; fi
    $X timeout 120 /tmp/cltrace-head bench $B $D $C --work-group $W 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $s]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  [ $r = 1 ] && wait
  [ $r = 1 ] && timeout 120 /tmp/cltrace-head bench $B $D --methods cl-bvh --layouts bin64 --rays diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r 16x8]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  T="tiles scan"; [ $r = 1 ] && T="tiles scan d16"
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 150 /tmp/harness /tmp/data/$m $T 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s" | tee -a $OUT/bench.txt
done
for m in $B $D; do
  timeout 60 /tmp/cltrace-head render $m --device gpu --layout bin64 --width 1920 --height 1080 --shade normal -o /tmp/img-head.png --hits /tmp/hits-head.bin > /tmp/render-head.txt 2>&1
  CLTRACE_KERNEL_DIR=$PWD/.gpu/k-S1 timeout 60 /tmp/cltrace-head render $m --device gpu --layout bin64 --width 1920 --height 1080 --shade normal -o /tmp/img-S1.png --hits /tmp/hits-S1.bin > /tmp/render-S1.txt 2>&1
  if cmp -s /tmp/img-head.png /tmp/img-S1.png && cmp -s /tmp/hits-head.bin /tmp/hits-S1.bin; then echo "$m bin64 S1: same image and hits"; else echo "$m bin64 S1: DIFFERENT"; tail -2 /tmp/render-*.txt; fi | tee -a $OUT/render.txt
done
echo "all done at ${SECONDS}s" | tee -a $OUT/bench.txt
