#!/bin/bash
# Item 2: main (cltrace-head.xz, 9f0080d) against the paired-shadow commit (cltrace-paired.xz,
# dbf3acc: GPUs' bin64 path programs trace each shadow ray with the next ray in one
# traversal) on compare.py's three scenes, 1920x1080, 256 spp, --max-bounces 8, bin64,
# alternated rounds and PFM compares; then compare.py speed against Mitsuba 3 cuda_ad_rgb
# with each binary; on an H200 item 4 (run74.sh: not reached this session).
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-3}
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee -a $OUT/gpu.txt
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz) &
for v in head paired; do xz -dc .gpu/cltrace-$v.xz > /tmp/cltrace-$v; chmod +x /tmp/cltrace-$v; done
cp /tmp/cltrace-head /tmp/cltrace
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > $OUT/scenes.txt 2>&1
for r in $(seq $ROUNDS); do for v in head paired; do for s in cornell gold glass; do
  timeout 60 /tmp/cltrace-$v render /tmp/sc/$s/scene.toml -q --device gpu --layout bin64 --max-bounces 8 -o /tmp/x-$v-$s.pfm --json /tmp/j.json > /tmp/log-$v-$s.txt 2>&1 || tail -3 /tmp/log-$v-$s.txt | tee -a $OUT/path.txt
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s (sampling %.1f ms)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms']))" | tee -a $OUT/path.txt
  rm -f /tmp/j.json
done; done; echo "round $r done at ${SECONDS}s" | tee -a $OUT/path.txt; done
for s in cornell gold glass; do cmp -s /tmp/x-head-$s.pfm /tmp/x-paired-$s.pfm && echo "$s: same image" || echo "$s: DIFFERENT"; done | tee -a $OUT/path.txt
wait
S="--variant cuda_ad_rgb --devices gpu --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3"
for v in head paired; do
  PYTHONPATH=/tmp/site timeout 200 python3 scripts/mitsuba/compare.py speed $S --cltrace /tmp/cltrace-$v --out /tmp/spm 2>&1 | grep -vE "^\s*$" | tail -12 | tee $OUT/mitsuba-$v.txt
  echo "$v compare done at ${SECONDS}s" | tee -a $OUT/path.txt
done
if nvidia-smi -L | grep -q H200 && [ $SECONDS -lt 400 ]; then CONFIGS=16x8 ROUNDS=2 bash .gpu/run74.sh; fi
echo "run83 done at ${SECONDS}s" | tee -a $OUT/path.txt
