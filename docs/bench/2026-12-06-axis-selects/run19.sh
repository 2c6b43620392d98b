#!/bin/bash
# Main with AXIS_PICKS on GPUs against main before the selects: same images, same speed?
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
xz -dc .gpu/cltrace.xz > /tmp/new; xz -dc .gpu/cltrace-old.xz > /tmp/old; chmod +x /tmp/new /tmp/old
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee $OUT/gpu.txt
cp -r .gpu/sp /tmp/sp
for s in glass gold cornell; do
  /tmp/old render /tmp/sp/$s/scene.toml -q --device gpu --max-bounces 8 --spp 16 -o /tmp/a.pfm
  /tmp/new render /tmp/sp/$s/scene.toml -q --device gpu --max-bounces 8 --spp 16 -o /tmp/b.pfm
  cmp -s /tmp/a.pfm /tmp/b.pfm && echo "same image $s" | tee -a $OUT/eq.txt || echo "DIFFERENT $s" | tee -a $OUT/eq.txt
done
/tmp/old render .gpu/scenes/stanford_dragon.obj.gz -q --device gpu --hits /tmp/a.hits -o /tmp/a.png
/tmp/new render .gpu/scenes/stanford_dragon.obj.gz -q --device gpu --hits /tmp/b.hits -o /tmp/b.png
cmp -s /tmp/a.hits /tmp/b.hits && echo "same hits dragon" | tee -a $OUT/eq.txt || echo "DIFFERENT hits dragon" | tee -a $OUT/eq.txt
for r in 1 2; do for b in old new; do
  timeout 100 /tmp/$b bench .gpu/scenes/stanford_dragon.obj.gz .gpu/scenes/stanford_bunny.obj.gz --methods cl-bvh --layouts bin64 \
    --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu 2>&1 | grep -E "^\| stanford" | cut -d'|' -f2,6,8,14 | sed "s/^/[$b r$r] /" | tee -a $OUT/bench.txt
done; done
for b in old new; do BIN=/tmp/$b timeout 100 python3 .gpu/matrix.py /tmp/sp 2 "E=X=0" glass,gold,cornell 2>&1 | grep "^| [a-z]" | sed "s/^/[$b] /" | tee -a $OUT/path.txt; done
