#!/bin/sh
# PoCL 7.1 built from source against Debian 12's LLVM 19, into /opt/pocl7, with an ICD file
# of its own in /tmp/icd7 (OCL_ICD_VENDORS=/tmp/icd7 then lists it alone). A measurement
# only: cltrace's set-up does not use it. POCL_SRC: a checkout of pocl/pocl at v7.1.
set -eu
apt-get install -y -q clang-19 llvm-19-dev libclang-19-dev libclang-cpp19-dev cmake ninja-build \
    libhwloc-dev ocl-icd-dev ocl-icd-opencl-dev pkg-config >/dev/null
cmake -G Ninja -S "$POCL_SRC" -B /tmp/pocl-build -DCMAKE_BUILD_TYPE=Release \
    -DWITH_LLVM_CONFIG=/usr/bin/llvm-config-19 -DCMAKE_INSTALL_PREFIX=/opt/pocl7 -DENABLE_ICD=ON \
    -DENABLE_TESTS=OFF -DENABLE_EXAMPLES=OFF -DENABLE_SPIRV=OFF -DENABLE_LLVM_PLATFORM_SUPPORT=OFF
ninja -C /tmp/pocl-build install
mkdir -p /tmp/icd7
echo /opt/pocl7/lib/libpocl.so > /tmp/icd7/pocl7.icd
OCL_ICD_VENDORS=/tmp/icd7 clinfo -l
