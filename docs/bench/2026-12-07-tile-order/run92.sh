#!/bin/bash
# run92: (1) main (cltrace-main.xz, a8d8e11) against the first sample's ray counts read on
# a second queue by a thread (cltrace-cnt.xz), compare.py's three scenes, 1920x1080, 256
# spp, alternated rounds, PFMs compared; (2) run91.sh's tile orders (none, golden, rows).
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-3}
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
for v in main cnt; do xz -dc .gpu/cltrace-$v.xz > /tmp/cltrace-$v; chmod +x /tmp/cltrace-$v; done
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null 2>&1
for r in $(seq $ROUNDS); do for v in main cnt; do for s in cornell gold glass; do
  timeout 60 /tmp/cltrace-$v render /tmp/sc/$s/scene.toml -v --device gpu --max-bounces 8 -o /tmp/st-$v-$s.pfm --json /tmp/j.json 2>&1 | grep -E "^load" | grep -oE "samples [0-9.]+ ms, read-back [0-9.]+ ms, launch [0-9.]+ ms" | sed "s/^/[stages r$r $v $s] /" >> $OUT/stages.txt
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s (sampling %.1f ms, rays %d)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms'],j['rays']))" | tee -a $OUT/stages.txt; rm -f /tmp/j.json
done; done; done
for s in cornell gold glass; do cmp -s /tmp/st-main-$s.pfm /tmp/st-cnt-$s.pfm && echo "$s: same image" || echo "$s: DIFFERENT"; done | tee -a $OUT/stages.txt
echo "stages done at ${SECONDS}s" | tee -a $OUT/stages.txt
ORDERS="none golden rows" ROUNDS=${ROUNDS91:-2} bash .gpu/run91.sh > /dev/null 2>&1
cat $OUT/order.txt
