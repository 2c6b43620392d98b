/* clbin: builds an OpenCL C file for the first GPU and writes the program binary
 * (PTX on NVIDIA). Usage: clbin FILE.cl "OPTIONS" OUT [PREFIX-TEXT] */
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
int main(int argc, char** argv) {
    if (argc < 4) { fprintf(stderr, "usage: clbin FILE.cl OPTIONS OUT [PREFIX]\n"); return 2; }
    FILE* f = fopen(argv[1], "rb"); if (!f) { perror(argv[1]); return 1; }
    fseek(f, 0, SEEK_END); long n = ftell(f); fseek(f, 0, SEEK_SET);
    const char* pre = argc > 4 ? argv[4] : "";
    size_t pn = strlen(pre);
    char* src = malloc(pn + n + 1); memcpy(src, pre, pn);
    if (fread(src + pn, 1, n, f) != (size_t)n) return 1; src[pn + n] = 0; fclose(f);
    cl_platform_id ps[8]; cl_uint np = 0; clGetPlatformIDs(8, ps, &np);
    cl_device_id dev = 0;
    for (cl_uint i = 0; i < np && !dev; i++) { cl_uint nd = 0; if (clGetDeviceIDs(ps[i], CL_DEVICE_TYPE_GPU, 1, &dev, &nd) != CL_SUCCESS) dev = 0; }
    if (!dev) { fprintf(stderr, "no GPU\n"); return 1; }
    cl_int err; cl_context ctx = clCreateContext(0, 1, &dev, 0, 0, &err);
    const char* s = src; cl_program p = clCreateProgramWithSource(ctx, 1, &s, 0, &err);
    err = clBuildProgram(p, 1, &dev, argv[2], 0, 0);
    size_t ln = 0; clGetProgramBuildInfo(p, dev, CL_PROGRAM_BUILD_LOG, 0, 0, &ln);
    char* log = malloc(ln + 1); clGetProgramBuildInfo(p, dev, CL_PROGRAM_BUILD_LOG, ln, log, 0); log[ln] = 0;
    fprintf(stderr, "%s", log);
    if (err != CL_SUCCESS) { fprintf(stderr, "build failed: %d\n", err); return 1; }
    size_t bn = 0; clGetProgramInfo(p, CL_PROGRAM_BINARY_SIZES, sizeof bn, &bn, 0);
    unsigned char* bin = malloc(bn); unsigned char* bins[1] = {bin};
    clGetProgramInfo(p, CL_PROGRAM_BINARIES, sizeof bins, bins, 0);
    while (bn > 0 && bin[bn - 1] == 0) bn--; FILE* o = fopen(argv[3], "wb"); fwrite(bin, 1, bn, o); fclose(o);
    printf("%s: %zu bytes\n", argv[3], bn);
    return 0;
}
