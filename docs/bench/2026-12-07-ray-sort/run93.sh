#!/bin/bash
# run93 (run91 with the morton and blocks orders): the samples' tile order (cltrace-ord.xz: lpt branch with CLTRACE_TILE_ORDER=none
# (main's order), cost (costliest first), morton, blocks (16 x 8 tiles) added; golden (consecutive groups strided across the
# image by n/phi), rows (tile rows of 8 bands interleaved)): compare.py's three scenes at
# 1920x1080, 256 spp, and the dragon path-traced (64 spp), alternated rounds, PFMs compared.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-3}
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace-ord.xz > /tmp/cltrace-ord; chmod +x /tmp/cltrace-ord
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null 2>&1
for r in $(seq $ROUNDS); do for o in ${ORDERS:-none cost golden rows}; do
  for s in cornell gold glass; do
    CLTRACE_TILE_ORDER=$o timeout 60 /tmp/cltrace-ord render /tmp/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/st-$o-$s.pfm --json /tmp/j.json > /dev/null 2>&1
    python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $o $s] %.1f Msamples/s (sampling %.1f ms)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms']))" | tee -a $OUT/order.txt; rm -f /tmp/j.json
  done
  CLTRACE_TILE_ORDER=$o timeout 60 /tmp/cltrace-ord render .gpu/scenes/stanford_dragon.obj.gz -q --device gpu --shade path --spp 64 --width 1920 --height 1080 -o /tmp/st-$o-dragon.pfm --json /tmp/j.json > /dev/null 2>&1
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $o dragon] %.1f Msamples/s (sampling %.1f ms)'%(1920*1080*64/j['sampling_ms']/1e3,j['sampling_ms']))" | tee -a $OUT/order.txt; rm -f /tmp/j.json
done; done
for o in ${ORDERS:-none cost golden rows}; do [ $o = none ] && continue; for s in cornell gold glass dragon; do cmp -s /tmp/st-none-$s.pfm /tmp/st-$o-$s.pfm && echo "$o $s: same image" || echo "$o $s: DIFFERENT"; done; done | tee -a $OUT/order.txt
echo "run91 done at ${SECONDS}s" | tee -a $OUT/order.txt
