#!/bin/bash
# Item 1 scenes (compare.py scenes --size 512x512 --spp 64 into /tmp/sc5): wide8, bin64 and
# bin64 with the paired shadow ray on PoCL, two rounds.
B=${B:-target/release/cltrace}; KP=${KP:-.gpu/k-P}  # k-P: main's cl/ with ../../2026-12-07-local-scene/paired-shadow.diff
for r in 1 2; do for s in gold glass; do
 for v in w8 b64 b64P; do
  case $v in w8) E="";L=wide8;; b64) E="";L=bin64;; b64P) E="CLTRACE_KERNEL_DIR=$KP CLTRACE_BUILD_OPTIONS=-DPAIRED_SHADOW";L=bin64;; esac
  env $E $B render /tmp/sc5/$s/scene.toml -q --device ${DEV:-1:0} --layout $L --max-bounces 8 -o /tmp/l.pfm --json /tmp/l.json >/dev/null 2>&1
  python3 -c "import json;j=json.load(open('/tmp/l.json'));print('r$r $s $v %.2f Msamples/s'%(512*512*64/j['sampling_ms']/1e3))"
 done; done; done
