/* state_fuzz.c: a host that feeds one native FMU mutated FMU states (tests/test_fmu_state_fuzz.py).
 *
 * Compiled together with the FMU's own sources (its config.h, the FMI plumbing of one standard,
 * the model and the C twin), under AddressSanitizer and UBSan where the compiler has them, so
 * that a read or a write outside the FMU's memory stops the run:
 *
 *   cc -DFUZZ_FMI=2|3 -DFUZZ_KIND_ESTIMATOR|_SENSOR|_PLANT -I SOURCES state_fuzz.c SOURCES/... -lm
 *   state_fuzz N SEED
 *
 * It runs the FMU through samples that keep every state busy (motion, rest, bad samples), saves
 * valid states at several moments (before and during initialisation, aligning, in motion, at
 * rest), then N times: takes one, mutates its bytes (random bit flips; an extreme value in one
 * value or state field; integer fields, the FMI state, the time and the header fields out of
 * range; truncations; lengths off by one), recomputes the checksum (mostly, so that the mutation
 * reaches the field checks), and hands the bytes to deserialize + set (FMI 2.0
 * fmi2DeSerializeFMUstate / fmi2SetFMUstate, FMI 3.0 fmi3DeserializeFMUState / fmi3SetFMUState)
 * or, same-sized, straight to set as a state. A refused state must be an error status with a log
 * line; an accepted one must give finite outputs, then and over the next valid samples. Prints
 * one line: tried, refused, accepted, non-finite, silent refusals, and exits 0 when the last two
 * are 0 (ASan and UBSan abort on their own findings).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "fmu_model.h"

#if FUZZ_FMI == 3
#include "fmi3Functions.h"
#else
#include "fmi2Functions.h"
#endif

#define STEPS 700
#define MAX_SAVED 8

static long errors_logged;

/* xorshift64*: a small reproducible generator (the seed is the test's) */
static uint64_t rng_state = 88172645463325252ull;
static uint64_t next_u64(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ull;
}
static size_t below(size_t n) { return n ? (size_t)(next_u64() % n) : 0; }

/* ----- the two standards behind one small API ----------------------------------------------- */
#if FUZZ_FMI == 3
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                   fmi3String message)
{
    (void)env;
    (void)category;
    (void)message;
    if (status >= fmi3Error) {
        errors_logged++;
    }
}
typedef fmi3Instance instance;
typedef fmi3FMUState fmu_state;
static instance open_instance(void)
{
    instance c = fmi3InstantiateCoSimulation("fuzz", MODEL_TOKEN, NULL, fmi3False, fmi3True,
                                             fmi3False, fmi3False, NULL, 0, NULL, logger, NULL);
    return c;
}
static int enter_init(instance c) { return fmi3EnterInitializationMode(c, 0, 0, 0.0, 0, 0); }
static int exit_init(instance c) { return fmi3ExitInitializationMode(c); }
static int set_real(instance c, unsigned vr, double v)
{
    fmi3ValueReference r = vr;
    return fmi3SetFloat64(c, &r, 1, &v, 1);
}
static int get_real(instance c, unsigned vr, double *v)
{
    fmi3ValueReference r = vr;
    return fmi3GetFloat64(c, &r, 1, v, 1);
}
static int do_step(instance c, double t, double h)
{
    fmi3Boolean event = 0, term = 0, early = 0;
    fmi3Float64 last = 0.0;
    return fmi3DoStep(c, t, h, fmi3False, &event, &term, &early, &last);
}
static int get_state(instance c, fmu_state *s) { return fmi3GetFMUState(c, s); }
static int set_state(instance c, fmu_state s) { return fmi3SetFMUState(c, s); }
static void free_state(instance c, fmu_state *s) { fmi3FreeFMUState(c, s); }
static size_t state_size(instance c, fmu_state s)
{
    size_t n = 0;
    fmi3SerializedFMUStateSize(c, s, &n);
    return n;
}
static int serialize(instance c, fmu_state s, unsigned char *out, size_t n)
{
    return fmi3SerializeFMUState(c, s, out, n);
}
static int deserialize(instance c, const unsigned char *in, size_t n, fmu_state *s)
{
    return fmi3DeserializeFMUState(c, in, n, s);
}
static void close_instance(instance c) { fmi3FreeInstance(c); }
#define STATUS_ERROR fmi3Error
#else
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    (void)name;
    (void)category;
    (void)message;
    if (status >= fmi2Error) {
        errors_logged++;
    }
}
static const fmi2CallbackFunctions CALLBACKS = {logger, calloc, free, NULL, NULL};
typedef fmi2Component instance;
typedef fmi2FMUstate fmu_state;
static instance open_instance(void)
{
    return fmi2Instantiate("fuzz", fmi2CoSimulation, MODEL_TOKEN, NULL, &CALLBACKS, fmi2False,
                           fmi2True);
}
static int enter_init(instance c)
{
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    return fmi2EnterInitializationMode(c);
}
static int exit_init(instance c) { return fmi2ExitInitializationMode(c); }
static int set_real(instance c, unsigned vr, double v)
{
    fmi2ValueReference r = vr;
    return fmi2SetReal(c, &r, 1, &v);
}
static int get_real(instance c, unsigned vr, double *v)
{
    fmi2ValueReference r = vr;
    return fmi2GetReal(c, &r, 1, v);
}
static int do_step(instance c, double t, double h) { return fmi2DoStep(c, t, h, fmi2True); }
static int get_state(instance c, fmu_state *s) { return fmi2GetFMUstate(c, s); }
static int set_state(instance c, fmu_state s) { return fmi2SetFMUstate(c, s); }
static void free_state(instance c, fmu_state *s) { fmi2FreeFMUstate(c, s); }
static size_t state_size(instance c, fmu_state s)
{
    size_t n = 0;
    fmi2SerializedFMUstateSize(c, s, &n);
    return n;
}
static int serialize(instance c, fmu_state s, unsigned char *out, size_t n)
{
    return fmi2SerializeFMUstate(c, s, (fmi2Byte *)out, n);
}
static int deserialize(instance c, const unsigned char *in, size_t n, fmu_state *s)
{
    return fmi2DeSerializeFMUstate(c, (const fmi2Byte *)in, n, s);
}
static void close_instance(instance c) { fmi2FreeInstance(c); }
#define STATUS_ERROR fmi2Error
#endif

