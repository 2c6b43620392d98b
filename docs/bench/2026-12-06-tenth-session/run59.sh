#!/bin/bash
# Camera rays with z as their dominant axis traced by a loop whose vertex permutation is the
# identity (k-I: the kx/ky swap dropped, which changes no hit, and bin64's coherent trace
# specialized), the swap dropped alone (k-J), main's kernels; alternated, with tinybvh's
# Aila-Laine kernel on the same rays in each round; then render's path program on
# compare.py's three scenes (main and I).
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
xz -dc .gpu/tinybvh/harness.xz > /tmp/harness; xz -dc .gpu/tinybvh/raydump.xz > /tmp/raydump; chmod +x /tmp/harness /tmp/raydump
mkdir -p /tmp/data
(/tmp/raydump .gpu/scenes/stanford_bunny.obj.gz /tmp/data/bunny && /tmp/raydump .gpu/scenes/stanford_dragon.obj.gz /tmp/data/dragon) > $OUT/raydump.txt 2>&1
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null &
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 20"
for r in 1 2 3 4; do
  for v in main I J; do
    if [ $v = main ]; then K=""; else K="CLTRACE_KERNEL_DIR=$REPO/.gpu/k-$v"; fi
    env $K timeout 60 /tmp/cltrace bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s median %s min %s Mrays/s %s\n", t, $2, $8, $12, $13, $14}' | tee -a $OUT/bench.txt
  done
  (cd .gpu/tinybvh && for m in bunny dragon; do timeout 60 /tmp/harness /tmp/data/$m tiles d16 2>&1 | grep -E "tinybvh gpu|rror" | sed "s/^/[tinybvh r$r] /"; done) | tee -a $OUT/tinybvh.txt
  echo "round $r done at ${SECONDS}s"
done
wait
for r in 1 2; do
  for v in main I; do
    for s in cornell gold glass; do
      if [ $v = main ]; then K=""; else K="CLTRACE_KERNEL_DIR=$REPO/.gpu/k-$v"; fi
      env $K timeout 60 /tmp/cltrace render /tmp/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/x-$v-$s.exr --json /tmp/j.json 2>&1 | tail -2
      python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s (sampling %.1f ms)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms']))" | tee -a $OUT/path.txt
    done
  done
done
echo "done at ${SECONDS}s"
