#!/bin/bash
# Registers of the tracing kernels: main against three kernel copies (B: the leaf's rows read as
# 12-byte vload3s instead of 16-byte float4s; C: the watertight test's three axes packed in one
# uint; D: both). First the ptxas register counts of each (-cl-nv-verbose), then three
# alternated rounds of bench, bunny and dragon, primary, diffuse-16 and path rows.
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,uuid,driver_version --format=csv,noheader | tee $OUT/gpu.txt
xz -dc .gpu/cltrace.xz > /tmp/cltrace; chmod +x /tmp/cltrace
S=.gpu/scenes
MESHES="$S/stanford_bunny.obj.gz $S/stanford_dragon.obj.gz"
kdir() { if [ "$1" = main ]; then echo "-u CLTRACE_KERNEL_DIR"; else echo "CLTRACE_KERNEL_DIR=$PWD/.gpu/k-regs-$1"; fi; }
for v in main B C D; do
  env $(kdir $v) CLTRACE_BUILD_LOG=1 CLTRACE_BUILD_OPTIONS=-cl-nv-verbose timeout 200 /tmp/cltrace bench $S/stanford_bunny.obj.gz --methods cl-bvh --layouts bin64 --rays primary,diffuse-16,path --resolutions 320x180 --devices gpu --repetitions 1 2>&1 | grep -iE "Compiling entry|Used [0-9]+ registers|spill" | sed "s/^/$v /" | tee -a $OUT/registers.txt
done
for r in 1 2 3; do
  for v in main B C D; do
    env $(kdir $v) timeout 200 /tmp/cltrace bench $MESHES --methods cl-bvh --layouts bin64 --rays primary,diffuse-16,path --resolutions 1920x1080 --devices gpu --repetitions 10 2>&1 | grep -E "^\| [a-z]|rror" | sed "s/^/r$r $v /" | tee -a $OUT/bench.txt
  done
done
