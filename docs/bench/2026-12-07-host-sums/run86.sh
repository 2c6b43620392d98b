#!/bin/bash
# run86: main (cltrace-head.xz, 9f0080d) against the read-back made ready during the launches
# (cltrace-prep.xz): path renders of compare.py's three scenes at 1920x1080, 256 spp,
# `-v` stage times and samples/s, alternated rounds, PFMs compared. On an H200 then items
# 3 and 4 (run74.sh against tinybvh, shapes 16x8 and 32x4) and item 2 (compare.py speed,
# both binaries).
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-3}
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz) &
for v in head prep; do xz -dc .gpu/cltrace-$v.xz > /tmp/cltrace-$v; chmod +x /tmp/cltrace-$v; done
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null 2>&1
for r in $(seq $ROUNDS); do for v in head prep; do for s in cornell gold glass; do
  timeout 60 /tmp/cltrace-$v render /tmp/sc/$s/scene.toml -v --device gpu --max-bounces 8 -o /tmp/st-$v-$s.pfm --json /tmp/j.json 2>&1 | grep -E "^load" | grep -oE "samples [0-9.]+ ms, read-back [0-9.]+ ms, launch [0-9.]+ ms" | sed "s/^/[stages r$r $v $s] /" | tee -a $OUT/stages.txt
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s (sampling %.1f ms, wall %.1f ms)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms'],j['wall_ms']))" | tee -a $OUT/stages.txt; rm -f /tmp/j.json
done; done; done
for s in cornell gold glass; do cmp -s /tmp/st-head-$s.pfm /tmp/st-prep-$s.pfm && echo "$s: same image" || echo "$s: DIFFERENT"; done | tee -a $OUT/stages.txt
echo "stages done at ${SECONDS}s" | tee -a $OUT/stages.txt
if nvidia-smi -L | grep -q H200; then
  CONFIGS="16x8 32x4" ROUNDS=${ROUNDS74:-4} bash .gpu/run74.sh
  wait
  S="--variant cuda_ad_rgb --devices gpu --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3"
  for v in head prep; do
    PYTHONPATH=/tmp/site timeout 200 python3 scripts/mitsuba/compare.py speed $S --cltrace /tmp/cltrace-$v --out /tmp/spm 2>&1 | grep -vE "^\s*$" | tail -12 | tee $OUT/mitsuba-$v.txt
    echo "$v compare done at ${SECONDS}s" | tee -a $OUT/stages.txt
  done
fi
wait
echo "run86 done at ${SECONDS}s" | tee -a $OUT/stages.txt