/* ----- the samples: every input of the model at step k ------------------------------------- */
static void set_inputs(instance c, long k)
{
    double t = 0.01 * (double)k;
#if defined(FUZZ_KIND_ESTIMATOR)
    double roll = 0.6 * sin(0.7 * t), pitch = 0.4 * sin(0.45 * t + 0.3);
    double a[3], g[3], dt = 0.01;
    int rest = (k % 700) > 350 && (k % 700) < 600;  /* rest: the bias, the position queue */
    a[0] = -9.80665 * sin(pitch) + 0.8 * sin(11.0 * t);
    a[1] = 9.80665 * sin(roll) * cos(pitch);
    a[2] = 9.80665 * cos(roll) * cos(pitch);
    g[0] = 0.42 * cos(0.7 * t) + 0.01;
    g[1] = 0.18 * cos(0.45 * t + 0.3) - 0.006;
    g[2] = 0.2 * sin(0.1 * t);
    if (rest) {
        a[0] = a[1] = 0.0;
        a[2] = 9.80665;
        g[0] = 0.01;
        g[1] = -0.006;
        g[2] = 0.004;
    }
    if (k % 53 == 7) {
        a[1] = NAN;  /* a rejected sample now and then */
    }
    set_real(c, VR_acc_x, a[0]);
    set_real(c, VR_acc_y, a[1]);
    set_real(c, VR_acc_z, a[2]);
    set_real(c, VR_gyro_x, g[0]);
    set_real(c, VR_gyro_y, g[1]);
    set_real(c, VR_gyro_z, g[2]);
    set_real(c, VR_dt, dt);
#elif defined(FUZZ_KIND_SENSOR)
    set_real(c, VR_omega_x, 0.4 * sin(t));
    set_real(c, VR_omega_y, 0.3 * cos(0.5 * t));
    set_real(c, VR_omega_z, 0.1);
    set_real(c, VR_f_x, 0.5 * sin(3.0 * t));
    set_real(c, VR_f_y, 0.2);
    set_real(c, VR_f_z, 9.80665);
#else
    (void)c;
    (void)t;
#endif
}

/* Every Real output finite, where the instance's state lets a host read it (getReal before
 * initialisation is refused, as the standard says). */
static int outputs_finite(instance c)
{
    unsigned vr;
    for (vr = 0; vr < N_VARIABLES; vr++) {
        double v = 0.0;
        if (VARIABLES[vr].causality == FMU_OUTPUT && VARIABLES[vr].type == FMU_REAL &&
            get_real(c, vr, &v) == 0 && !isfinite(v)) {
            fprintf(stderr, "non-finite output %s = %.17g\n", VARIABLES[vr].name, v);
            return 0;
        }
    }
    return 1;
}

