#!/bin/bash
# run85: items 3 and 4 (run74.sh: cltrace bench bin64 against tinybvh's kernel on the same rays,
# the harness rebuilt this session), then on an H200 item 2 (compare.py speed against
# Mitsuba 3 cuda_ad_rgb). Main's binary (cltrace-head.xz, 9f0080d).
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz) &
# ptxas's register and spill counts of the path programs, main's and the paired commit's.
for v in head paired; do xz -dc .gpu/cltrace-$v.xz > /tmp/cltrace-$v; chmod +x /tmp/cltrace-$v; done
python3 scripts/mitsuba/compare.py scenes --out /tmp/sv --size 64x36 --spp 1 --scenes cornell,glass > /dev/null 2>&1
for v in head paired; do for s in cornell glass; do
  CLTRACE_BUILD_LOG=1 CLTRACE_KERNEL_CACHE=off CLTRACE_BUILD_OPTIONS=-cl-nv-verbose timeout 60 /tmp/cltrace-$v render /tmp/sv/$s/scene.toml -q --device gpu --layout bin64 --max-bounces 8 -o /tmp/v.pfm 2>&1 | grep -iE "ptxas|registers|spill|stack frame|build log" | sed "s/^/[$v $s] /" | tee -a $OUT/ptxas.txt
done; done
# Where a path render's samples stage goes besides the kernels (launch, read-back), 1080p
# 256 spp: main against the read-back in bands (cltrace-band.xz), alternated.
xz -dc .gpu/cltrace-band.xz > /tmp/cltrace-band; chmod +x /tmp/cltrace-band
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null 2>&1
for r in 1 2 3; do for v in head band; do for s in cornell gold glass; do
  timeout 60 /tmp/cltrace-$v render /tmp/sc/$s/scene.toml -v --device gpu --max-bounces 8 -o /tmp/st-$v-$s.pfm --json /tmp/j.json 2>&1 | grep -E "^load" | grep -oE "samples [0-9.]+ ms, read-back [0-9.]+ ms, launch [0-9.]+ ms" | sed "s/^/[stages r$r $v $s] /" | tee -a $OUT/stages.txt
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s (sampling %.1f ms)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms']))" | tee -a $OUT/stages.txt; rm -f /tmp/j.json
done; done; done
for s in cornell gold glass; do cmp -s /tmp/st-head-$s.pfm /tmp/st-band-$s.pfm && echo "$s: same image" || echo "$s: DIFFERENT"; done | tee -a $OUT/stages.txt
if nvidia-smi -L | grep -q H200; then R=${ROUNDS_H200:-1}; else R=${ROUNDS_H100:-1}; fi
CONFIGS="${CONFIGS:-16x8 32x4}" ROUNDS=$R bash .gpu/run74.sh
wait
if nvidia-smi -L | grep -q H200 && [ $SECONDS -lt 300 ]; then
  xz -dc .gpu/cltrace-head.xz > /tmp/cltrace; chmod +x /tmp/cltrace
  PYTHONPATH=/tmp/site timeout 200 python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace /tmp/cltrace --devices gpu \
    --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3 --out /tmp/spm 2>&1 | grep -vE "^\s*$" | tail -12 | tee $OUT/mitsuba.txt
fi
echo "run85 done at ${SECONDS}s" | tee -a $OUT/bench.txt
