/* native_host.c: a small FMI importer in C, as a tool that is not ours would load a native FMU:
 * dlopen the binary with no Python anywhere, then one run of the FMI 2.0 or FMI 3.0 co-simulation
 * calls, a state saved, serialized, deserialized and restored, every misuse of docs/interface.md
 * "FMI calls" (each must return an error status and log a line, and the run must go on), free,
 * dlclose, exit 0. Any unexpected status or a difference after the restore exits 1.
 *
 *   native_host 2|3 BINARY MODEL_IDENTIFIER TOKEN KIND N_VARIABLES OUTPUT_VR...
 *
 * KIND says what the first value references are: estimator (acc x,y,z, gyro x,y,z, dt), sensor
 * (omega x,y,z, f x,y,z) or plant (no inputs). Prints the last outputs, one per line.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"
#include "fmi3FunctionTypes.h"

#ifdef _WIN32  /* the same host cross-compiled for Windows (mingw-w64), run under wine */
#include <windows.h>
#define dlopen(path, flags) ((void *)LoadLibraryA(path))
#define dlsym(lib, name) ((void *)GetProcAddress((HMODULE)(lib), (name)))
#define dlclose(lib) FreeLibrary((HMODULE)(lib))
#define dlerror() "LoadLibrary failed"
#else
#include <dlfcn.h>
#endif

#define STEPS 600
#define MAX_OUT 32

static int errors_logged;

static void logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                 fmi2String category, fmi2String message, ...)
{
    (void)env;
    (void)name;
    (void)category;
    if (status == fmi2Error) {
        errors_logged++;
    }
    (void)message;
}

static void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                 fmi3String message)
{
    (void)env;
    (void)category;
    (void)message;
    if (status == fmi3Error) {
        errors_logged++;
    }
}

static void *sym(void *lib, const char *name)
{
    void *f = dlsym(lib, name);
    if (!f) {
        fprintf(stderr, "missing %s\n", name);
        exit(1);
    }
    return f;
}

/* The inputs of sample k for a kind of model. */
static int inputs(const char *kind, int k, double in[7])
{
    double t = 0.01 * k, roll = 0.4 * sin(0.7 * t), rate = 0.28 * cos(0.7 * t);
    if (strcmp(kind, "estimator") == 0) {
        in[0] = 0.0;
        in[1] = 9.80665 * sin(roll);
        in[2] = 9.80665 * cos(roll);
        in[3] = rate + 0.01;
        in[4] = -0.005;
        in[5] = 0.002;
        in[6] = k % 97 == 50 ? NAN : 0.01;  /* a bad sample now and then: rejected, logged */
        return 7;
    }
    if (strcmp(kind, "sensor") == 0) {
        in[0] = rate;
        in[1] = in[2] = 0.0;
        in[3] = 0.0;
        in[4] = 9.80665 * sin(roll);
        in[5] = 9.80665 * cos(roll);
        return 6;
    }
    return 0;
}

#define EXPECT(cond, what)                                                                    \
    if (!(cond)) {                                                                            \
        fprintf(stderr, "unexpected: %s\n", what);                                            \
        return 1;                                                                             \
    }
#define REFUSED(call, what)                                                                   \
    do {                                                                                      \
        int before = errors_logged;                                                           \
        EXPECT((call) == 3 && errors_logged == before + 1, what " was not refused with a log line"); \
    } while (0)