/* ----- mutations ---------------------------------------------------------------------------- */
static const double EXTREMES[] = {
    NAN, INFINITY, -INFINITY, 1e308, -1e308, 1e300, -1e300, 2e150, -2e150, 1e151, -1.0, 0.0,
    0.5, 1.5, 4.0, 7.0, 1e-320, 2147483648.0, -2147483649.0, 9007199254740994.0,
    9223372036854775808.0, -9223372036854775808.0, 2048.0, 2049.0, 6.0, 3.2, -3.2, 1.6,
    1e10, 1e20,
};
#define N_EXTREMES (sizeof EXTREMES / sizeof EXTREMES[0])
#define HEADER 88  /* sizeof(state_header) in fmu_instance.c */
#define BODY_HEAD 16  /* sizeof(state_body) */

static void put_double(unsigned char *p, double x) { memcpy(p, &x, sizeof x); }

/* What the double at byte offset `at` of a state is: a variable's value or a state field. */
static void describe(size_t at, char *out, size_t size)
{
    long i = ((long)at - HEADER - BODY_HEAD) / 8;
    int f;
    if ((long)at < HEADER + BODY_HEAD) {
        snprintf(out, size, "the header or the FMI state");
        return;
    }
    if (i < (long)N_VARIABLES) {
        snprintf(out, size, "variable %s", VARIABLES[i].name);
        return;
    }
    i -= N_VARIABLES;
    for (f = 0; FMU_MODEL.state && f < FMU_MODEL.state->n_fields; f++) {
        const fc_field *field = &FMU_MODEL.state->fields[f];
        if (i < field->count) {
            snprintf(out, size, "state field %s[%ld]", field->name, i);
            return;
        }
        i -= field->count;
    }
    snprintf(out, size, "byte %lu", (unsigned long)at);
}

static size_t last_slot;  /* the double the last mutation changed (0: none in particular) */

/* A double of the body, each variable and each state field as likely as any other (the
 * position filter's queue is 10,240 of its 10,400 values), an element of it at random. */
static size_t random_slot(void)
{
    size_t fields = FMU_MODEL.state ? (size_t)FMU_MODEL.state->n_fields : 0;
    size_t pick = below(N_VARIABLES + fields), at = N_VARIABLES;
    int f;
    if (pick < N_VARIABLES) {
        return HEADER + BODY_HEAD + 8 * pick;
    }
    for (f = 0; f < (int)(pick - N_VARIABLES); f++) {
        at += (size_t)FMU_MODEL.state->fields[f].count;
    }
    return HEADER + BODY_HEAD + 8 * (at + below((size_t)FMU_MODEL.state->fields[f].count));
}

/* One mutation of a state of n bytes in buf (capacity n + 1), possibly changing *len. */
static void mutate(unsigned char *buf, size_t n, size_t *len, int *seal)
{
    size_t slot = random_slot();
    int i, kind = (int)below(12);
    *seal = 1;
    *len = n;
    last_slot = slot;
    switch (kind) {
    case 0: case 1: case 2:  /* an extreme value in one value or state field */
        put_double(buf + slot, EXTREMES[below(N_EXTREMES)]);
        break;
    case 3:  /* a random double */
        {
            uint64_t bits = next_u64();
            memcpy(buf + slot, &bits, 8);
        }
        break;
    case 4:  /* a state field at +-1 ulp-ish, a count one past */
        {
            double x;
            memcpy(&x, buf + slot, 8);
            put_double(buf + slot, below(2) ? x + 1.0 : -x - 1.0);
        }
        break;
    case 5:  /* random bit flips anywhere after the header */
        for (i = 0; i < 1 + (int)below(8); i++) {
            size_t at = HEADER + below(n - HEADER);
            buf[at] ^= (unsigned char)(1u << below(8));
        }
        break;
    case 6:  /* random bit flips anywhere, the checksum mostly resealed */
        for (i = 0; i < 1 + (int)below(4); i++) {
            size_t at = below(n);
            buf[at] ^= (unsigned char)(1u << below(8));
        }
        *seal = below(4) != 0;
        break;
    case 7:  /* the FMI state, its reserved word, the time */
        {
            int32_t v[] = {-1, 0, 3, 5, 6, 7, 16, 31, 32, 1 << 30, INT32_MIN, 2};
            unsigned char *body = buf + HEADER;
            if (below(3) == 0) {
                put_double(body + 8, EXTREMES[below(3)]);
            } else {
                memcpy(body + 4 * below(2), &v[below(sizeof v / sizeof v[0])], 4);
            }
        }
        break;
    case 8:  /* a header field: n_variables, n_state, length, format */
        {
            size_t at[] = {56, 60, 64, 72};
            uint64_t v = below(2) ? next_u64() : (uint64_t)below(3) - 1;
            size_t k = below(4);
            memcpy(buf + at[k], &v, k < 2 ? 4 : 8);
            *seal = below(2);
        }
        break;
    case 9:  /* truncated */
        *len = below(n);
        break;
    case 10:  /* one byte short, or one more */
        *len = below(2) ? n - 1 : n + 1;
        break;
    default:  /* the checksum left stale */
        put_double(buf + slot, EXTREMES[below(N_EXTREMES)]);
        *seal = 0;
        break;
    }
}

