#!/bin/bash
# Issue 19 item 2: where the GPU path kernel's time goes (clock64 around trace and
# path_vertex, summed into the ray counts), and which relaxed-maths option pays.
set -u
REPO=$PWD
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
DEV=${DEV:-gpu}
SIZE=${SIZE:-1920x1080}; SPP=${SPP:-256}
W=${SIZE%x*}; H=${SIZE#*x}
xz -dc $REPO/.gpu/cltrace.xz > /tmp/cltrace && chmod +x /tmp/cltrace
PY=${PY:-python3}
nvidia-smi --query-gpu=name,driver_version --format=csv 2>&1 | tee $OUT/gpu.txt
$PY scripts/mitsuba/compare.py scenes --out /tmp/sp --size $SIZE --spp $SPP --scenes cornell,gold,glass > /dev/null || exit 1
cfgs="${CFGS:-base r64 fm56 nat fma fmanat64 p1 p3 p4 p5}"
run() { # cfg scene round
  local cfg=$1 s=$2 opts="" kd="" lay=""
  case $cfg in
    base) ;;
    fm56) opts="-cl-fast-relaxed-math" ;;
    fin) opts="-cl-finite-math-only" ;;
    uns) opts="-cl-unsafe-math-optimizations" ;;
    mad) opts="-cl-mad-enable" ;;
    nat) kd=k-opt; opts="-D NATIVE_TRIG" ;;
    fma) kd=k-opt; opts="-D CONTRACT_SHADING" ;;
    fmanat) kd=k-opt; opts="-D CONTRACT_SHADING -D NATIVE_TRIG" ;;
    fmanat64) kd=k-opt; opts="-D CONTRACT_SHADING -D NATIVE_TRIG -cl-nv-maxrregcount=64" ;;
    r64) opts="-cl-nv-maxrregcount=64" ;;
    all64) kd=k-opt; opts="-D CONTRACT_SHADING -D NATIVE_TRIG -cl-fast-relaxed-math -cl-nv-maxrregcount=64" ;;
    all56) kd=k-opt; opts="-D CONTRACT_SHADING -D NATIVE_TRIG -cl-fast-relaxed-math" ;;
    leaf1) lay="--max-leaf-size 1" ;; leaf2) lay="--max-leaf-size 2" ;; leaf4) lay="--max-leaf-size 4" ;;
    sweep) lay="--builder sweep" ;; opt8) lay="--optimize 8" ;;
    allsw) kd=k-opt; opts="-D CONTRACT_SHADING -D NATIVE_TRIG -cl-fast-relaxed-math -cl-nv-maxrregcount=64"; lay="--builder sweep" ;;
    p*) kd=k-prof; opts="-D PROF=${cfg#p}" ;;
  esac
  if [ -n "$kd" ]; then export CLTRACE_KERNEL_DIR=$REPO/.gpu/$kd; else unset CLTRACE_KERNEL_DIR; fi
  CLTRACE_BUILD_OPTIONS="$opts" /tmp/cltrace render /tmp/sp/$s/scene.toml -q --device $DEV --max-bounces 8 $lay \
    -o /tmp/o_${cfg}_$s.pfm --json /tmp/r.json 2>&1 | tail -3 || { echo "$3 $cfg $s FAILED"; return; }
  $PY -c "import json;r=json.load(open('/tmp/r.json'));print('$3 $cfg $s %.1f Msamples/s rays %d ms %.1f' % ($W*$H*$SPP/r['sampling_ms']/1e3, r['rays'], r['sampling_ms']))"
  rm -f /tmp/r.json
}
for round in ${ROUNDS:-0 1 2}; do for cfg in $cfgs; do for s in cornell gold glass; do
  case "$round$cfg" in 2p*) continue ;; esac
  run $cfg $s $round
done; done; done 2>&1 | tee $OUT/sweep.txt
$PY $REPO/.gpu/summary.py $OUT/sweep.txt /tmp | tee $OUT/summary.txt
