#!/bin/bash
# The triangle rows as 12-byte vload3s (docs/bench/2026-12-06-indexed-triangles/rows-vload3.diff)
# in render's capped path program: compare.py's three scenes at 1080p, 256 spp, 8 bounces, main
# and the variant (CLTRACE_KERNEL_DIR) alternated, three rounds; Msamples/s of the samples stage.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
[ -x /tmp/cltrace ] || { xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace; }
nvidia-smi --query-gpu=name,uuid --format=csv,noheader
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null
for r in 0 1 2 3; do
  for v in main B; do
    for s in cornell gold glass; do
      if [ $v = main ]; then K=""; else K="CLTRACE_KERNEL_DIR=$REPO/.gpu/k-$v"; fi
      env -u CLTRACE_KERNEL_DIR $K timeout 60 /tmp/cltrace render /tmp/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/x-$v-$s.exr --json /tmp/j.json 2>&1 | tail -2
      python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s (sampling %.1f ms)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms']))" | tee -a $OUT/vload3.txt
    done
  done
done
