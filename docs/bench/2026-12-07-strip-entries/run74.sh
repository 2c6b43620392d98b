#!/bin/bash
# Item 4 on whatever card came (the H200 wanted), and which part of a work-group's shape
# moves camera rays: the tile the group walks for, or the block of pixels each SIMD group
# of 32 traces. Configurations of the head's binary (cltrace-head.xz, 93d1383): a shape
# (`bench --work-group`), or K@shape with kernels from .gpu/k-K: R84 puts each SIMD group on
# an 8x4 block of the tile, R162 on a 16x2 block (plain 16x8 tiles already do; 32x4 tiles
# give 32x1 rows). Rounds alternated, tinybvh each round; round 1 adds bin64's diffuse-16.
set -u
ROUNDS=${ROUNDS:-3}; CONFIGS=${CONFIGS:-16x8 32x4 R84@16x8 R84@32x4 R162@32x4}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace-head.xz > /tmp/cltrace-head; chmod +x /tmp/cltrace-head
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1 &
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 20"
for r in $(seq $ROUNDS); do
  for c in $CONFIGS; do
    case $c in *@*) X="env CLTRACE_KERNEL_DIR=$PWD/.gpu/k-${c%@*}"; W=${c#*@};; *) X=; W=$c;; esac
    $X timeout 120 /tmp/cltrace-head bench $B $D $C --work-group $W 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $c]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  [ $r = 1 ] && wait
  [ $r = 1 ] && timeout 120 /tmp/cltrace-head bench $B $D --methods cl-bvh --layouts bin64 --rays diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r 16x8]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  T="tiles scan"; [ $r = 1 ] && T="tiles scan d16"
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 150 /tmp/harness /tmp/data/$m $T 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s" | tee -a $OUT/bench.txt
done
for m in $B $D; do
  timeout 60 /tmp/cltrace-head render $m --device gpu --layout bin64 --width 1920 --height 1080 --shade normal -o /tmp/img-head.png --hits /tmp/hits-head.bin > /tmp/render-head.txt 2>&1
  CLTRACE_KERNEL_DIR=$PWD/.gpu/k-R84 timeout 60 /tmp/cltrace-head render $m --device gpu --layout bin64 --width 1920 --height 1080 --shade normal -o /tmp/img-R84.png --hits /tmp/hits-R84.bin > /tmp/render-R84.txt 2>&1
  if cmp -s /tmp/img-head.png /tmp/img-R84.png && cmp -s /tmp/hits-head.bin /tmp/hits-R84.bin; then echo "$m bin64 R84: same image and hits"; else echo "$m bin64 R84: DIFFERENT"; tail -2 /tmp/render-*.txt; fi | tee -a $OUT/render.txt
done
echo "all done at ${SECONDS}s" | tee -a $OUT/bench.txt
