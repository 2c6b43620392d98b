#!/bin/bash
# Issue 19 item 2: register caps, fast math and the Lambert shortcut of the GPU path
# programs, with Mitsuba cuda_ad_rgb in the same run. Usage: bash .gpu/run-m.sh [quick]
set -u
REPO=$PWD
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
DEV=${DEV:-gpu}
SIZE=${SIZE:-1920x1080}; SPP=${SPP:-256}
W=${SIZE%x*}; H=${SIZE#*x}
cd /tmp && tar -xJf $REPO/.gpu/site.tar.xz && xz -dc $REPO/.gpu/cltrace.xz > /tmp/cltrace && chmod +x /tmp/cltrace
cd $REPO
export PYTHONPATH=${PYPATH-/tmp/site}; PY=${PY:-python3}
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv 2>&1 | tee $OUT/gpu.txt
/tmp/cltrace devices 2>&1 | tee -a $OUT/gpu.txt
if [ "${SKIP_MITSUBA:-0}" = 0 ]; then
  timeout 240 $PY scripts/mitsuba/compare.py speed --variant cuda_ad_rgb --cltrace /tmp/cltrace --devices $DEV \
    --size $SIZE --spp $SPP --max-bounces 8 --scenes cornell,gold,glass --repetitions 2 --out /tmp/sp 2>&1 | tail -12 | tee $OUT/mitsuba.md
else
  /tmp/cltrace --version
  $PY scripts/mitsuba/compare.py scenes --out /tmp/sp --size $SIZE --spp $SPP --scenes cornell,gold,glass >/dev/null
fi
# natural register counts
for regs in 56 255; do for s in cornell gold glass; do
  CLTRACE_KERNEL_CACHE=off CLTRACE_BUILD_LOG=1 CLTRACE_BUILD_OPTIONS="-cl-nv-maxrregcount=$regs -cl-nv-verbose" \
    /tmp/cltrace render /tmp/sp/$s/scene.toml -q --device $DEV --max-bounces 8 --spp 1 -o /tmp/o.exr 2>&1 \
    | grep -i "registers\|spill\|sample_path" | sed "s/^/$s regs=$regs: /" | head -6 >> $OUT/regs.txt
done; done
cfgs="${CFGS:-base r40 r48 r64 r72 r80 r96 r128 fm56 fm72 v2 v2r72 v3 cw w8}"
run() { # cfg scene round
  local cfg=$1 s=$2 opts="" kd="" lay=""
  case $cfg in
    base) ;; r*) opts="-cl-nv-maxrregcount=${cfg#r}" ;;
    fm*) opts="-cl-nv-maxrregcount=${cfg#fm} -cl-fast-relaxed-math" ;;
    v2) kd=$REPO/.gpu/k-v2 ;; v3) kd=$REPO/.gpu/k-v3 ;; cw) lay="--layout cwbvh" ;; w8) lay="--layout wide8" ;; v2r72) kd=$REPO/.gpu/k-v2; opts="-cl-nv-maxrregcount=72" ;;
  esac
  if [ -n "$kd" ]; then export CLTRACE_KERNEL_DIR=$kd; else unset CLTRACE_KERNEL_DIR; fi
  CLTRACE_BUILD_OPTIONS="$opts" /tmp/cltrace render /tmp/sp/$s/scene.toml -q --device $DEV --max-bounces 8 $lay \
    -o /tmp/o_${cfg}_$s.pfm --json /tmp/r.json || { echo "$3 $cfg $s FAILED"; return; }
  $PY -c "import json;r=json.load(open('/tmp/r.json'));print('$3 $cfg $s %.1f Msamples/s rays %d ms %.1f' % ($W*$H*$SPP/r['sampling_ms']/1e3, r['rays'], r['sampling_ms']))"
}
for round in ${ROUNDS:-0 1 2}; do for cfg in $cfgs; do for s in cornell gold glass; do
  run $cfg $s $round
done; done; done 2>&1 | tee $OUT/sweep.txt
$PY $REPO/.gpu/summary.py $OUT/sweep.txt /tmp | tee $OUT/summary.txt
