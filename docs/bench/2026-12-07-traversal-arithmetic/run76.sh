#!/bin/bash
# The machine code of the tracing kernels: cltrace's programs as the head's build (93d1383)
# compiles them, written by cldump.so (an LD_PRELOAD shim over clBuildProgram): bin64's
# camera and diffuse-16 rays, and the path program of compare.py's glass scene (the first
# lease ran --layouts bin64,cwbvh, whose cwbvh program is kept); tinybvh's traverse.cl as
# its harness builds it, through clbin (a small OpenCL host program that writes a
# program's binary). Each PTX goes through ptxas for sm_90 (registers, spills) and
# cuobjdump (SASS).
set -u
OUT=${OUT:-/tmp/out}; mkdir -p $OUT /tmp/sass
nvidia-smi --query-gpu=name,uuid,driver_version,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
export PATH=$PATH:$(ls -d /usr/local/cuda*/bin 2>/dev/null | head -1)
(command -v ptxas; command -v nvdisasm; command -v cuobjdump; ptxas --version | tail -1) | tee /tmp/sass/tools.txt
xz -dc .gpu/cltrace-head.xz > /tmp/cltrace; chmod +x /tmp/cltrace
python3 scripts/mitsuba/compare.py scenes --out /tmp/sc --size 1920x1080 --spp 256 --scenes glass > /dev/null 2>&1
export CLTRACE_KERNEL_CACHE=off CLDUMP_DIR=/tmp/sass
B=.gpu/scenes/stanford_bunny.obj.gz
LD_PRELOAD=$PWD/.gpu/bin/cldump.so /tmp/cltrace bench $B --methods cl-bvh --layouts bin64 --rays primary,diffuse-16 --resolutions 1920x1080 --devices gpu --repetitions 2 > /tmp/sass/bench.txt 2>&1
LD_PRELOAD=$PWD/.gpu/bin/cldump.so /tmp/cltrace render /tmp/sc/glass/scene.toml -q --device gpu --max-bounces 8 --spp 4 -o /tmp/g.exr > /tmp/sass/render.txt 2>&1
for b in /tmp/sass/prog-*.bin; do mv $b ${b%.bin}.ptx; done
clbin .gpu/tinybvh/traverse.cl "-cl-std=CL2.0 -cl-strict-aliasing -cl-fast-relaxed-math -cl-single-precision-constant -cl-nv-opt-level=9 -I $PWD/.gpu/tinybvh" /tmp/sass/tinybvh.ptx "#define ISNVIDIA
" > /tmp/sass/clbin.txt 2>&1
for p in /tmp/sass/*.ptx; do
  b=${p%.ptx}
  cap=$(grep -o "maxrregcount=[0-9]*" $b.opts 2>/dev/null | sed 's/.*=/-maxrregcount=/')
  grep -o "\.entry [a-z_0-9]*" $p > $b.entries.txt
  ptxas -arch=sm_90 -v $cap $p -o $b.cubin > $b.ptxas.txt 2>&1
  cuobjdump -sass $b.cubin > $b.sass 2>&1 || nvdisasm $b.cubin > $b.sass 2>&1
done
ls -la /tmp/sass | tee $OUT/ls.txt
tar czf $OUT/sass.tgz -C /tmp sass
