#!/bin/bash
# CPU A/B of kernel dirs on compare.py's scenes, 512x512, 64 spp; sampling_ms per render.
for r in 1 2 3; do for d in "0:0" "1:0"; do for s in cornell gold glass; do for k in k0 k1 k4; do
  CLTRACE_KERNEL_DIR=/tmp/kv/$k /work/main/target/release/cltrace render /tmp/sc512/$s/scene.toml -q --device $d --max-bounces 8 -o /tmp/kv/cpu-$k-$s.pfm --json /tmp/kv/jc.json > /dev/null 2>&1
  python3 -c "import json;j=json.load(open('/tmp/kv/jc.json'));print('[r$r $d $s $k] %.2f Msamples/s'%(512*512*64/j['sampling_ms']/1e3))"
done; done; done; done