int main(int argc, char **argv)
{
    long n = argc > 1 ? atol(argv[1]) : 1000, k, trial;
    unsigned char *saved[MAX_SAVED], *mutated;
    size_t size = 0;
    int n_saved = 0;
    long refused = 0, accepted = 0, nonfinite = 0, silent = 0;
    instance c;
    fmu_state s = NULL;
    if (argc > 2) {
        rng_state ^= (uint64_t)atoll(argv[2]) * 0x9E3779B97F4A7C15ull;
    }
    c = open_instance();
    if (!c) {
        fprintf(stderr, "instantiate failed\n");
        return 2;
    }
    /* valid states: instantiated, in initialisation, then along the run */
    get_state(c, &s);
    size = state_size(c, s);
    saved[n_saved] = malloc(size);
    serialize(c, s, saved[n_saved++], size);
    enter_init(c);
    get_state(c, &s);
    saved[n_saved] = malloc(size);
    serialize(c, s, saved[n_saved++], size);
    exit_init(c);
    for (k = 0; k < STEPS; k++) {
        set_inputs(c, k);
        do_step(c, 0.01 * (double)k, 0.01);
        if ((k == 20 || k == 150 || k == 420 || k == 560 || k == STEPS - 1) &&
            n_saved < MAX_SAVED) {  /* aligning, moving, at rest (queue), leaving it, the end */
            get_state(c, &s);
            saved[n_saved] = malloc(size);
            serialize(c, s, saved[n_saved++], size);
        }
    }
    free_state(c, &s);
    mutated = malloc(size);
    for (trial = 0; trial < n; trial++) {
        const unsigned char *base = saved[below((size_t)n_saved)];
        unsigned char *buf;
        size_t len;
        int seal, status, direct;
        long before = errors_logged;
        fmu_state got = NULL;
        char what[96];
        double value;
        buf = malloc(size + 1);
        memcpy(buf, base, size);
        buf[size] = 0;
        mutate(buf, size, &len, &seal);
        if (seal) {
            fmu_state_seal(buf);
        }
        memcpy(mutated, buf, size);
        direct = len == size && below(4) == 0;
        if (direct) {  /* the bytes as a state the host hands back */
            unsigned char *exact = malloc(size);
            memcpy(exact, buf, size);
            status = set_state(c, (fmu_state)exact);
            free(exact);
        } else {
            /* exactly len bytes, so that AddressSanitizer sees a read past them */
            unsigned char *exact = malloc(len ? len : 1);
            memcpy(exact, buf, len);
            status = deserialize(c, exact, len, &got);
            free(exact);
            if (status == 0) {
                status = set_state(c, got);
                free_state(c, &got);
            }
        }
        free(buf);
        if (status != 0) {
            refused++;
            if (status != STATUS_ERROR || errors_logged == before) {
                silent++;
            }
            continue;
        }
        accepted++;
        describe(last_slot, what, sizeof what);
        memcpy(&value, mutated + last_slot, sizeof value);
        if (!outputs_finite(c)) {
            fprintf(stderr, "  after a restore; mutated %s = %.17g\n", what, value);
            nonfinite++;
            continue;
        }
        for (k = 0; k < 5; k++) {  /* step on (a state before initialisation refuses: fine) */
            set_inputs(c, 100 + k);
            do_step(c, 1000.0 + 0.01 * (double)k, 0.01);
        }
        if (!outputs_finite(c)) {
            fprintf(stderr, "  after 5 steps; mutated %s = %.17g\n", what, value);
            nonfinite++;
        }
    }
    for (k = 0; k < n_saved; k++) {
        free(saved[k]);
    }
    free(mutated);
    close_instance(c);
    printf("tried %ld refused %ld accepted %ld nonfinite %ld silent %ld state_bytes %lu\n", n,
           refused, accepted, nonfinite, silent, (unsigned long)size);
    return nonfinite || silent ? 1 : 0;
}
