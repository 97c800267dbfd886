/* fmu_model.h: what the FMI plumbing (fmi2Functions.c, fmi3Functions.c) needs of a model, and
 * the instance layer both standards share (fmu_instance.c).
 *
 * A model is plain C behind this interface, as in the Modelica Association's Reference-FMUs: a
 * table of variables indexed by value reference (generated into the model's config.h from the
 * same variable table as the pythonfmu FMUs), the size of its data (a plain struct without
 * pointers), the layout of its state (fc_state.h) and four functions. Every variable's value
 * lives in one array of doubles indexed by value reference (Real, Integer, Boolean and
 * Enumeration values all fit a double exactly); the plumbing checks every call against the FMI
 * state machine, the variables' causality, variability and range, and only then calls the model.
 *
 * An FMU state holds values only: the FMI state, the time, every variable's value and the model
 * data's state fields as doubles (its layout), never the data's bytes. So it holds no pointer
 * and no value derived from the parameters, and bytes written by one process (or platform)
 * restore in another. A restore checks everything before the instance takes anything: the
 * header and checksum, the FMI state, every value against its variable (a parameter in its
 * range, an output finite, an Integer whole), every state field against its check; then it sets
 * the model up from the restored parameters (which derives everything else), takes the state
 * fields and lets the model recompute what follows from them.
 *
 * No global mutable state: everything lives in the instance.
 */
#ifndef FMU_MODEL_H
#define FMU_MODEL_H

#include <stddef.h>
#include <stdint.h>

#include "fc_state.h"

typedef enum fmu_type { FMU_REAL, FMU_INTEGER, FMU_BOOLEAN, FMU_ENUMERATION } fmu_type;
typedef enum fmu_causality { FMU_PARAMETER, FMU_INPUT, FMU_OUTPUT } fmu_causality;

typedef struct fmu_variable {
    const char *name;
    fmu_type type;
    fmu_causality causality;
    int tunable;            /* a parameter a running FMU accepts */
    double start;
    double low, high;       /* allowed range (-HUGE_VAL / HUGE_VAL: unbounded; an Enumeration:
                               1..number of items) */
    int low_open, high_open;
} fmu_variable;

typedef struct fmu_model {
    const char *name;               /* model identifier */
    const char *token;              /* FMI 2.0 guid, FMI 3.0 instantiationToken */
    const fmu_variable *variables;  /* by value reference 0 .. n_variables - 1 */
    unsigned n_variables;
    size_t data_size;               /* bytes of the model's data */
    /* The fields of the data that make up its state (offsets from the data's start; NULL: none,
     * the data is all derived from the parameters). Only these are saved. */
    const fc_layout *state;
    /* A model built from the parameter values for a start at time t: at instantiation and
     * reset, whenever the start time or a parameter changes before step mode (so outputs read
     * in initialization mode or right after it follow the parameters), at
     * exitInitializationMode and on a restore. It may write output values: the plant writes
     * its truth at t, so a master that passes outputs on before the first step (Jacobi) passes
     * the truth, not a start value (their start values stay otherwise). */
    void (*setup)(void *data, double *values, double t);
    /* A tunable parameter changed in a running model (values holds the new value). */
    void (*tune)(void *data, const double *values);
    /* One communication step [t, t+h] with the inputs in values; writes the outputs into values.
     * Returns 0, or 1 when the step's sample was rejected (message says why, for the log). */
    int (*step)(void *data, double *values, double t, double h, char *message, size_t size);
    /* After a restore took the state fields: recompute what follows from them (NULL: nothing). */
    void (*restored)(void *data);
} fmu_model;

extern const fmu_model FMU_MODEL;  /* the one model of this FMU (the model's .c file) */

/* ----- the instance layer: state machine, values, checks, FMU state ------------------------ */

/* The FMI states both standards share (a bit each, so a call names the states it allows). */
enum {
    FMU_INSTANTIATED = 1 << 0,
    FMU_CONFIGURATION = 1 << 1,     /* FMI 3.0 configuration mode */
    FMU_INITIALIZATION = 1 << 2,
    FMU_STEP = 1 << 3,              /* FMI 2.0 stepComplete, FMI 3.0 step mode */
    FMU_TERMINATED = 1 << 4
};
#define FMU_ANY_STATE (FMU_INSTANTIATED | FMU_CONFIGURATION | FMU_INITIALIZATION | FMU_STEP | \
                       FMU_TERMINATED)