static int run2(void *lib, const char *model, const char *token, const char *kind,
                unsigned n_vars, const fmi2ValueReference *out_vr, size_t n_out)
{
    fmi2InstantiateTYPE *instantiate = sym(lib, "fmi2Instantiate");
    fmi2SetupExperimentTYPE *setup = sym(lib, "fmi2SetupExperiment");
    fmi2EnterInitializationModeTYPE *enter = sym(lib, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *exit_init = sym(lib, "fmi2ExitInitializationMode");
    fmi2SetRealTYPE *set_real = sym(lib, "fmi2SetReal");
    fmi2GetRealTYPE *get_real = sym(lib, "fmi2GetReal");
    fmi2DoStepTYPE *do_step = sym(lib, "fmi2DoStep");
    fmi2GetFMUstateTYPE *get_state = sym(lib, "fmi2GetFMUstate");
    fmi2SetFMUstateTYPE *set_state = sym(lib, "fmi2SetFMUstate");
    fmi2FreeFMUstateTYPE *free_state = sym(lib, "fmi2FreeFMUstate");
    fmi2SerializedFMUstateSizeTYPE *state_size = sym(lib, "fmi2SerializedFMUstateSize");
    fmi2SerializeFMUstateTYPE *serialize = sym(lib, "fmi2SerializeFMUstate");
    fmi2DeSerializeFMUstateTYPE *deserialize = sym(lib, "fmi2DeSerializeFMUstate");
    fmi2TerminateTYPE *terminate = sym(lib, "fmi2Terminate");
    fmi2FreeInstanceTYPE *free_instance = sym(lib, "fmi2FreeInstance");
    fmi2CallbackFunctions cb = {logger2, calloc, free, NULL, NULL};
    fmi2ValueReference in_vr[7] = {0, 1, 2, 3, 4, 5, 6}, bad_vr = n_vars + 5;
    fmi2FMUstate state = NULL, restored = NULL;
    double in[7], out[MAX_OUT], first[MAX_OUT], again[MAX_OUT], value = 1.0;
    size_t size, k;
    unsigned char *bytes, garbage[64];
    fmi2Component c;
    (void)model;

    EXPECT(instantiate("bad", fmi2CoSimulation, "{wrong}", "", &cb, fmi2False, fmi2False) == NULL,
           "a wrong GUID was accepted");
    EXPECT(errors_logged == 1, "a wrong GUID was not logged");
    c = instantiate("host", fmi2CoSimulation, token, "", &cb, fmi2False, fmi2True);
    EXPECT(c != NULL, "instantiate failed");
    REFUSED(do_step(c, 0.0, 0.01, fmi2True), "doStep before initialisation");
    EXPECT(setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK, "setupExperiment");
    EXPECT(enter(c) == fmi2OK && exit_init(c) == fmi2OK, "initialisation");
    REFUSED(set_real(c, out_vr, 1, &value), "setting an output");
    REFUSED(get_real(c, &bad_vr, 1, out), "getting an unknown value reference");
    REFUSED(set_real(c, &bad_vr, 1, &value), "setting an unknown value reference");
    REFUSED(do_step(c, 0.0, -0.01, fmi2True), "a negative step size");
    memset(garbage, 0x5a, sizeof garbage);
    REFUSED(deserialize(c, (const fmi2Byte *)garbage, sizeof garbage, &restored), "garbage bytes");
    for (k = 0; k < STEPS; k++) {
        size_t n = (size_t)inputs(kind, (int)k, in);
        EXPECT(set_real(c, in_vr, n, in) == fmi2OK, "setReal");
        EXPECT(do_step(c, 0.01 * k, 0.01, fmi2True) == fmi2OK, "doStep");
        if (k == STEPS / 2) {
            EXPECT(get_state(c, &state) == fmi2OK && state_size(c, state, &size) == fmi2OK,
                   "getFMUstate");
            bytes = malloc(size);
            EXPECT(serialize(c, state, (fmi2Byte *)bytes, size) == fmi2OK, "serialize");
            EXPECT(deserialize(c, (const fmi2Byte *)bytes, size, &restored) == fmi2OK,
                   "deserialize");
            free(bytes);
        }
    }
    EXPECT(get_real(c, out_vr, n_out, first) == fmi2OK, "getReal");
    EXPECT(set_state(c, restored) == fmi2OK, "setFMUstate");
    for (k = STEPS / 2 + 1; k < STEPS; k++) {
        size_t n = (size_t)inputs(kind, (int)k, in);
        set_real(c, in_vr, n, in);
        do_step(c, 0.01 * k, 0.01, fmi2True);
    }
    EXPECT(get_real(c, out_vr, n_out, again) == fmi2OK, "getReal");
    EXPECT(memcmp(first, again, n_out * sizeof(double)) == 0, "the restored run differs");
    EXPECT(terminate(c) == fmi2OK, "terminate");
    REFUSED(do_step(c, 6.0, 0.01, fmi2True), "doStep after terminate");
    free_state(c, &state);
    free_state(c, &restored);
    free_instance(c);
    for (k = 0; k < n_out; k++) {
        printf("%.17g\n", first[k]);
    }
    return 0;
}

static int run3(void *lib, const char *model, const char *token, const char *kind,
                unsigned n_vars, const fmi3ValueReference *out_vr, size_t n_out)
{
    fmi3InstantiateCoSimulationTYPE *instantiate = sym(lib, "fmi3InstantiateCoSimulation");
    fmi3EnterInitializationModeTYPE *enter = sym(lib, "fmi3EnterInitializationMode");
    fmi3ExitInitializationModeTYPE *exit_init = sym(lib, "fmi3ExitInitializationMode");
    fmi3SetFloat64TYPE *set_real = sym(lib, "fmi3SetFloat64");
    fmi3GetFloat64TYPE *get_real = sym(lib, "fmi3GetFloat64");
    fmi3DoStepTYPE *do_step = sym(lib, "fmi3DoStep");
    fmi3GetFMUStateTYPE *get_state = sym(lib, "fmi3GetFMUState");
    fmi3SetFMUStateTYPE *set_state = sym(lib, "fmi3SetFMUState");
    fmi3FreeFMUStateTYPE *free_state = sym(lib, "fmi3FreeFMUState");
    fmi3SerializedFMUStateSizeTYPE *state_size = sym(lib, "fmi3SerializedFMUStateSize");
    fmi3SerializeFMUStateTYPE *serialize = sym(lib, "fmi3SerializeFMUState");
    fmi3DeserializeFMUStateTYPE *deserialize = sym(lib, "fmi3DeserializeFMUState");
    fmi3TerminateTYPE *terminate = sym(lib, "fmi3Terminate");
    fmi3FreeInstanceTYPE *free_instance = sym(lib, "fmi3FreeInstance");
    fmi3ValueReference in_vr[7] = {0, 1, 2, 3, 4, 5, 6}, bad_vr = n_vars + 5;
    fmi3FMUState state = NULL, restored = NULL;
    fmi3Boolean event, stop, early;
    fmi3Float64 last;
    double in[7], out[MAX_OUT], first[MAX_OUT], again[MAX_OUT], value = 1.0;
    size_t size, k;
    unsigned char *bytes, garbage[64];
    fmi3Instance c;
    (void)model;

    EXPECT(instantiate("bad", "{wrong}", "", fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0,
                       NULL, logger3, NULL) == NULL, "a wrong instantiationToken was accepted");
    EXPECT(errors_logged == 1, "a wrong instantiationToken was not logged");
    c = instantiate("host", token, "", fmi3False, fmi3True, fmi3False, fmi3False, NULL, 0, NULL,
                    logger3, NULL);
    EXPECT(c != NULL, "instantiate failed");
    REFUSED(do_step(c, 0.0, 0.01, fmi3True, &event, &stop, &early, &last),
            "doStep before initialisation");
    EXPECT(enter(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK && exit_init(c) == fmi3OK,
           "initialisation");
    REFUSED(set_real(c, out_vr, 1, &value, 1), "setting an output");
    REFUSED(get_real(c, &bad_vr, 1, out, 1), "getting an unknown value reference");
    REFUSED(set_real(c, &bad_vr, 1, &value, 1), "setting an unknown value reference");
    REFUSED(do_step(c, 0.0, 0.0, fmi3True, &event, &stop, &early, &last), "a zero step size");
    memset(garbage, 0x5a, sizeof garbage);
    REFUSED(deserialize(c, garbage, sizeof garbage, &restored), "garbage bytes");
    for (k = 0; k < STEPS; k++) {
        size_t n = (size_t)inputs(kind, (int)k, in);
        EXPECT(set_real(c, in_vr, n, in, n) == fmi3OK, "setFloat64");
        EXPECT(do_step(c, 0.01 * k, 0.01, fmi3True, &event, &stop, &early, &last) == fmi3OK,
               "doStep");
        if (k == STEPS / 2) {
            EXPECT(get_state(c, &state) == fmi3OK && state_size(c, state, &size) == fmi3OK,
                   "getFMUState");
            bytes = malloc(size);
            EXPECT(serialize(c, state, bytes, size) == fmi3OK, "serialize");
            EXPECT(deserialize(c, bytes, size, &restored) == fmi3OK, "deserialize");
            free(bytes);
        }
    }
    EXPECT(get_real(c, out_vr, n_out, first, n_out) == fmi3OK, "getFloat64");
    EXPECT(set_state(c, restored) == fmi3OK, "setFMUState");
    for (k = STEPS / 2 + 1; k < STEPS; k++) {
        size_t n = (size_t)inputs(kind, (int)k, in);
        set_real(c, in_vr, n, in, n);
        do_step(c, 0.01 * k, 0.01, fmi3True, &event, &stop, &early, &last);
    }
    EXPECT(get_real(c, out_vr, n_out, again, n_out) == fmi3OK, "getFloat64");
    EXPECT(memcmp(first, again, n_out * sizeof(double)) == 0, "the restored run differs");
    EXPECT(terminate(c) == fmi3OK, "terminate");
    REFUSED(do_step(c, 6.0, 0.01, fmi3True, &event, &stop, &early, &last),
            "doStep after terminate");
    free_state(c, &state);
    free_state(c, &restored);
    free_instance(c);
    for (k = 0; k < n_out; k++) {
        printf("%.17g\n", first[k]);
    }
    return 0;
}

int main(int argc, char **argv)
{
    unsigned vr[MAX_OUT];
    size_t n_out = 0;
    void *lib;
    int status, i;
    if (argc < 8 || argc - 7 > MAX_OUT) {
        fprintf(stderr, "usage: %s 2|3 BINARY MODEL TOKEN KIND N_VARIABLES OUTPUT_VR...\n",
                argv[0]);
        return 2;
    }
    for (i = 7; i < argc; i++) {
        vr[n_out++] = (unsigned)strtoul(argv[i], NULL, 10);
    }
    lib = dlopen(argv[2], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 1;
    }
    status = argv[1][0] == '3'
                 ? run3(lib, argv[3], argv[4], argv[5], (unsigned)atoi(argv[6]), vr, n_out)
                 : run2(lib, argv[3], argv[4], argv[5], (unsigned)atoi(argv[6]), vr, n_out);
    dlclose(lib);
    return status;
}
