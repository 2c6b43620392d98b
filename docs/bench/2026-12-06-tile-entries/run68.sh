#!/bin/bash
# Tile entry nodes for camera rays on the GPU. main = before (cltrace.xz, 5b4ff34);
# new = the head (cltrace-new.xz: a tile_entries pass before trace_primary); E = new with
# kernels k-E (each work-group's first work-item walks to its entry inside trace_primary,
# shared through local memory; the separate pass returns at once). Bench rounds first,
# alternated, tinybvh each round, the renders compared between rounds, so that a short
# lease still returns the first round.
# For a short lease: ROUNDS=3 (default 4); DIFFUSE=0 leaves out round 1's diffuse-16 rays;
# TINYBVH=0 leaves out tinybvh and its ray dump. The shortest answer to whether the entries
# pay on a GPU, about two minutes: DIFFUSE=0 TINYBVH=0 ROUNDS=2 bash run68.sh.
set -u
ROUNDS=${ROUNDS:-4}; DIFFUSE=${DIFFUSE:-1}; TINYBVH=${TINYBVH:-1}
REPO=$PWD
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace-main; xz -dc .gpu/cltrace-new.xz > /tmp/cltrace-new; chmod +x /tmp/cltrace-*
if [ $TINYBVH = 1 ]; then
  xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
  mkdir -p /tmp/data
  (/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1 &
fi
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
run() { local v=$1; shift
  if [ $v = E ]; then CLTRACE_KERNEL_DIR=$REPO/.gpu/k-E timeout 60 /tmp/cltrace-new "$@"; else timeout 60 /tmp/cltrace-$v "$@"; fi; }
renders() { for m in $B $D; do for l in "$@"; do for v in main new E; do
  run $v render $m --device gpu --layout $l --width 1920 --height 1080 --shade normal -o /tmp/img-$v.png --hits /tmp/hits-$v.bin > /tmp/render-$v.txt 2>&1
  done
  for v in new E; do if cmp -s /tmp/img-main.png /tmp/img-$v.png && cmp -s /tmp/hits-main.bin /tmp/hits-$v.bin; then echo "$m $l $v: same image and hits"; else echo "$m $l $v: DIFFERENT"; tail -2 /tmp/render-$v.txt; fi | tee -a $OUT/render.txt; done
done; done; }
C="--methods cl-bvh --layouts bin64,cwbvh --resolutions 1920x1080 --devices gpu --repetitions 20"
for r in $(seq $ROUNDS); do
  for v in main new E; do
    R=primary; [ $r = 1 ] && [ $DIFFUSE = 1 ] && R=primary,diffuse-16
    run $v bench $B $D $C --rays $R 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  [ $r = 1 ] && wait
  [ $TINYBVH = 1 ] && (cd .gpu/tinybvh && for m in bunny dragon; do timeout 60 /tmp/harness /tmp/data/$m tiles scan 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s" | tee -a $OUT/bench.txt
  [ $r = 1 ] && renders bin64
  [ $r = 2 ] && renders cwbvh
  [ $r = 3 ] && renders bin32 wide8
done
