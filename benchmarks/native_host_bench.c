/* native_host_bench.c: the true cost of a native FMU step, timed in a C host's own loop (no
 * Python): dlopen the binary, instantiate, initialise, then N x (set the 7 inputs, doStep, get
 * the outputs) on a recording read from a binary file of doubles (acc x,y,z, gyro x,y,z, dt per
 * sample), timed with CLOCK_MONOTONIC; the best of P passes, each on a fresh instance.
 *
 *   native_host_bench 2|3 BINARY TOKEN SAMPLES.bin PASSES OUTPUT_VR...
 *
 * Prints the microseconds per step of the best pass.
 */
#define _POSIX_C_SOURCE 199309L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "fmi2FunctionTypes.h"
#include "fmi3FunctionTypes.h"

static void quiet2(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c,
                   fmi2String m, ...)
{
    (void)e; (void)n; (void)s; (void)c; (void)m;
}

#define SYM(T, name) ((T *)dlsym(lib, name))

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv)
{
    const unsigned in_vr[7] = {0, 1, 2, 3, 4, 5, 6};
    unsigned out_vr[16];
    double out[16], best = 1e30;
    size_t n_out = 0, n, k;
    int p, passes, v3;
    double *samples;
    long bytes;
    FILE *f;
    void *lib;
    if (argc < 7) {
        fprintf(stderr, "usage: %s 2|3 BINARY TOKEN SAMPLES.bin PASSES OUTPUT_VR...\n", argv[0]);
        return 2;
    }
    v3 = argv[1][0] == '3';
    for (p = 6; p < argc && n_out < 16; p++) {
        out_vr[n_out++] = (unsigned)strtoul(argv[p], NULL, 10);
    }
    passes = atoi(argv[5]);
    f = fopen(argv[4], "rb");
    if (!f || fseek(f, 0, SEEK_END) != 0 || (bytes = ftell(f)) <= 0) {
        fprintf(stderr, "cannot read %s\n", argv[4]);
        return 1;
    }
    rewind(f);
    samples = malloc((size_t)bytes);
    n = (size_t)bytes / (7 * sizeof(double));
    if (!samples || fread(samples, 1, (size_t)bytes, f) != (size_t)bytes) {
        return 1;
    }
    fclose(f);
    lib = dlopen(argv[2], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 1;
    }
    for (p = 0; p < passes; p++) {
        double t0, t1;
        if (v3) {
            fmi3InstantiateCoSimulationTYPE *inst =
                SYM(fmi3InstantiateCoSimulationTYPE, "fmi3InstantiateCoSimulation");
            fmi3EnterInitializationModeTYPE *enter =
                SYM(fmi3EnterInitializationModeTYPE, "fmi3EnterInitializationMode");
            fmi3ExitInitializationModeTYPE *exit_init =
                SYM(fmi3ExitInitializationModeTYPE, "fmi3ExitInitializationMode");
            fmi3SetFloat64TYPE *set = SYM(fmi3SetFloat64TYPE, "fmi3SetFloat64");
            fmi3GetFloat64TYPE *get = SYM(fmi3GetFloat64TYPE, "fmi3GetFloat64");
            fmi3DoStepTYPE *step = SYM(fmi3DoStepTYPE, "fmi3DoStep");
            fmi3FreeInstanceTYPE *free_instance = SYM(fmi3FreeInstanceTYPE, "fmi3FreeInstance");
            fmi3Boolean ev, term, early;
            fmi3Float64 last;
            fmi3Instance c = inst("bench", argv[3], "", fmi3False, fmi3False, fmi3False, fmi3False,
                                  NULL, 0, NULL, NULL, NULL);
            if (!c || enter(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK ||
                exit_init(c) != fmi3OK) {
                return 1;
            }
            t0 = now();
            for (k = 0; k < n; k++) {
                set(c, in_vr, 7, samples + 7 * k, 7);
                step(c, 0.01 * k, 0.01, fmi3True, &ev, &term, &early, &last);
                get(c, out_vr, n_out, out, n_out);
            }
            t1 = now();
            free_instance(c);
        } else {
            fmi2InstantiateTYPE *inst = SYM(fmi2InstantiateTYPE, "fmi2Instantiate");
            fmi2SetupExperimentTYPE *setup = SYM(fmi2SetupExperimentTYPE, "fmi2SetupExperiment");
            fmi2EnterInitializationModeTYPE *enter =
                SYM(fmi2EnterInitializationModeTYPE, "fmi2EnterInitializationMode");
            fmi2ExitInitializationModeTYPE *exit_init =
                SYM(fmi2ExitInitializationModeTYPE, "fmi2ExitInitializationMode");
            fmi2SetRealTYPE *set = SYM(fmi2SetRealTYPE, "fmi2SetReal");
            fmi2GetRealTYPE *get = SYM(fmi2GetRealTYPE, "fmi2GetReal");
            fmi2DoStepTYPE *step = SYM(fmi2DoStepTYPE, "fmi2DoStep");
            fmi2FreeInstanceTYPE *free_instance = SYM(fmi2FreeInstanceTYPE, "fmi2FreeInstance");
            fmi2CallbackFunctions cb = {quiet2, calloc, free, NULL, NULL};
            fmi2Component c = inst("bench", fmi2CoSimulation, argv[3], "", &cb, fmi2False,
                                   fmi2False);
            if (!c || setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
                enter(c) != fmi2OK || exit_init(c) != fmi2OK) {
                return 1;
            }
            t0 = now();
            for (k = 0; k < n; k++) {
                set(c, in_vr, 7, samples + 7 * k);
                step(c, 0.01 * k, 0.01, fmi2True);
                get(c, out_vr, n_out, out);
            }
            t1 = now();
            free_instance(c);
        }
        if ((t1 - t0) / n < best) {
            best = (t1 - t0) / n;
        }
    }
    printf("%.6f\n", best * 1e6);
    free(samples);
    dlclose(lib);
    return 0;
}
