#!/bin/bash
# run70: the shortest form of run68 for a lease of a few minutes: main, new (the tile
# entries pass) and E (the walk inside trace_primary), alternated, primary rays on bin64 and
# cwbvh; the bin64 renders compared after round 2; no tinybvh.
set -u
REPO=$PWD
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace-main; xz -dc .gpu/cltrace-new.xz > /tmp/cltrace-new; chmod +x /tmp/cltrace-*
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
run() { local v=$1; shift
  if [ $v = E ]; then CLTRACE_KERNEL_DIR=$REPO/.gpu/k-E timeout 60 /tmp/cltrace-new "$@"; else timeout 60 /tmp/cltrace-$v "$@"; fi; }
C="--methods cl-bvh --layouts bin64,cwbvh --resolutions 1920x1080 --devices gpu --repetitions 20 --rays primary"
for r in 1 2 3 4; do
  for v in main new E; do
    run $v bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  echo "round $r done at ${SECONDS}s" | tee -a $OUT/bench.txt
  if [ $r = 2 ]; then for m in $B $D; do for v in main new E; do
    run $v render $m --device gpu --layout bin64 --width 1920 --height 1080 --shade normal -o /tmp/img-$v.png --hits /tmp/hits-$v.bin > /tmp/render-$v.txt 2>&1; done
    for v in new E; do if cmp -s /tmp/img-main.png /tmp/img-$v.png && cmp -s /tmp/hits-main.bin /tmp/hits-$v.bin; then echo "$m bin64 $v: same image and hits"; else echo "$m bin64 $v: DIFFERENT"; tail -2 /tmp/render-$v.txt; fi | tee -a $OUT/render.txt; done; done; fi
done
