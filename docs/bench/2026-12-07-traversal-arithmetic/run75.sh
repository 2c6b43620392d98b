#!/bin/bash
# The slab test in fused multiply-adds with a per-ray error bound (k-F, bin64.cl only)
# against the head's kernels (cltrace-head.xz, 93d1383): camera and diffuse-16 rays,
# alternated, tinybvh each round (items 3 and 4); renders compared; then render's path
# program on compare.py's three scenes (head and F, two rounds; item 2's programs).
# The second run: VARIANTS="head Q" LAYOUTS=bin64,cwbvh PATHS=0 (k-Q: cwbvh.cl's bytes made
# floats without a conversion instruction).
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-3}; VARIANTS=${VARIANTS:-head F}
LAYOUTS=${LAYOUTS:-bin64}; PATHS=${PATHS:-1}
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace-head.xz > /tmp/cltrace; chmod +x /tmp/cltrace
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1 &
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null 2>&1 &
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts $LAYOUTS --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 20"
k() { if [ $1 = head ]; then echo ""; else echo "CLTRACE_KERNEL_DIR=$REPO/.gpu/k-$1"; fi; }
for r in $(seq $ROUNDS); do
  for v in $VARIANTS; do
    env $(k $v) timeout 120 /tmp/cltrace bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  [ $r = 1 ] && wait
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 150 /tmp/harness /tmp/data/$m tiles scan d16 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s" | tee -a $OUT/bench.txt
done
for l in ${LAYOUTS//,/ }; do R="--device gpu --layout $l --width 1920 --height 1080 --shade normal"
for m in $B $D; do for v in $VARIANTS; do
  env $(k $v) timeout 60 /tmp/cltrace render $m $R -o /tmp/img-$v.png --hits /tmp/hits-$v.bin > /tmp/render-$v.txt 2>&1
  if cmp -s /tmp/img-head.png /tmp/img-$v.png && cmp -s /tmp/hits-head.bin /tmp/hits-$v.bin; then echo "$m $l $v: same image and hits"; else echo "$m $l $v: DIFFERENT"; tail -2 /tmp/render-$v.txt; fi | tee -a $OUT/render.txt
done; done; done
[ $PATHS = 1 ] && for r in 1 2; do for v in $VARIANTS; do for s in cornell gold glass; do
  env $(k $v) timeout 60 /tmp/cltrace render /tmp/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/x-$v-$s.exr --json /tmp/j.json 2>&1 | tail -2
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s (sampling %.1f ms)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms']))" | tee -a $OUT/path.txt
done; done; done
[ $PATHS = 1 ] && for s in cornell gold glass; do for v in $VARIANTS; do cmp -s /tmp/x-head-$s.exr /tmp/x-$v-$s.exr && echo "$s $v: same image" || echo "$s $v: DIFFERENT"; done; done | tee -a $OUT/path.txt
echo "all done at ${SECONDS}s" | tee -a $OUT/bench.txt
