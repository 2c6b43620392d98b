#!/bin/bash
# One division a ray in the watertight test's setup instead of three: main ("old") against the
# change ("new"), bench primary and diffuse-16 rays (bin64) and path tracing, alternated rounds.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
xz -dc .gpu/cltrace.xz > /tmp/old; xz -dc .gpu/cltrace-new.xz > /tmp/new; chmod +x /tmp/old /tmp/new
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
for b in old new; do /tmp/$b bench .gpu/scenes/stanford_bunny.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 320x240 --devices gpu >/dev/null 2>&1; done
for r in 1 2 3; do
  for b in old new; do
    [ $r = 2 ] && b=$([ $b = old ] && echo new || echo old)
    timeout 100 /tmp/$b bench .gpu/scenes/stanford_bunny.obj.gz .gpu/scenes/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 \
      --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu 2>&1 | grep -E "^\| stanford" | cut -d'|' -f2,8,14 | sed "s/^/[$b r$r] /" | tee -a $OUT/bench.txt
  done
done
for r in 1 2; do
  for b in old new; do
    for s in cornell gold glass; do
      /tmp/$b render .gpu/sp/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/o.png --json /tmp/j.json >/dev/null 2>&1
      python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[$b r$r] $s', round(j['sampling_ms'],1))" | tee -a $OUT/paths.txt
    done
  done
done
