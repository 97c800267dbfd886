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
    inst->time = 0.0;
    fmu_instance_setup(inst);
    inst->state = FMU_INSTANTIATED;
}

void fmu_instance_setup(fmu_instance *inst)
{
    memset(inst->data, 0, FMU_MODEL.data_size);
    FMU_MODEL.setup(inst->data, inst->values, inst->time);
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
    int tuned = 0, configured = 0;
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
        if (v->causality == FMU_PARAMETER && inst->values[vr[i]] != value) {
            tuned |= inst->state == FMU_STEP;
            configured |= (inst->state & (FMU_INSTANTIATED | FMU_CONFIGURATION |
                                          FMU_INITIALIZATION)) != 0;
        }
        inst->values[vr[i]] = value;
    }
    if (tuned) {
        FMU_MODEL.tune(inst->data, inst->values);
    }
    if (configured) {
        fmu_instance_setup(inst);  /* before step mode: outputs follow the parameters */
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
    fmu_instance_setup(inst);
    inst->state = FMU_STEP;
    return FMU_OK;
}

/* How far (relative, at least 1 s's worth) a communication point may lie from the FMU's time:
 * masters sum their steps in their own way (libcosim in integer nanoseconds), so t and the
 * FMU's own sum differ by rounding; a skipped or repeated step differs by a whole step. */
#define STEP_TIME_TOLERANCE 1e-9

