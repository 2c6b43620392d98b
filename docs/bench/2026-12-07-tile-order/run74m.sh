#!/bin/bash
# Camera rays' entry walks and work-group shapes, and item 4, on whatever card came (the
# H200 wanted). Each configuration in CONFIGS is a shape (`bench --work-group`) or K@shape:
# the head's binary (cltrace-main.xz, 93d1383) with kernels from .gpu/k-K (this folder's
# diffs: W2, W4 strip-entries.diff with ENTRY_ROWS 2 or 4; S1 root-slack.diff; R84, R162
# simd-blocks-8x4.diff, simd-blocks-16x2.diff). Rounds alternate the configurations,
# tinybvh each round; round 1 adds bin64's diffuse-16; then each K's renders against the
# head's. This session's leases ran it as
#   CONFIGS="16x8 W2@16x8 W4@16x8" ROUNDS=4         (GPU-3009c8d8; then run72.sh)
#   CONFIGS="16x8 16x16 32x8 32x16 8x8 S1@16x8"      (GPU-0ca4952e; then run73.sh)
#   CONFIGS="16x8 32x4 32x8 64x2 16x16 8x16"         (GPU-0ca4952e, second run)
#   the default                                      (GPU-7d50a0f4, GPU-2925f0f4)
# Item 4 alone: CONFIGS=16x8 ROUNDS=4.
set -u
ROUNDS=${ROUNDS:-3}; CONFIGS=${CONFIGS:-16x8 32x4 R84@16x8 R84@32x4 R162@32x4}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace-main.xz > /tmp/cltrace-main; chmod +x /tmp/cltrace-main
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1 &
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 20"
# Runs the rest of the line with configuration $1's kernels (none for a plain shape).
with() { local c=$1; shift; case $c in *@*) CLTRACE_KERNEL_DIR=$PWD/.gpu/k-${c%@*} "$@";; *) "$@";; esac; }
row() { grep -E "^\| stanford|rror" | awk -F'|' -v t="$1" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}'; }
for r in $(seq $ROUNDS); do
  for c in $CONFIGS; do
    with $c timeout 120 /tmp/cltrace-main bench $B $D $C --work-group ${c#*@} 2>&1 | row "[r$r $c]" | tee -a $OUT/bench.txt
  done
  [ $r = 1 ] && wait
  [ $r = 1 ] && timeout 120 /tmp/cltrace-main bench $B $D --methods cl-bvh --layouts bin64 --rays diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | row "[r$r 16x8]" | tee -a $OUT/bench.txt
  T="tiles scan"; [ $r = 1 ] && T="tiles scan d16"
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 150 /tmp/harness /tmp/data/$m $T 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s" | tee -a $OUT/bench.txt
done
R="--device gpu --layout bin64 --width 1920 --height 1080 --shade normal"
for m in $B $D; do
  timeout 60 /tmp/cltrace-main render $m $R -o /tmp/img-head.png --hits /tmp/hits-head.bin > /tmp/render-head.txt 2>&1
  for k in $(for c in $CONFIGS; do case $c in *@*) echo ${c%@*};; esac; done | sort -u); do
    with $k@ timeout 60 /tmp/cltrace-main render $m $R -o /tmp/img-$k.png --hits /tmp/hits-$k.bin > /tmp/render-$k.txt 2>&1
    if cmp -s /tmp/img-head.png /tmp/img-$k.png && cmp -s /tmp/hits-head.bin /tmp/hits-$k.bin; then echo "$m bin64 $k: same image and hits"; else echo "$m bin64 $k: DIFFERENT"; tail -2 /tmp/render-$k.txt; fi | tee -a $OUT/render.txt
  done
done
echo "all done at ${SECONDS}s" | tee -a $OUT/bench.txt
