/*
 * A minimal FMI 2.0 co-simulation host in C, loading an FMU's linux64 binary the way a Modelica
 * tool or Simulink does: dlopen the .so, look up the fmi2 functions, instantiate, initialise,
 * then one fmi2DoStep per input line, and free the instance.
 *
 * The binary does not link libpython (pythonfmu FMUs embed the host's Python): run the host
 * with the interpreter's shared library preloaded, as one would run the tool itself:
 *   LD_PRELOAD=/path/libpython3.11.so.1.0 PYTHONPATH=<site-packages with numpy, scipy> \
 *   fmu_host BINARY.so RESOURCE_URI GUID REAL_IN_VRS REAL_OUT_VRS INT_OUT_VRS [--finalize-python]
 *            < samples > outputs
 * VRS are comma-separated value references. Each input line holds one value per REAL_IN_VR,
 * the last of which is the communication step size h (the sample's dt); each output line
 * holds the REAL_OUT values (%.17g, so they round-trip exactly) and then the INT_OUT values.
 * Exit status: 0 on success; 2 cannot load; 3 cannot instantiate; 4 an fmi2 call failed.
 *
 * --finalize-python works around a pythonfmu 0.7 defect: its binary resets a static
 * std::shared_ptr (the embedded interpreter) in an ELF destructor that runs at process exit
 * after the C++ static destructors have already destroyed that shared_ptr, so a C host that
 * exits normally aborts in exit() with a corrupted heap, after every FMI call has returned OK.
 * Calling the binary's exported finalizePythonInterpreter() before exit ends the interpreter
 * while everything is still alive. A Modelica tool or Simulink does not do this.
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define MAX_VRS 64

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    va_list args;
    (void)env;
    fprintf(stderr, "[%s] %s (status %d): ", category ? category : "", instance, (int)status);
    va_start(args, message);
    vfprintf(stderr, message, args);
    va_end(args);
    fputc('\n', stderr);
}

static int parse_vrs(const char *text, fmi2ValueReference *vrs) {
    int n = 0;
    const char *p = text;
    while (*p) {
        char *end;
        unsigned long vr = strtoul(p, &end, 10);
        if (end == p || n == MAX_VRS) return -1;
        vrs[n++] = (fmi2ValueReference)vr;
        if (*end == ',') p = end + 1;
        else if (*end == '\0') p = end;
        else return -1;
    }
    return n;
}

static void *need(void *lib, const char *name) {
    void *f = dlsym(lib, name);
    if (f == NULL) {
        fprintf(stderr, "missing symbol %s: %s\n", name, dlerror());
        exit(2);
    }
    return f;
}

#define CHECK(call)                                                              \
    do {                                                                         \
        fmi2Status s_ = (call);                                                  \
        if (s_ != fmi2OK) {                                                      \
            fprintf(stderr, "%s returned status %d\n", #call, (int)s_);          \
            return 4;                                                            \
        }                                                                        \
    } while (0)

int main(int argc, char **argv) {
    fmi2ValueReference in_vr[MAX_VRS], out_vr[MAX_VRS], int_vr[MAX_VRS];
    fmi2Real in[MAX_VRS], out[MAX_VRS];
    fmi2Integer ints[MAX_VRS];
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    int n_in, n_out, n_int, steps = 0;
    double t = 0.0;

    int finalize = argc == 8 && strcmp(argv[7], "--finalize-python") == 0;
    if (argc != 7 && !finalize) {
        fprintf(stderr, "usage: %s BINARY.so RESOURCE_URI GUID REAL_IN_VRS REAL_OUT_VRS "
                        "INT_OUT_VRS [--finalize-python] < samples\n", argv[0]);
        return 1;
    }
    n_in = parse_vrs(argv[4], in_vr);
    n_out = parse_vrs(argv[5], out_vr);
    n_int = parse_vrs(argv[6], int_vr);
    if (n_in < 1 || n_out < 0 || n_int < 0) {
        fprintf(stderr, "cannot read the value references\n");
        return 1;
    }

    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "cannot load %s: %s\n", argv[1], dlerror());
        return 2;
    }
    fmi2InstantiateTYPE *instantiate = (fmi2InstantiateTYPE *)need(lib, "fmi2Instantiate");
    fmi2SetupExperimentTYPE *setup = (fmi2SetupExperimentTYPE *)need(lib, "fmi2SetupExperiment");
    fmi2EnterInitializationModeTYPE *enter =
        (fmi2EnterInitializationModeTYPE *)need(lib, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *exit_init =
        (fmi2ExitInitializationModeTYPE *)need(lib, "fmi2ExitInitializationMode");
    fmi2SetRealTYPE *set_real = (fmi2SetRealTYPE *)need(lib, "fmi2SetReal");
    fmi2GetRealTYPE *get_real = (fmi2GetRealTYPE *)need(lib, "fmi2GetReal");
    fmi2GetIntegerTYPE *get_integer = (fmi2GetIntegerTYPE *)need(lib, "fmi2GetInteger");
    fmi2DoStepTYPE *do_step = (fmi2DoStepTYPE *)need(lib, "fmi2DoStep");
    fmi2TerminateTYPE *terminate = (fmi2TerminateTYPE *)need(lib, "fmi2Terminate");
    fmi2FreeInstanceTYPE *free_instance = (fmi2FreeInstanceTYPE *)need(lib, "fmi2FreeInstance");

    fmi2Component c = instantiate("c_host", fmi2CoSimulation, argv[3], argv[2], &callbacks,
                                  fmi2False, fmi2True);
    if (c == NULL) {
        fprintf(stderr, "fmi2Instantiate failed\n");
        return 3;
    }
    CHECK(setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(enter(c));
    CHECK(exit_init(c));
    for (;;) {
        int i, got = 0;
        for (i = 0; i < n_in; i++) got += scanf("%lf", &in[i]);
        if (got != n_in) break;
        CHECK(set_real(c, in_vr, (size_t)n_in, in));
        CHECK(do_step(c, t, in[n_in - 1], fmi2True));
        t += in[n_in - 1];
        CHECK(get_real(c, out_vr, (size_t)n_out, out));
        CHECK(get_integer(c, int_vr, (size_t)n_int, ints));
        for (i = 0; i < n_out; i++) printf(i ? " %.17g" : "%.17g", out[i]);
        for (i = 0; i < n_int; i++) printf(" %d", (int)ints[i]);
        putchar('\n');
        steps++;
    }
    CHECK(terminate(c));
    free_instance(c);
    fprintf(stderr, "%d steps\n", steps);
    fflush(stdout);
    if (finalize) {
        void (*finalize_python)(void) = (void (*)(void))need(lib, "finalizePythonInterpreter");
        finalize_python();
    }
    dlclose(lib);
    return 0;
}
