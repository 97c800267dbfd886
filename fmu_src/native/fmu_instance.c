/* fmu_instance.c: the part of the FMI plumbing that FMI 2.0 and FMI 3.0 share (fmu_model.h):
 * the instance, the log, the state checks, the value table with its checks, the step and the
 * FMU state. The standards' own layers (fmi2Functions.c, fmi3Functions.c) map their calls
 * onto these. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmu_model.h"

static const char *type_name(fmu_type t)
{
    static const char *const names[] = {"Real", "Integer", "Boolean", "Enumeration"};
    return names[t];
}

fmu_instance *fmu_instance_new(const char *name, fmu_emit emit, const void *callbacks,
                               void (*log_message)(void), void *environment, int logging_on)
{
    fmu_instance *inst = calloc(1, sizeof *inst);
    if (!inst) {
        return NULL;
    }
    inst->name = malloc(strlen(name) + 1);
    inst->values = calloc(FMU_MODEL.n_variables ? FMU_MODEL.n_variables : 1, sizeof(double));
    inst->data = calloc(1, FMU_MODEL.data_size ? FMU_MODEL.data_size : 1);
    if (!inst->name || !inst->values || !inst->data) {
        fmu_instance_free(inst);
        return NULL;
    }
    strcpy(inst->name, name);
    inst->emit = emit;
    inst->callbacks = callbacks;
    inst->log_message = log_message;
    inst->environment = environment;
    inst->logging_on = logging_on;
    inst->time_vr = -1;
    fmu_instance_reset(inst);
    return inst;
}

void fmu_instance_free(fmu_instance *inst)
{
    if (!inst) {
        return;
    }
    free(inst->name);
    free(inst->values);
    free(inst->data);
    free(inst);
}

void fmu_instance_reset(fmu_instance *inst)
{
    unsigned i;
    for (i = 0; i < FMU_MODEL.n_variables; i++) {
        inst->values[i] = FMU_MODEL.variables[i].start;
    }
    memset(inst->data, 0, FMU_MODEL.data_size);
    FMU_MODEL.setup(inst->data, inst->values);
    inst->time = 0.0;
    inst->state = FMU_INSTANTIATED;
}

void fmu_log(const fmu_instance *inst, int status, const char *format, ...)
{
    char message[1024];
    va_list args;
    if (!inst || !inst->emit || (status < FMU_ERROR && !inst->logging_on)) {
        return;
    }
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    inst->emit(inst, status,
               status >= FMU_ERROR ? "logStatusError"
                                   : (status == FMU_WARNING ? "logStatusWarning" : "logEvents"),
               message);
}

const char *fmu_state_name(int state)
{
    switch (state) {
    case FMU_INSTANTIATED: return "instantiated";
    case FMU_CONFIGURATION: return "configuration mode";
    case FMU_INITIALIZATION: return "initialization mode";
    case FMU_STEP: return "step mode";
    case FMU_TERMINATED: return "terminated";
    default: return "unknown";
    }
}

int fmu_allow(const fmu_instance *inst, int allowed, const char *call)
{
    if (inst->state & allowed) {
        return FMU_OK;
    }
    fmu_log(inst, FMU_ERROR, "%s is not allowed in state '%s': nothing was done", call,
            fmu_state_name(inst->state));
    return FMU_ERROR;
}

const fmu_variable *fmu_variable_of(const fmu_instance *inst, const char *call, uint32_t vr,
                                    int types)
{
    const fmu_variable *v;
    if (vr >= FMU_MODEL.n_variables) {
        fmu_log(inst, FMU_ERROR, "%s: unknown value reference %lu (this FMU has 0..%u)", call,
                (unsigned long)vr, FMU_MODEL.n_variables - 1);
        return NULL;
    }
    v = &FMU_MODEL.variables[vr];
    if (!(types & FMU_TYPE_BIT(v->type))) {
        fmu_log(inst, FMU_ERROR, "%s: value reference %lu is %s, a %s variable", call,
                (unsigned long)vr, v->name, type_name(v->type));
        return NULL;
    }
    return v;
}

int fmu_get(const fmu_instance *inst, const char *call, const uint32_t vr[], size_t nvr,
            int types, double out[])
{
    size_t i;
    if (nvr > 0 && (!vr || !out)) {
        fmu_log(inst, FMU_ERROR, "%s: NULL value references or values for %lu variables", call,
                (unsigned long)nvr);
        return FMU_ERROR;
    }
    for (i = 0; i < nvr; i++) {
        if (inst->time_vr >= 0 && vr[i] == (uint32_t)inst->time_vr &&
            (types & FMU_TYPE_BIT(FMU_REAL))) {
            out[i] = inst->time;
            continue;
        }
        if (!fmu_variable_of(inst, call, vr[i], types)) {
            return FMU_ERROR;
        }
        out[i] = inst->values[vr[i]];
    }
    return FMU_OK;
}

/* Whether a parameter's value is in its variable's range: fusion_core's Param.validate, finite
 * or +inf where the range has no upper bound. */
