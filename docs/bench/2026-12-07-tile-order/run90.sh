#!/bin/bash
# run90: main (cltrace-main.xz, a8d8e11) against the samples' tiles taken costliest first
# (cltrace-lpt.xz): path renders of compare.py's three scenes at 1920x1080, 256 spp,
# alternated rounds, PFMs compared; on an H200 then run89.sh's items 4 and 2, and item 2
# with the lpt binary.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-3}
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
for v in main lpt; do xz -dc .gpu/cltrace-$v.xz > /tmp/cltrace-$v; chmod +x /tmp/cltrace-$v; done
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null 2>&1
for r in $(seq $ROUNDS); do for v in main lpt; do for s in cornell gold glass; do
  timeout 60 /tmp/cltrace-$v render /tmp/sc/$s/scene.toml -v --device gpu --max-bounces 8 -o /tmp/st-$v-$s.pfm --json /tmp/j.json 2>&1 | grep -E "^load" | grep -oE "samples [0-9.]+ ms, read-back [0-9.]+ ms, launch [0-9.]+ ms" | sed "s/^/[stages r$r $v $s] /" >> $OUT/stages.txt
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s (sampling %.1f ms, wall %.1f ms)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms'],j['wall_ms']))" | tee -a $OUT/stages.txt; rm -f /tmp/j.json
done; done; done
for s in cornell gold glass; do cmp -s /tmp/st-main-$s.pfm /tmp/st-lpt-$s.pfm && echo "$s: same image" || echo "$s: DIFFERENT"; done | tee -a $OUT/stages.txt
echo "stages done at ${SECONDS}s" | tee -a $OUT/stages.txt
if nvidia-smi -L | grep -q H200; then
  ROUNDS=3 UNTIL=400 CROUNDS=1 bash .gpu/run89.sh
  PYTHONPATH=/tmp/site timeout 150 python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace /tmp/cltrace-lpt --devices gpu \
    --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3 --out /tmp/spm 2>&1 | grep -vE "^\s*$" | tail -12 | tee $OUT/mitsuba-lpt.txt
fi
echo "run90 done at ${SECONDS}s" | tee -a $OUT/stages.txt
