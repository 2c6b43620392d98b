#!/bin/bash
# Tile entry nodes for camera rays (cltrace-new.xz): tile_entries finds, per work-group's
# tile, the node where a walk down the tree meets two children in the tile's frustum; the
# tile's rays start there. Against main (cltrace.xz), alternated; tinybvh each round.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace-main; xz -dc .gpu/cltrace-new.xz > /tmp/cltrace-new; chmod +x /tmp/cltrace-*
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1 &
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
for m in $B $D; do for l in bin32 bin64 wide8 cwbvh; do for v in main new; do
  timeout 60 /tmp/cltrace-$v render $m --device gpu --layout $l --width 1920 --height 1080 --shade normal -o /tmp/img-$v.png --hits /tmp/hits-$v.bin > /tmp/render-$v.txt 2>&1
done
if cmp -s /tmp/img-main.png /tmp/img-new.png && cmp -s /tmp/hits-main.bin /tmp/hits-new.bin; then echo "$m $l: same image and hits"; else echo "$m $l: DIFFERENT"; tail -2 /tmp/render-new.txt; fi | tee -a $OUT/render.txt
done; done
wait
C="--methods cl-bvh --layouts bin64,cwbvh --resolutions 1920x1080 --devices gpu --repetitions 20"
for r in 1 2 3 4; do
  for v in main new; do
    R=primary; [ $r = 1 ] && R=primary,diffuse-16
    timeout 60 /tmp/cltrace-$v bench $B $D $C --rays $R 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 60 /tmp/harness /tmp/data/$m tiles scan 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s"
done
