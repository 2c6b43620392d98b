#!/bin/bash
# run87: where a path render's samples stage goes on the host: a timeline of render_samples
# (cltrace-tl.xz: the prep commit with CLTRACE_TIMELINE prints, and CLTRACE_LAUNCH_MS for
# the launch target), compare.py's three scenes, 1920x1080, 256 spp, targets 100 and 250 ms,
# two rounds; then run86.sh's alternation (and on an H200 items 2-4).
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
xz -dc .gpu/cltrace-tl.xz > /tmp/cltrace-tl; chmod +x /tmp/cltrace-tl
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null 2>&1
for r in 1; do for L in 100; do for s in cornell gold glass; do
  echo "== r$r $s target $L" | tee -a $OUT/timeline.txt
  CLTRACE_LAUNCH_MS=$L CLTRACE_TIMELINE=1 timeout 60 /tmp/cltrace-tl render /tmp/sc/$s/scene.toml -q --device gpu --max-bounces 8 -o /tmp/tl.pfm --json /tmp/j.json 2>&1 | grep -E "^TL" | tee -a $OUT/timeline.txt
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[tl r$r $s $L] %.1f Msamples/s (sampling %.1f ms)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms']))" | tee -a $OUT/timeline.txt; rm -f /tmp/j.json
done; done; done
ROUNDS=${ROUNDS:-3} bash .gpu/run86.sh > /dev/null 2>&1
grep -h "Msamples\|same\|DIFF\|done" $OUT/stages.txt
