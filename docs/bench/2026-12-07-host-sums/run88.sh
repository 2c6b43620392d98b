#!/bin/bash
# run88, for an H200: item 4 (run74.sh, 16x8, main's binary against tinybvh, alternated
# rounds; item 3 in round 1), then item 2 (compare.py speed against Mitsuba 3 cuda_ad_rgb)
# with the read-back prepared during the launches (cltrace-prep.xz), then with main's.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT
(cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz) &
CONFIGS=16x8 ROUNDS=${ROUNDS:-3} bash .gpu/run74.sh
wait
for v in prep head; do
  [ $SECONDS -lt ${UNTIL:-150} ] || break
  xz -dc .gpu/cltrace-$v.xz > /tmp/cltrace-$v; chmod +x /tmp/cltrace-$v
  PYTHONPATH=/tmp/site timeout 100 python3 scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace /tmp/cltrace-$v --devices gpu \
    --size 1920x1080 --spp 256 --max-bounces 8 --scenes cornell,gold,glass --repetitions 3 --out /tmp/spm 2>&1 | grep -vE "^\s*$" | tail -12 | tee $OUT/mitsuba-$v.txt
  echo "$v compare done at ${SECONDS}s" | tee -a $OUT/bench.txt
done
echo "run88 done at ${SECONDS}s" | tee -a $OUT/bench.txt