static int in_range(const fmu_variable *v, double value)
{
    int ok = isfinite(value) || (value == HUGE_VAL && v->high == HUGE_VAL);
    if (v->low != -HUGE_VAL) {
        ok = ok && (v->low_open ? value > v->low : value >= v->low);
    }
    if (v->high != HUGE_VAL) {
        ok = ok && (v->high_open ? value < v->high : value <= v->high);
    }
    return ok;
}

/* Why the value cannot be taken (a log line), or FMU_OK. */
static int check_value(const fmu_instance *inst, const char *call, const fmu_variable *v,
                       double value)
{
    int ok;
    if (v->causality == FMU_OUTPUT) {
        fmu_log(inst, FMU_ERROR, "%s: %s is an output, computed by the FMU: it cannot be set "
                "(value %.17g refused)", call, v->name, value);
        return FMU_ERROR;
    }
    if (v->causality == FMU_PARAMETER && !v->tunable &&
        !(inst->state & (FMU_INSTANTIATED | FMU_CONFIGURATION | FMU_INITIALIZATION))) {
        fmu_log(inst, FMU_ERROR, "%s: parameter %s is fixed after initialisation: set it before "
                "exitInitializationMode (value %.17g refused, it keeps %.17g)", call, v->name,
                value, inst->values[v - FMU_MODEL.variables]);
        return FMU_ERROR;
    }
    if (v->causality == FMU_INPUT || v->type == FMU_BOOLEAN) {
        return FMU_OK;  /* an input sample is the model's to judge (a bad one is rejected) */
    }
    ok = in_range(v, value);
    if (!ok) {
        fmu_log(inst, FMU_ERROR, "%s: parameter %s = %.17g is out of range: allowed %s%.17g, "
                "%.17g%s; it keeps %.17g", call, v->name, value, v->low_open ? "(" : "[",
                v->low, v->high, v->high_open ? ")" : "]", inst->values[v - FMU_MODEL.variables]);
        return FMU_ERROR;
    }
    return FMU_OK;
}

int fmu_set(fmu_instance *inst, const char *call, const uint32_t vr[], size_t nvr, int types,
            const double in[])
{
    size_t i;
    int tuned = 0;
    if (nvr > 0 && (!vr || !in)) {
        fmu_log(inst, FMU_ERROR, "%s: NULL value references or values for %lu variables", call,
                (unsigned long)nvr);
        return FMU_ERROR;
    }
    for (i = 0; i < nvr; i++) {
        const fmu_variable *v;
        if (inst->time_vr >= 0 && vr[i] == (uint32_t)inst->time_vr) {
            fmu_log(inst, FMU_ERROR, "%s: value reference %lu is time, the independent variable: "
                    "it cannot be set", call, (unsigned long)vr[i]);
            return FMU_ERROR;
        }
        v = fmu_variable_of(inst, call, vr[i], types);
        if (!v || check_value(inst, call, v, in[i]) != FMU_OK) {
            return FMU_ERROR;
        }
    }
    for (i = 0; i < nvr; i++) {
        const fmu_variable *v = &FMU_MODEL.variables[vr[i]];
        double value = v->type == FMU_BOOLEAN ? (in[i] != 0.0) : in[i];
        if (v->causality == FMU_PARAMETER && inst->state == FMU_STEP &&
            inst->values[vr[i]] != value) {
            tuned = 1;
        }
        inst->values[vr[i]] = value;
    }
    if (tuned) {
        FMU_MODEL.tune(inst->data, inst->values);
    }
    return FMU_OK;
}

int fmu_no_variables(const fmu_instance *inst, const char *call, const char *type,
                     const uint32_t vr[], size_t nvr)
{
    if (nvr == 0) {
        return FMU_OK;
    }
    fmu_log(inst, FMU_ERROR, "%s: this FMU has no %s variables (value reference %lu)", call, type,
            vr ? (unsigned long)vr[0] : 0ul);
    return FMU_ERROR;
}

