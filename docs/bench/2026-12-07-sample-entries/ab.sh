#!/bin/bash
# usage: ab.sh rounds bin... ; alternated renders of cornell,gold,glass on PoCL and Intel; prints sampling_ms
R=$1; shift
for r in $(seq $R); do
 for s in cornell gold glass; do for d in 0:0 1:0; do for b in "$@"; do
  $b render /tmp/sc/$s/scene.toml -q --device $d --max-bounces 8 -o /tmp/ab.exr --json /tmp/ab.json >/dev/null 2>&1 || echo FAIL $b $s
  echo "$s $d $(basename $b) $(python3 -c "import json;print(json.load(open('/tmp/ab.json'))['sampling_ms'])")"
 done; done; done
done
