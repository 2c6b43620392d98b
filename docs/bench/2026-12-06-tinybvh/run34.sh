#!/bin/bash
# Item 4: is the SIMD groups' best pixel tile (32x1 rows in 32x4 groups, or 16x2 in 16x8)
# a matter of triangles per pixel? The bunny and the dragon at four resolutions, and three
# other meshes at 1080p, under both shapes; three rounds, alternated.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
S=.gpu/scenes
for r in 1 2 3; do for wg in 16x8 32x4; do
  timeout 120 /tmp/cltrace bench $S/stanford_bunny.obj.gz $S/stanford_dragon.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 480x270,960x540,1920x1080,3840x2160 --devices gpu --repetitions 10 --work-group $wg 2>&1 | grep -E "^\| " | grep -v "| scene" | awk -F'|' -v r=$r -v n=$wg '{print "r" r, n, $2, $4, $12, $13, $14}' | tee -a $OUT/density.txt
  timeout 120 /tmp/cltrace bench $S/barcelona_pavilion.obj $S/utah_teapot.obj $S/spot.obj.gz --methods cl-bvh --layouts bin64 --rays primary --resolutions 1920x1080 --devices gpu --repetitions 10 --work-group $wg 2>&1 | grep -E "^\| " | grep -v "| scene" | awk -F'|' -v r=$r -v n=$wg '{print "r" r, n, $2, $4, $12, $13, $14}' | tee -a $OUT/density.txt
done; done
