/* cldump: LD_PRELOAD shim that writes every built program's binary and build options to
 * $CLDUMP_DIR (prog-N.bin, prog-N.opts). */
#define _GNU_SOURCE
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>
typedef cl_int (*build_fn)(cl_program, cl_uint, const cl_device_id*, const char*, void (CL_CALLBACK*)(cl_program, void*), void*);
static int counter = 0;
CL_API_ENTRY cl_int CL_API_CALL clBuildProgram(cl_program p, cl_uint n, const cl_device_id* d, const char* opts,
                                             void (CL_CALLBACK* cb)(cl_program, void*), void* ud) {
    build_fn real = (build_fn)dlsym(RTLD_NEXT, "clBuildProgram");
    cl_int r = real(p, n, d, opts, cb, ud);
    const char* dir = getenv("CLDUMP_DIR");
    if (r != CL_SUCCESS || !dir) return r;
    cl_uint nd = 0; clGetProgramInfo(p, CL_PROGRAM_NUM_DEVICES, sizeof nd, &nd, 0);
    if (nd != 1) return r;
    size_t bn = 0; clGetProgramInfo(p, CL_PROGRAM_BINARY_SIZES, sizeof bn, &bn, 0);
    unsigned char* bin = malloc(bn); unsigned char* bins[1] = {bin};
    clGetProgramInfo(p, CL_PROGRAM_BINARIES, sizeof bins, bins, 0);
    while (bn > 0 && bin[bn - 1] == 0) bn--;
    char path[4096]; int k = __sync_fetch_and_add(&counter, 1);
    snprintf(path, sizeof path, "%s/prog-%d-%d.bin", dir, (int)getpid(), k);
    FILE* f = fopen(path, "wb"); if (f) { fwrite(bin, 1, bn, f); fclose(f); }
    snprintf(path, sizeof path, "%s/prog-%d-%d.opts", dir, (int)getpid(), k);
    f = fopen(path, "w"); if (f) { fprintf(f, "%s\n", opts ? opts : ""); fclose(f); }
    free(bin);
    return r;
}
