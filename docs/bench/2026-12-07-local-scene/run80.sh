#!/bin/bash
# Item 2: each shadow ray traced with the path's next ray in one traversal (k-P: bin64.cl's
# trace_two, integrator.cl under -D PAIRED_SHADOW) against the head's kernels
# (cltrace-head.xz, 93d1383), on compare.py's three scenes at 1920x1080, 256 spp,
# --max-bounces 8, bin64, alternated rounds. Variants: head; P.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-3}; SIZE=${SIZE:-1920x1080}; DEV=${DEV:-gpu}; W=${SIZE%x*}; H=${SIZE#*x}; VARIANTS=${VARIANTS:-head P}
nvidia-smi 2>/dev/null --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee -a $OUT/gpu.txt
CL=${CL:-/tmp/cltrace}; [ $CL = /tmp/cltrace ] && { xz -dc .gpu/cltrace-head.xz > /tmp/cltrace; chmod +x /tmp/cltrace; }
${PY:-python3} scripts/mitsuba/compare.py scenes --out /tmp/sc --size $SIZE --spp 256 --scenes cornell,gold,glass > $OUT/scenes.txt 2>&1
# Runs cltrace with variant $1's kernels and options, the rest of the line its arguments.
with() { local v=$1; shift
  case $v in
    head) "$@";;
    P) CLTRACE_KERNEL_DIR=$REPO/.gpu/k-P CLTRACE_BUILD_OPTIONS="-DPAIRED_SHADOW" "$@";;
  esac; }
for r in $(seq $ROUNDS); do for v in $VARIANTS; do for s in cornell gold glass; do
  with $v timeout 60 $CL render /tmp/sc/$s/scene.toml -q --device $DEV --layout bin64 --max-bounces 8 -o /tmp/x-$v-$s.pfm --json /tmp/j.json > /tmp/log-$v-$s.txt 2>&1 || tail -3 /tmp/log-$v-$s.txt | tee -a $OUT/path.txt
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$r $v $s] %.1f Msamples/s (sampling %.1f ms)'%($W*$H*256/j['sampling_ms']/1e3,j['sampling_ms']))" | tee -a $OUT/path.txt
  rm -f /tmp/j.json
done; done; echo "round $r done at ${SECONDS}s" | tee -a $OUT/path.txt; done
for s in cornell gold glass; do for v in $VARIANTS; do cmp -s /tmp/x-head-$s.pfm /tmp/x-$v-$s.pfm && echo "$s $v: same image" || echo "$s $v: DIFFERENT"; done; done | tee -a $OUT/path.txt
echo "all done at ${SECONDS}s" | tee -a $OUT/path.txt