/* Status codes: the values of fmi2Status and fmi3Status alike. */
enum { FMU_OK = 0, FMU_WARNING = 1, FMU_DISCARD = 2, FMU_ERROR = 3, FMU_FATAL = 4 };

struct fmu_instance;
/* How a standard's layer passes a log line to the host's callback. */
typedef void (*fmu_emit)(const struct fmu_instance *inst, int status, const char *category,
                         const char *message);

typedef struct fmu_instance {
    char *name;
    int state;
    int logging_on;
    fmu_emit emit;
    const void *callbacks;          /* FMI 2.0: the host's callback functions */
    void (*log_message)(void);      /* FMI 3.0: the host's log callback */
    void *environment;              /* the host's instance environment */
    double time;
    int time_vr;                    /* FMI 3.0: the value reference of the independent variable
                                       `time` (FMU_MODEL.n_variables), -1 where there is none */
    double *values;                 /* by value reference */
    void *data;                     /* the model's data (FMU_MODEL.data_size bytes) */
} fmu_instance;

fmu_instance *fmu_instance_new(const char *name, fmu_emit emit, const void *callbacks,
                               void (*log_message)(void), void *environment, int logging_on);
void fmu_instance_free(fmu_instance *inst);
/* Values back to their start values, the model set up from them, state INSTANTIATED. */
void fmu_instance_reset(fmu_instance *inst);
/* The model set up anew from the values at the instance's time (fmu_model.setup). */
void fmu_instance_setup(fmu_instance *inst);

/* Log a line: errors always (when the host gave a logger), the rest while logging is on. */
void fmu_log(const fmu_instance *inst, int status, const char *format, ...);
const char *fmu_state_name(int state);
/* FMU_OK if inst is in one of the states `allowed`, else FMU_ERROR with a log line naming the
 * call and the state. */
int fmu_allow(const fmu_instance *inst, int allowed, const char *call);
/* The variable of a value reference, or NULL with a log line (call names the FMI function). */
const fmu_variable *fmu_variable_of(const fmu_instance *inst, const char *call, uint32_t vr,
                                    int types);
#define FMU_TYPE_BIT(t) (1 << (t))

/* Getters and setters for every standard: nvr value references of the types `types` (a mask of
 * FMU_TYPE_BIT); a set is checked whole (causality, variability in this state, range) before
 * any value is taken, so a refused call changes nothing. */
int fmu_get(const fmu_instance *inst, const char *call, const uint32_t vr[], size_t nvr,
            int types, double out[]);
int fmu_set(fmu_instance *inst, const char *call, const uint32_t vr[], size_t nvr, int types,
            const double in[]);

/* A get or set of a type this FMU has no variables of: FMU_OK for none asked, else FMU_ERROR
 * with a log line naming the first value reference. */
int fmu_no_variables(const fmu_instance *inst, const char *call, const char *type,
                     const uint32_t vr[], size_t nvr);

int fmu_exit_initialization(fmu_instance *inst);
int fmu_do_step(fmu_instance *inst, double t, double h);

/* FMU states: a header (magic, model, format, sizes, checksum) then the instance's FMI state and
 * time, the values and the model data's state fields, all as doubles (see the top). */
size_t fmu_state_size(void);
void fmu_state_write(const fmu_instance *inst, unsigned char *out);
/* The checksum of a state's body written into its header (fmu_state_write does it; a test that
 * alters a state's fields calls it so that the alteration reaches the field checks). */
void fmu_state_seal(unsigned char *state);
/* FMU_OK if `in` is a whole state of this FMU and format whose every value passes its check,
 * else FMU_ERROR with a log line naming what is wrong. */
int fmu_state_check(const fmu_instance *inst, const char *call, const unsigned char *in,
                    size_t size);
/* The instance takes a checked state; FMU_ERROR with a log line (and the instance as it was)
 * when it fails a check. */
int fmu_state_read(fmu_instance *inst, const char *call, const unsigned char *in, size_t size);
/* The FMU-state functions of both standards: get (allocating *state when NULL), size, serialize,
 * deserialize (checked), free. */
int fmu_state_get(const fmu_instance *inst, const char *call, void **state);
int fmu_state_size_of(const fmu_instance *inst, const char *call, size_t *size);
int fmu_state_serialize(const fmu_instance *inst, const char *call, const void *state,
                        void *out, size_t size);
int fmu_state_deserialize(const fmu_instance *inst, const char *call, const void *in,
                          size_t size, void **state);
void fmu_state_free(void **state);

#endif /* FMU_MODEL_H */