int fmu_do_step(fmu_instance *inst, double t, double h)
{
    char message[512];
    if (!(h > 0.0) || !isfinite(h) || !isfinite(t)) {
        fmu_log(inst, FMU_ERROR, "doStep(t = %.17g, h = %.17g): the communication step size must "
                "be finite and > 0, and the time finite: nothing was done", t, h);
        return FMU_ERROR;
    }
    if (fabs(t - inst->time) > STEP_TIME_TOLERANCE * fmax(1.0, fabs(inst->time))) {
        fmu_log(inst, FMU_ERROR, "doStep(t = %.17g, h = %.17g): the communication point must be "
                "the FMU's current time %.17g (the end of the last step, or the start time): "
                "nothing was done", t, h, inst->time);
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
#define STATE_FORMAT 3u  /* 3: values and the model's state fields, as doubles (fmu_model.h),
                            * CRC-64 checked */
#define MODEL_NAME_SIZE 48

/* The header every FMU state starts with. */
typedef struct state_header {
    char magic[8];
    char model[MODEL_NAME_SIZE];
    uint32_t format;
    uint32_t n_variables;
    uint64_t n_state;               /* the model's state fields, in doubles */
    uint64_t length;                /* of the whole state, header included */
    uint64_t checksum;              /* crc64 of everything after the header */
} state_header;

/* Then the body: this, the values (n_variables doubles) and the state fields (n_state). */
typedef struct state_body {
    int32_t state;
    int32_t reserved;
    double time;
} state_body;

/* CRC-64/XZ (ECMA-182 polynomial, reflected; init and final xor all ones), a byte at a time
 * from a constant table. A CRC of degree 64 detects every change confined to 64 consecutive
 * bits and every change of two bits, so any change of one word, and of two words whose
 * differences fit its Hamming distance, is refused for certain (a word-wise FNV hash missed
 * sign flips of two words: the top bits of a product never reach a lower bit). */
static const uint64_t CRC64_TABLE[256] = {
    0x0000000000000000u, 0xb32e4cbe03a75f6fu, 0xf4843657a840a05bu,
    0x47aa7ae9abe7ff34u, 0x7bd0c384ff8f5e33u, 0xc8fe8f3afc28015cu,
    0x8f54f5d357cffe68u, 0x3c7ab96d5468a107u, 0xf7a18709ff1ebc66u,
    0x448fcbb7fcb9e309u, 0x0325b15e575e1c3du, 0xb00bfde054f94352u,
    0x8c71448d0091e255u, 0x3f5f08330336bd3au, 0x78f572daa8d1420eu,
    0xcbdb3e64ab761d61u, 0x7d9ba13851336649u, 0xceb5ed8652943926u,
    0x891f976ff973c612u, 0x3a31dbd1fad4997du, 0x064b62bcaebc387au,
    0xb5652e02ad1b6715u, 0xf2cf54eb06fc9821u, 0x41e11855055bc74eu,
    0x8a3a2631ae2dda2fu, 0x39146a8fad8a8540u, 0x7ebe1066066d7a74u,
    0xcd905cd805ca251bu, 0xf1eae5b551a2841cu, 0x42c4a90b5205db73u,
    0x056ed3e2f9e22447u, 0xb6409f5cfa457b28u, 0xfb374270a266cc92u,
    0x48190ecea1c193fdu, 0x0fb374270a266cc9u, 0xbc9d3899098133a6u,
    0x80e781f45de992a1u, 0x33c9cd4a5e4ecdceu, 0x7463b7a3f5a932fau,
    0xc74dfb1df60e6d95u, 0x0c96c5795d7870f4u, 0xbfb889c75edf2f9bu,
    0xf812f32ef538d0afu, 0x4b3cbf90f69f8fc0u, 0x774606fda2f72ec7u,
    0xc4684a43a15071a8u, 0x83c230aa0ab78e9cu, 0x30ec7c140910d1f3u,
    0x86ace348f355aadbu, 0x3582aff6f0f2f5b4u, 0x7228d51f5b150a80u,
    0xc10699a158b255efu, 0xfd7c20cc0cdaf4e8u, 0x4e526c720f7dab87u,
    0x09f8169ba49a54b3u, 0xbad65a25a73d0bdcu, 0x710d64410c4b16bdu,
    0xc22328ff0fec49d2u, 0x85895216a40bb6e6u, 0x36a71ea8a7ace989u,
    0x0adda7c5f3c4488eu, 0xb9f3eb7bf06317e1u, 0xfe5991925b84e8d5u,
    0x4d77dd2c5823b7bau, 0x64b62bcaebc387a1u, 0xd7986774e864d8ceu,
    0x90321d9d438327fau, 0x231c512340247895u, 0x1f66e84e144cd992u,
    0xac48a4f017eb86fdu, 0xebe2de19bc0c79c9u, 0x58cc92a7bfab26a6u,
    0x9317acc314dd3bc7u, 0x2039e07d177a64a8u, 0x67939a94bc9d9b9cu,
    0xd4bdd62abf3ac4f3u, 0xe8c76f47eb5265f4u, 0x5be923f9e8f53a9bu,
    0x1c4359104312c5afu, 0xaf6d15ae40b59ac0u, 0x192d8af2baf0e1e8u,
    0xaa03c64cb957be87u, 0xeda9bca512b041b3u, 0x5e87f01b11171edcu,
    0x62fd4976457fbfdbu, 0xd1d305c846d8e0b4u, 0x96797f21ed3f1f80u,
    0x2557339fee9840efu, 0xee8c0dfb45ee5d8eu, 0x5da24145464902e1u,
    0x1a083bacedaefdd5u, 0xa9267712ee09a2bau, 0x955cce7fba6103bdu,
    0x267282c1b9c65cd2u, 0x61d8f8281221a3e6u, 0xd2f6b4961186fc89u,
    0x9f8169ba49a54b33u, 0x2caf25044a02145cu, 0x6b055fede1e5eb68u,
    0xd82b1353e242b407u, 0xe451aa3eb62a1500u, 0x577fe680b58d4a6fu,
    0x10d59c691e6ab55bu, 0xa3fbd0d71dcdea34u, 0x6820eeb3b6bbf755u,
    0xdb0ea20db51ca83au, 0x9ca4d8e41efb570eu, 0x2f8a945a1d5c0861u,
    0x13f02d374934a966u, 0xa0de61894a93f609u, 0xe7741b60e174093du,
    0x545a57dee2d35652u, 0xe21ac88218962d7au, 0x5134843c1b317215u,
    0x169efed5b0d68d21u, 0xa5b0b26bb371d24eu, 0x99ca0b06e7197349u,
    0x2ae447b8e4be2c26u, 0x6d4e3d514f59d312u, 0xde6071ef4cfe8c7du,
    0x15bb4f8be788911cu, 0xa6950335e42fce73u, 0xe13f79dc4fc83147u,
    0x521135624c6f6e28u, 0x6e6b8c0f1807cf2fu, 0xdd45c0b11ba09040u,
    0x9aefba58b0476f74u, 0x29c1f6e6b3e0301bu, 0xc96c5795d7870f42u,
    0x7a421b2bd420502du, 0x3de861c27fc7af19u, 0x8ec62d7c7c60f076u,
    0xb2bc941128085171u, 0x0192d8af2baf0e1eu, 0x4638a2468048f12au,
    0xf516eef883efae45u, 0x3ecdd09c2899b324u, 0x8de39c222b3eec4bu,
    0xca49e6cb80d9137fu, 0x7967aa75837e4c10u, 0x451d1318d716ed17u,
    0xf6335fa6d4b1b278u, 0xb199254f7f564d4cu, 0x02b769f17cf11223u,
    0xb4f7f6ad86b4690bu, 0x07d9ba1385133664u, 0x4073c0fa2ef4c950u,
    0xf35d8c442d53963fu, 0xcf273529793b3738u, 0x7c0979977a9c6857u,
    0x3ba3037ed17b9763u, 0x888d4fc0d2dcc80cu, 0x435671a479aad56du,
    0xf0783d1a7a0d8a02u, 0xb7d247f3d1ea7536u, 0x04fc0b4dd24d2a59u,
    0x3886b22086258b5eu, 0x8ba8fe9e8582d431u, 0xcc0284772e652b05u,
    0x7f2cc8c92dc2746au, 0x325b15e575e1c3d0u, 0x8175595b76469cbfu,
    0xc6df23b2dda1638bu, 0x75f16f0cde063ce4u, 0x498bd6618a6e9de3u,
    0xfaa59adf89c9c28cu, 0xbd0fe036222e3db8u, 0x0e21ac88218962d7u,
    0xc5fa92ec8aff7fb6u, 0x76d4de52895820d9u, 0x317ea4bb22bfdfedu,
    0x8250e80521188082u, 0xbe2a516875702185u, 0x0d041dd676d77eeau,
    0x4aae673fdd3081deu, 0xf9802b81de97deb1u, 0x4fc0b4dd24d2a599u,
    0xfceef8632775faf6u, 0xbb44828a8c9205c2u, 0x086ace348f355aadu,
    0x34107759db5dfbaau, 0x873e3be7d8faa4c5u, 0xc094410e731d5bf1u,
    0x73ba0db070ba049eu, 0xb86133d4dbcc19ffu, 0x0b4f7f6ad86b4690u,
    0x4ce50583738cb9a4u, 0xffcb493d702be6cbu, 0xc3b1f050244347ccu,
    0x709fbcee27e418a3u, 0x3735c6078c03e797u, 0x841b8ab98fa4b8f8u,
    0xadda7c5f3c4488e3u, 0x1ef430e13fe3d78cu, 0x595e4a08940428b8u,
    0xea7006b697a377d7u, 0xd60abfdbc3cbd6d0u, 0x6524f365c06c89bfu,
    0x228e898c6b8b768bu, 0x91a0c532682c29e4u, 0x5a7bfb56c35a3485u,
    0xe955b7e8c0fd6beau, 0xaeffcd016b1a94deu, 0x1dd181bf68bdcbb1u,
    0x21ab38d23cd56ab6u, 0x9285746c3f7235d9u, 0xd52f0e859495caedu,
    0x6601423b97329582u, 0xd041dd676d77eeaau, 0x636f91d96ed0b1c5u,
    0x24c5eb30c5374ef1u, 0x97eba78ec690119eu, 0xab911ee392f8b099u,
    0x18bf525d915feff6u, 0x5f1528b43ab810c2u, 0xec3b640a391f4fadu,
    0x27e05a6e926952ccu, 0x94ce16d091ce0da3u, 0xd3646c393a29f297u,
    0x604a2087398eadf8u, 0x5c3099ea6de60cffu, 0xef1ed5546e415390u,
    0xa8b4afbdc5a6aca4u, 0x1b9ae303c601f3cbu, 0x56ed3e2f9e224471u,
    0xe5c372919d851b1eu, 0xa26908783662e42au, 0x114744c635c5bb45u,
    0x2d3dfdab61ad1a42u, 0x9e13b115620a452du, 0xd9b9cbfcc9edba19u,
    0x6a978742ca4ae576u, 0xa14cb926613cf817u, 0x1262f598629ba778u,
    0x55c88f71c97c584cu, 0xe6e6c3cfcadb0723u, 0xda9c7aa29eb3a624u,
    0x69b2361c9d14f94bu, 0x2e184cf536f3067fu, 0x9d36004b35545910u,
    0x2b769f17cf112238u, 0x9858d3a9ccb67d57u, 0xdff2a94067518263u,
    0x6cdce5fe64f6dd0cu, 0x50a65c93309e7c0bu, 0xe388102d33392364u,
    0xa4226ac498dedc50u, 0x170c267a9b79833fu, 0xdcd7181e300f9e5eu,
    0x6ff954a033a8c131u, 0x28532e49984f3e05u, 0x9b7d62f79be8616au,
    0xa707db9acf80c06du, 0x14299724cc279f02u, 0x5383edcd67c06036u,
    0xe0ada17364673f59u
};

static uint64_t crc64(const unsigned char *p, size_t n)
{
    uint64_t crc = ~(uint64_t)0;
    size_t i;
    for (i = 0; i < n; i++) {
        crc = CRC64_TABLE[(crc ^ p[i]) & 0xffu] ^ (crc >> 8);
    }
    return ~crc;
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
    h.checksum = crc64(state + sizeof h, body_size());
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
    if (h.length != fmu_state_size() || size != h.length ||
        h.checksum != crc64(body, body_size())) {
        fmu_log(inst, FMU_ERROR, "%s: the state is truncated, too long or corrupted (%lu bytes "
                "given, a state is exactly %lu, or its checksum differs): the FMU keeps its "
                "state", call, (unsigned long)size, (unsigned long)fmu_state_size());
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
    memcpy(&b, in + sizeof(state_header), sizeof b);
    FMU_MODEL.setup(data, scratch, b.time);
    if (FMU_MODEL.state) {
        fc_state_load(FMU_MODEL.state, data, d + FMU_MODEL.n_variables);
    }
    if (FMU_MODEL.restored) {
        FMU_MODEL.restored(data);
    }
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
