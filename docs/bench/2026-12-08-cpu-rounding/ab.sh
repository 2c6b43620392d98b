#!/bin/bash
# CPU A/B of binaries /tmp/cltrace-<name> (args) on compare.py's scenes, 512x512, 64 spp; Msamples/s per render.
R=${R:-3}; DEVS=${DEVS:-"0:0 1:0"}
for r in $(seq $R); do for d in $DEVS; do for s in cornell gold glass; do for k in "$@"; do
  /tmp/cltrace-$k render /tmp/sc512/$s/scene.toml -q --device $d --max-bounces 8 -o /tmp/abb-$k-$s.pfm --json /tmp/abb.json > /dev/null 2>&1
  python3 -c "import json;j=json.load(open('/tmp/abb.json'));print('[r$r $d $s $k] %.3f'%(512*512*64/j['sampling_ms']/1e3))"
done; done; done; done
