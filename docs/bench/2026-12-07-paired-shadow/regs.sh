#!/bin/bash
# The register caps of the GPUs' sample programs (-cl-nv-maxrregcount, NV_SAMPLE_REGISTERS:
# 64 on main), on the same lease right after run83.sh (its binaries and scenes in /tmp):
# first the paired-shadow commit at 56-96 against main at 56 and 72 (regs-paired.txt),
# then main alone, none to 128 (regs-main.txt; "none" keeps the host's 64). Two rounds.
VARIANTS=${VARIANTS:-"head:56 paired:56 paired:64 paired:72 paired:96 head:72"}
for r in 1 2; do for v in $VARIANTS; do b=${v%:*}; rr=${v#*:}; for s in cornell gold glass; do
  O=""; [ $rr != none ] && O="-cl-nv-maxrregcount=$rr"
  CLTRACE_BUILD_OPTIONS="$O" timeout 60 /tmp/cltrace-$b render /tmp/sc/$s/scene.toml -q --device gpu --layout bin64 --max-bounces 8 -o /tmp/y.pfm --json /tmp/j.json > /tmp/l.txt 2>&1 || tail -2 /tmp/l.txt
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s'%(1920*1080*256/j['sampling_ms']/1e3))" | tee -a $OUT/regs.txt
  rm -f /tmp/j.json
done; done; done
# regs-main.txt: VARIANTS="head:none head:64 head:72 head:80 head:96 head:128"
