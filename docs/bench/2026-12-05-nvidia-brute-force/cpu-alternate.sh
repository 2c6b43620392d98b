#!/bin/bash
# usage: cpubench.sh label:kerneldir ... ; alternates configs, 2 rounds, after a warm-up
D="Portable Computing Language"
run() { local l=${1%%:*} k=${1#*:}
  for s in ${SCENES:-cornell gold glass}; do
    if [ "$k" = base ]; then unset CLTRACE_KERNEL_DIR; else export CLTRACE_KERNEL_DIR=$k; fi
    /work/main/target/release/cltrace render /tmp/sp5/$s/scene.toml -q --device "$D" --max-bounces 8 -o /tmp/o_${l}_$s.pfm --json /tmp/r.json $EXTRA || { echo "$l $s FAILED"; continue; }
    python3 -c "import json;r=json.load(open('/tmp/r.json'));print('$2 $l $s %.3f' % (512*512*64/r['sampling_ms']/1e3))"
  done; }
for c in "$@"; do SCENES=cornell run $c w >/dev/null; done
for round in 1 2; do for c in "$@"; do run $c $round; done; done