int fmu_exit_initialization(fmu_instance *inst)
{
    memset(inst->data, 0, FMU_MODEL.data_size);
    FMU_MODEL.setup(inst->data, inst->values);
    inst->state = FMU_STEP;
    return FMU_OK;
}

int fmu_do_step(fmu_instance *inst, double t, double h)
{
    char message[512];
    if (!(h > 0.0) || !isfinite(h) || !isfinite(t)) {
        fmu_log(inst, FMU_ERROR, "doStep(t = %.17g, h = %.17g): the communication step size must "
                "be finite and > 0, and the time finite: nothing was done", t, h);
        return FMU_ERROR;
    }
    message[0] = '\0';
    if (FMU_MODEL.step(inst->data, inst->values, t, h, message, sizeof message)) {
        fmu_log(inst, FMU_WARNING, "%s", message);
    }
    inst->time = t + h;
    return FMU_OK;
}

/* ----- FMU state ----------------------------------------------------------------------------- */

#define STATE_MAGIC "IMUFMUST"
#define STATE_FORMAT 2u  /* 2: values and the model's state fields, as doubles (fmu_model.h) */
#define MODEL_NAME_SIZE 48

/* The header every FMU state starts with. */
typedef struct state_header {
    char magic[8];
    char model[MODEL_NAME_SIZE];
    uint32_t format;
    uint32_t n_variables;
    uint64_t n_state;               /* the model's state fields, in doubles */
    uint64_t length;                /* of the whole state, header included */
    uint64_t checksum;              /* fnv1a of everything after the header */
} state_header;

/* Then the body: this, the values (n_variables doubles) and the state fields (n_state). */
typedef struct state_body {
    int32_t state;
    int32_t reserved;
    double time;
} state_body;

/* FNV-1a over 64-bit words (memcpy'ed: the bytes may lie anywhere), then the last bytes one by
 * one: a state of the position filter is 83 kB, checked at every deserialize and set. */
