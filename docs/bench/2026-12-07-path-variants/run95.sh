#!/bin/bash
# run95: the path kernel's variants (CLTRACE_KERNEL_DIR, same images): k0 main's kernels; k1
# the samples' sums in local memory; k2 path and shadow rays traced with unpipelined leaves
# (incoherent false); k3 both; k4 the camera rays from their tile's entry node (prototype of 2026-12-07-sample-entries); k5 all three; k6 every ray traced twice and k7 every vertex shaded twice (the shares of the time); then main's kernels with --max-leaf-size 1, 2, 4 (default 8), and --optimize 8 (reinsertion).
# compare.py's three scenes at 1920x1080, 256 spp, --max-bounces 8, alternated rounds; then
# compare.py speed against Mitsuba 3 cuda_ad_rgb with main's binary (0fbff22).
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-3}
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz) &
xz -dc .gpu/cltrace-m95.xz > /tmp/cltrace; chmod +x /tmp/cltrace
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null 2>&1
one() { # name, kernel dir, extra args, scene, round
  CLTRACE_KERNEL_DIR=$REPO/.gpu/kv/$2 timeout 60 /tmp/cltrace render /tmp/sc/$4/scene.toml -q --device gpu --max-bounces 8 $3 -o /tmp/st-$1-$4.pfm --json /tmp/j.json > /dev/null 2>&1
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$5 $1 $4] %.1f Msamples/s (sampling %.1f ms, rays %d)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms'],j['rays']))" | tee -a $OUT/paths.txt; rm -f /tmp/j.json
}
for r in $(seq $ROUNDS); do for s in cornell gold glass; do
  for k in ${KS:-k0 k1 k2 k3 k4 k5 k6 k7}; do one $k $k "" $s $r; done
  for l in ${LEAVES:-1 2 4}; do one leaf$l k0 "--max-leaf-size $l" $s $r; done
  [ ${OPT:-1} = 1 ] && one opt8 k0 "--optimize 8" $s $r
done; echo "round $r done at ${SECONDS}s" | tee -a $OUT/paths.txt; done
for k in ${KS:-k0 k1 k2 k3 k4 k5 k6 k7}; do [ $k = k0 ] && continue; for s in cornell gold glass; do cmp -s /tmp/st-k0-$s.pfm /tmp/st-$k-$s.pfm && echo "$k $s: same image" || echo "$k $s: DIFFERENT"; done; done | tee -a $OUT/paths.txt
wait
[ $SECONDS -lt ${UNTIL:-300} ] && PYTHONPATH=/tmp/site timeout 200 python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace /tmp/cltrace --devices gpu \
  --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3 --out /tmp/spm 2>&1 | grep -vE "^\s*$" | tail -12 | tee $OUT/mitsuba.txt
echo "run95 done at ${SECONDS}s" | tee -a $OUT/paths.txt
