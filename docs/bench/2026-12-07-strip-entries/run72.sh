#!/bin/bash
# Item 4 on whatever card came (the H200 wanted), and camera rays' entry nodes found per
# strip of ENTRY_ROWS rows of each 16x8 work-group (one per SIMD group of 32 at 2 rows)
# instead of per work-group: head = cltrace-head.xz (93d1383); W2, W4 = the same binary
# with CLTRACE_KERNEL_DIR=.gpu/k-W2 or k-W4. Rounds alternated, tinybvh each round; round
# 1 adds bin64's diffuse-16 and tinybvh's; then renders of W2 and W4 against head.
set -u
ROUNDS=${ROUNDS:-3}; LAYOUTS=${LAYOUTS:-bin64}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace-head.xz > /tmp/cltrace-head; chmod +x /tmp/cltrace-head
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1 &
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts $LAYOUTS --rays primary --resolutions 1920x1080 --devices gpu --repetitions 20"
kd() { case $1 in head) echo "";; *) echo "$PWD/.gpu/k-$1";; esac; }
run() { local v=$1; shift; if [ $v = head ]; then "$@"; else CLTRACE_KERNEL_DIR=$(kd $v) "$@"; fi; }
for r in $(seq $ROUNDS); do
  for v in head W2 W4; do
    run $v timeout 120 /tmp/cltrace-head bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  [ $r = 1 ] && wait
  [ $r = 1 ] && timeout 120 /tmp/cltrace-head bench $B $D --methods cl-bvh --layouts bin64 --rays diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r head]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  T="tiles scan"; [ $r = 1 ] && T="tiles scan d16"
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 150 /tmp/harness /tmp/data/$m $T 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s" | tee -a $OUT/bench.txt
done
for m in $B $D; do for l in ${LAYOUTS//,/ }; do
  for v in head W2 W4; do run $v timeout 60 /tmp/cltrace-head render $m --device gpu --layout $l --width 1920 --height 1080 --shade normal -o /tmp/img-$v.png --hits /tmp/hits-$v.bin > /tmp/render-$v.txt 2>&1; done
  for v in W2 W4; do
    if cmp -s /tmp/img-head.png /tmp/img-$v.png && cmp -s /tmp/hits-head.bin /tmp/hits-$v.bin; then echo "$m $l $v: same image and hits"; else echo "$m $l $v: DIFFERENT"; tail -2 /tmp/render-$v.txt; fi | tee -a $OUT/render.txt
  done
done; done
echo "all done at ${SECONDS}s" | tee -a $OUT/bench.txt
