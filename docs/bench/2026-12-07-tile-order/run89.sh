#!/bin/bash
# run89, for an H200: item 4 (run74m.sh = run74.sh with main's binary a8d8e11, 16x8,
# alternated rounds against tinybvh; item 3's diffuse-16 in round 1), then item 2
# (compare.py speed against Mitsuba 3 cuda_ad_rgb) with main's binary.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz) &
CONFIGS=16x8 ROUNDS=${ROUNDS:-3} bash .gpu/run74m.sh
wait
xz -dc .gpu/cltrace-main.xz > /tmp/cltrace-main; chmod +x /tmp/cltrace-main
for r in $(seq ${CROUNDS:-1}); do
  [ $SECONDS -lt ${UNTIL:-300} ] || break
  PYTHONPATH=/tmp/site timeout 150 python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace /tmp/cltrace-main --devices gpu \
    --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3 --out /tmp/spm 2>&1 | grep -vE "^\s*$" | tail -12 | tee $OUT/mitsuba-r$r.txt
  echo "compare round $r done at ${SECONDS}s" | tee -a $OUT/bench.txt
done
echo "run89 done at ${SECONDS}s" | tee -a $OUT/bench.txt