static uint64_t fnv1a(const unsigned char *p, size_t n)
{
    uint64_t h = 14695981039346656037ull, w;
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        memcpy(&w, p + i, 8);
        h ^= w;
        h *= 1099511628211ull;
    }
    for (; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

static size_t state_doubles(void)
{
    return FMU_MODEL.state ? (size_t)fc_state_size(FMU_MODEL.state) : 0;
}

static size_t body_size(void)
{
    return sizeof(state_body) + (FMU_MODEL.n_variables + state_doubles()) * sizeof(double);
}

size_t fmu_state_size(void)
{
    return sizeof(state_header) + body_size();
}

void fmu_state_seal(unsigned char *state)
{
    state_header h;
    memcpy(&h, state, sizeof h);
    h.checksum = fnv1a(state + sizeof h, body_size());
    memcpy(state, &h, sizeof h);
}

void fmu_state_write(const fmu_instance *inst, unsigned char *out)
{
    state_header h;
    state_body b;
    unsigned char *body = out + sizeof h;
    size_t n_values = FMU_MODEL.n_variables * sizeof(double);
    memset(&h, 0, sizeof h);
    memset(&b, 0, sizeof b);
    b.state = inst->state;
    b.time = inst->time;
    memcpy(body, &b, sizeof b);
    memcpy(body + sizeof b, inst->values, n_values);
    if (FMU_MODEL.state) {
        /* body + sizeof b is 8-byte aligned: the state is malloc'ed and the header's size is a
         * multiple of 8 */
        fc_state_save(FMU_MODEL.state, inst->data, (double *)(void *)(body + sizeof b + n_values));
    }
    memcpy(h.magic, STATE_MAGIC, sizeof h.magic);
    strncpy(h.model, FMU_MODEL.name, MODEL_NAME_SIZE - 1);
    h.format = STATE_FORMAT;
    h.n_variables = FMU_MODEL.n_variables;
    h.n_state = state_doubles();
    h.length = fmu_state_size();
    memcpy(out, &h, sizeof h);
    fmu_state_seal(out);
}

/* Why a restored value does not fit its variable (into why), or 0: of its type (an Integer or
 * Enumeration whole, a Boolean 0 or 1), a parameter in its range, an output finite and in its
 * range; an input may hold anything a host may set (a bad sample is the model's to reject). */
static int value_problem(const fmu_variable *v, double x, char *why, size_t size)
{
    if (v->type == FMU_BOOLEAN && x != 0.0 && x != 1.0) {
        snprintf(why, size, "the value of %s is %.17g, not a Boolean", v->name, x);
        return 1;
    }
    if ((v->type == FMU_INTEGER || v->type == FMU_ENUMERATION) &&
        (!isfinite(x) || x != floor(x) || x < -2147483648.0 || x > 2147483647.0)) {
        snprintf(why, size, "the value of %s is %.17g, not an Integer", v->name, x);
        return 1;
    }
    if (v->causality == FMU_INPUT || v->type == FMU_BOOLEAN) {
        return 0;
    }
    if (!in_range(v, x) || (v->causality == FMU_OUTPUT && !isfinite(x))) {
        snprintf(why, size, "the value of %s %s is %.17g: allowed %s%.17g, %.17g%s",
                 v->causality == FMU_OUTPUT ? "output" : "parameter", v->name, x,
                 v->low_open ? "(" : "[", v->low, v->high, v->high_open ? ")" : "]");
        return 1;
    }
    return 0;
}

/* The body's values and state fields as doubles: an aligned copy of bytes that may lie anywhere
 * in the host's memory; NULL when out of memory. */
static double *body_doubles(const unsigned char *body)
{
    size_t n = FMU_MODEL.n_variables + state_doubles();
    double *d = malloc(n ? n * sizeof(double) : sizeof(double));
    if (d) {
        memcpy(d, body + sizeof(state_body), n * sizeof(double));
    }
    return d;
}

/* Why the body's FMI state, time, values and state fields do not pass (into why), or 0. */
static int body_problem(const fmu_instance *inst, const unsigned char *body, const double *d,
                        char *why, size_t size)
{
    state_body b;
    unsigned i;
    memcpy(&b, body, sizeof b);
    if ((b.state != FMU_INSTANTIATED && b.state != FMU_CONFIGURATION &&
         b.state != FMU_INITIALIZATION && b.state != FMU_STEP && b.state != FMU_TERMINATED) ||
        (b.state == FMU_CONFIGURATION && inst->time_vr < 0) || b.reserved != 0) {
        snprintf(why, size, "it holds no FMI state of this standard (%ld)", (long)b.state);
        return 1;
    }
    if (!isfinite(b.time)) {
        snprintf(why, size, "its time %.17g is not finite", b.time);
        return 1;
    }
    for (i = 0; i < FMU_MODEL.n_variables; i++) {
        if (value_problem(&FMU_MODEL.variables[i], d[i], why, size)) {
            return 1;
        }
    }
    if (FMU_MODEL.state &&
        fc_state_check(FMU_MODEL.state, d + FMU_MODEL.n_variables, why, size) != 0) {
        return 1;
    }
    return 0;
}

/* The checked values and state fields of a state (malloc'ed: the caller frees them), or NULL
 * with a log line naming what is wrong. */
static double *checked_body(const fmu_instance *inst, const char *call, const unsigned char *in,
                            size_t size)
{
    state_header h;
    const unsigned char *body;
    char model[MODEL_NAME_SIZE];
    char why[512];
    double *d;
    if (!in || size < sizeof h) {
        fmu_log(inst, FMU_ERROR, "%s: %lu bytes are not an FMU state of %s (a state is %lu "
                "bytes): the FMU keeps its state", call, (unsigned long)size, FMU_MODEL.name,
                (unsigned long)fmu_state_size());
        return NULL;
    }
    memcpy(&h, in, sizeof h);
    memset(model, 0, sizeof model);
    strncpy(model, FMU_MODEL.name, MODEL_NAME_SIZE - 1);
    if (memcmp(h.magic, STATE_MAGIC, sizeof h.magic) != 0) {
        fmu_log(inst, FMU_ERROR, "%s: not an FMU state of this project (wrong magic): the FMU "
                "keeps its state", call);
        return NULL;
    }
    if (memcmp(h.model, model, MODEL_NAME_SIZE) != 0 || h.format != STATE_FORMAT ||
        h.n_variables != FMU_MODEL.n_variables || h.n_state != state_doubles()) {
        h.model[MODEL_NAME_SIZE - 1] = '\0';
        fmu_log(inst, FMU_ERROR, "%s: a state of model '%s', format %lu, does not fit %s, format "
                "%lu: the FMU keeps its state", call, h.model, (unsigned long)h.format,
                FMU_MODEL.name, (unsigned long)STATE_FORMAT);
        return NULL;
    }
    body = in + sizeof h;
    if (h.length != fmu_state_size() || size < h.length ||
        h.checksum != fnv1a(body, body_size())) {
        fmu_log(inst, FMU_ERROR, "%s: the state is truncated or corrupted (length %lu of %lu "
                "bytes, or its checksum differs): the FMU keeps its state", call,
                (unsigned long)size, (unsigned long)fmu_state_size());
        return NULL;
    }
    d = body_doubles(body);
    if (!d) {
        fmu_log(inst, FMU_ERROR, "%s: out of memory: the FMU keeps its state", call);
        return NULL;
    }
    if (body_problem(inst, body, d, why, sizeof why)) {
        free(d);
        fmu_log(inst, FMU_ERROR, "%s: the state is refused, the FMU keeps its state: %s", call,
                why);
        return NULL;
    }
    return d;
}

int fmu_state_check(const fmu_instance *inst, const char *call, const unsigned char *in,
                    size_t size)
{
    double *d = checked_body(inst, call, in, size);
    free(d);
    return d ? FMU_OK : FMU_ERROR;
}

int fmu_state_read(fmu_instance *inst, const char *call, const unsigned char *in, size_t size)
{
    state_body b;
    size_t n_values = FMU_MODEL.n_variables * sizeof(double);
    double *d = checked_body(inst, call, in, size), *scratch;
    void *data;
    if (!d) {
        return FMU_ERROR;
    }
    scratch = malloc(n_values ? n_values : 1);
    data = calloc(1, FMU_MODEL.data_size ? FMU_MODEL.data_size : 1);
    if (!scratch || !data) {
        free(d);
        free(scratch);
        free(data);
        fmu_log(inst, FMU_ERROR, "%s: out of memory: the FMU keeps its state", call);
        return FMU_ERROR;
    }
    /* the model from the restored parameters (setup may write outputs: into a scratch copy of
     * the values), then its state fields */
    memcpy(scratch, d, n_values);
    FMU_MODEL.setup(data, scratch);
    if (FMU_MODEL.state) {
        fc_state_load(FMU_MODEL.state, data, d + FMU_MODEL.n_variables);
    }
    if (FMU_MODEL.restored) {
        FMU_MODEL.restored(data);
    }
    memcpy(&b, in + sizeof(state_header), sizeof b);
    inst->state = b.state;
    inst->time = b.time;
    memcpy(inst->values, d, n_values);
    memcpy(inst->data, data, FMU_MODEL.data_size);
    free(d);
    free(scratch);
    free(data);
    return FMU_OK;
}

/* ----- the FMU-state calls both standards share: a state is a malloc'ed copy of
 * fmu_state_size() bytes (fmu_state_write) --------------------------------------------------- */

/* *state (allocated when NULL) holds the bytes, or FMU_ERROR with a log line. */
static int fill_state(const fmu_instance *inst, const char *call, void **state,
                      const unsigned char *bytes)
{
    unsigned char *out;
    if (!state) {
        fmu_log(inst, FMU_ERROR, "%s: the FMU state pointer is NULL", call);
        return FMU_ERROR;
    }
    out = *state ? (unsigned char *)*state : malloc(fmu_state_size());
    if (!out) {
        fmu_log(inst, FMU_ERROR, "%s: out of memory", call);
        return FMU_ERROR;
    }
    if (bytes) {
        memcpy(out, bytes, fmu_state_size());
    } else {
        fmu_state_write(inst, out);
    }
    *state = out;
    return FMU_OK;
}

int fmu_state_get(const fmu_instance *inst, const char *call, void **state)
{
    return fill_state(inst, call, state, NULL);
}

int fmu_state_size_of(const fmu_instance *inst, const char *call, size_t *size)
{
    if (!size) {
        fmu_log(inst, FMU_ERROR, "%s: size is NULL", call);
        return FMU_ERROR;
    }
    *size = fmu_state_size();
    return FMU_OK;
}

int fmu_state_serialize(const fmu_instance *inst, const char *call, const void *state,
                        void *out, size_t size)
{
    if (!state || !out || size < fmu_state_size()) {
        fmu_log(inst, FMU_ERROR, "%s: needs a state and %lu bytes (got %lu)", call,
                (unsigned long)fmu_state_size(), (unsigned long)size);
        return FMU_ERROR;
    }
    memcpy(out, state, fmu_state_size());
    return FMU_OK;
}

int fmu_state_deserialize(const fmu_instance *inst, const char *call, const void *in,
                          size_t size, void **state)
{
    if (fmu_state_check(inst, call, in, size) != FMU_OK) {
        return FMU_ERROR;
    }
    return fill_state(inst, call, state, in);
}

void fmu_state_free(void **state)
{
    if (state) {
        free(*state);
        *state = NULL;
    }
}
