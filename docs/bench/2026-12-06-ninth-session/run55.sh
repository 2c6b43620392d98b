#!/bin/bash
# The watertight test's shear and depth as fused multiply-adds (k-F: cl/ of the change) against
# main's kernels, alternated in one lease: cltrace bench (bin64, primary and diffuse-16, both
# meshes) four rounds, then render's path program on compare.py's three scenes, three rounds.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
B=.gpu/scenes/stanford_bunny.obj.gz; D=.gpu/scenes/stanford_dragon.obj.gz
C="--methods cl-bvh --layouts bin64 --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 20"
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null
for r in 1 2 3 4; do
  for v in main F; do
    if [ $v = main ]; then K=""; else K="CLTRACE_KERNEL_DIR=$REPO/.gpu/k-$v"; fi
    env $K timeout 60 /tmp/cltrace bench $B $D $C 2>&1 | grep -E "^\| stanford|rror" | awk -F'|' -v t="[r$r $v]" '{printf "%s %s %s median %s Mrays/s %s\n", t, $2, $8, $12, $14}' | tee -a $OUT/bench.txt
  done
done
echo "bench done at ${SECONDS}s"
for r in 1 2 3; do
  for v in main F; do
    for s in cornell gold glass; do
      if [ $v = main ]; then K=""; else K="CLTRACE_KERNEL_DIR=$REPO/.gpu/k-$v"; fi
      env $K timeout 60 /tmp/cltrace render /tmp/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/x-$v-$s.exr --json /tmp/j.json 2>&1 | tail -2
      python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s (sampling %.1f ms)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms']))" | tee -a $OUT/path.txt
    done
  done
done
echo "done at ${SECONDS}s"
