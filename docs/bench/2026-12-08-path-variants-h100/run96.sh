#!/bin/bash
# run96: path and shadow rays with unpipelined leaves (k2), by scene size. (1) cltrace bench
# --rays path, bin64, on the bunny, dragon, spot, teapot and pavilion, k0 (main) and k2
# alternated; (2) bench --scaling --rays path on hillsides of 10K-3M triangles, k0 and k2;
# (3) compare.py's scenes at 1080p 256 spp: k0, k2, k2p (path rays unpipelined, shadow rays
# pipelined), k2s (the reverse), k2 with register caps of 56 and 72 (main: 64), alternated rounds.
set -u
REPO=$PWD; OUT=${OUT:-/tmp/out}; mkdir -p $OUT; ROUNDS=${ROUNDS:-2}
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace-m95.xz > /tmp/cltrace; chmod +x /tmp/cltrace
S=.gpu/scenes
for r in $(seq $ROUNDS); do for k in k0 k2; do
  CLTRACE_KERNEL_DIR=$REPO/.gpu/kv/$k timeout 120 /tmp/cltrace bench $S/stanford_bunny.obj.gz $S/stanford_dragon.obj.gz $S/spot.obj.gz $S/utah_teapot.obj $S/barcelona_pavilion.obj \
    --methods cl-bvh --layouts bin64 --rays path --devices gpu --resolutions 1920x1080 --repetitions 5 2>&1 | grep "|" | sed "s/^/[r$r $k] /" | tee -a $OUT/bench.txt
done; echo "bench round $r at ${SECONDS}s" | tee -a $OUT/bench.txt; done
for k in ${SCALE_KS:-k0 k2}; do
  CLTRACE_KERNEL_DIR=$REPO/.gpu/kv/$k timeout 120 /tmp/cltrace bench --scaling --scaling-to 3M --rays path --layouts bin64 --methods cl-bvh --devices gpu --repetitions 5 2>&1 | grep "|" | sed "s/^/[$k] /" | tee -a $OUT/scaling.txt
done; echo "scaling at ${SECONDS}s" | tee -a $OUT/scaling.txt
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes cornell,gold,glass > /dev/null 2>&1
one() { # kernel dir, scene, round [, name, build options]
  CLTRACE_BUILD_OPTIONS="${5:-}" CLTRACE_KERNEL_DIR=$REPO/.gpu/kv/$1 timeout 60 /tmp/cltrace render /tmp/sc/$2/scene.toml -q --device gpu --max-bounces 8 -o /tmp/st-${4:-$1}-$2.pfm --json /tmp/j.json > /dev/null 2>&1
  python3 -c "import json;j=json.load(open('/tmp/j.json'));print('[r$3 ${4:-$1} $2] %.1f Msamples/s (sampling %.1f ms, rays %d)'%(1920*1080*256/j['sampling_ms']/1e3,j['sampling_ms'],j['rays']))" | tee -a $OUT/paths.txt; rm -f /tmp/j.json
}
for r in $(seq ${PROUNDS:-1}); do for s in cornell gold glass; do for k in k0 k2 k2p k2s; do one $k $s $r; done
  one k2 $s $r k2r56 -cl-nv-maxrregcount=56; one k2 $s $r k2r72 -cl-nv-maxrregcount=72; done; done
for k in k2 k2p k2s k2r56 k2r72; do for s in cornell gold glass; do cmp -s /tmp/st-k0-$s.pfm /tmp/st-$k-$s.pfm && echo "$k $s: same image" || echo "$k $s: DIFFERENT"; done; done | tee -a $OUT/paths.txt
echo "run96 done at ${SECONDS}s" | tee -a $OUT/paths.txt
