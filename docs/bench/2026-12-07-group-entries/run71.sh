#!/bin/bash
# Camera rays' tile entries found in each work-group (GROUP_ENTRIES) against the pass, on
# every layout. main = no entries (cltrace.xz, 5b4ff34); head = the pass (cltrace-new.xz,
# a362c5b); G = this session's build with GROUP_ENTRIES on GPUs for every layout
# (cltrace-gall.xz). Bench rounds alternated, tinybvh each round; then the renders of G
# and head compared on every layout. Round 1 adds bin64's diffuse-16 rows and tinybvh's.
# A shorter run: LAYOUTS=bin64,cwbvh D16=0 ROUNDS=3. GBIN=cltrace-head runs the head's build
# (93d1383: GROUP_ENTRIES for bin32 and bin64 only) as G.
set -u
ROUNDS=${ROUNDS:-3}; LAYOUTS=${LAYOUTS:-bin32,bin64,wide4,wide8,cwbvh}; D16=${D16:-1}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
GBIN=${GBIN:-cltrace-gall}
for v in main:cltrace new:cltrace-new gall:$GBIN; do xz -dc .gpu/${v#*:}.xz > /tmp/cltrace-${v%%:*}; done; chmod +x /tmp/cltrace-*
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1 &
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts $LAYOUTS --rays primary --resolutions 1920x1080 --devices gpu --repetitions 20"
for r in $(seq $ROUNDS); do
  for v in main new gall; do
    timeout 120 /tmp/cltrace-$v bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  [ $r = 1 ] && wait
  [ $r = 1 ] && [ $D16 = 1 ] && timeout 120 /tmp/cltrace-gall bench $B $D --methods cl-bvh --layouts bin64 --rays diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r gall]" '{printf "%s %s %s %s median %s min %s Mrays/s %s\n", t, $2, $5, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  T="tiles scan"; [ $r = 1 ] && [ $D16 = 1 ] && T="tiles scan d16"
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 150 /tmp/harness /tmp/data/$m $T 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s" | tee -a $OUT/bench.txt
done
for m in $B $D; do for l in ${LAYOUTS//,/ }; do
  for v in new gall; do timeout 60 /tmp/cltrace-$v render $m --device gpu --layout $l --width 1920 --height 1080 --shade normal -o /tmp/img-$v.png --hits /tmp/hits-$v.bin > /tmp/render-$v.txt 2>&1; done
  if cmp -s /tmp/img-new.png /tmp/img-gall.png && cmp -s /tmp/hits-new.bin /tmp/hits-gall.bin; then echo "$m $l: same image and hits"; else echo "$m $l: DIFFERENT"; tail -2 /tmp/render-*.txt; fi | tee -a $OUT/render.txt
done; done
echo "all done at ${SECONDS}s" | tee -a $OUT/bench.txt
