/* fc_state.h: a twin's state as a flat array of doubles, and the checks a restored one passes.
 *
 * The rule for every struct of the C twin (fc_cf, fc_mgcf, fc_kf, fc_ukf, fc_poskf, fc_sensor):
 * it holds three kinds of field, and only one of them is ever saved.
 *   - params: the parameters as the caller gave them;
 *   - the state: what the samples have made of the filter, listed field by field in the twin's
 *     layout (fc_state_tables.c, generated from the Python class's STATE declaration, the same
 *     names, each with the check of fusion_core/state.py);
 *   - everything T_configure derives from params, and what a step recomputes (caches such as
 *     the sensor DLPF's coefficients for the last interval, diagnostics such as kf's gains,
 *     the last estimate): never saved, derived again after a restore.
 * No field of any kind is a pointer: a table is chosen by an index resolved where it is used.
 *
 * A saved state is the layout's fields as doubles, in the layout's order (fc_state_save): no
 * pointer, no padding, no derived value, the same bytes from any process and any platform with
 * IEEE doubles. A restore starts from T_init(params), which derives everything else, checks every
 * value against its field's check (fc_state_check) and only then takes them (fc_state_load) and
 * lets the twin recompute what follows from them (T_restored).
 */
#ifndef FC_STATE_H
#define FC_STATE_H

#include <stddef.h>

/* What a value may hold (fusion_core.state.KINDS, in that order). */
typedef enum fc_check {
    FC_CHECK_REAL = 0,      /* finite, |x| <= 1e75 (state.STATE_BOUND) */
    FC_CHECK_NONNEG,        /* and >= 0 */
    FC_CHECK_ANGLE,         /* |x| <= pi */
    FC_CHECK_HALF_ANGLE,    /* |x| <= pi/2 */
    FC_CHECK_FLAG,          /* 0 or 1 */
    FC_CHECK_COUNT,         /* an integer in [0, high] (high 0: FC_STATE_COUNT_MAX) */
    FC_CHECK_INDEX,         /* an integer in [0, high) */
    FC_CHECK_UNIT,          /* the field's values a vector of norm 1 within FC_STATE_UNIT_TOL */
    FC_CHECK_COV,           /* a covariance row by row: diagonal >= 0, symmetric to rounding,
                               |P_ij| <= sqrt(P_ii P_jj) (Cauchy-Schwarz, to 1e-3) */
    FC_CHECK_COV_LOWER,     /* its lower triangle, packed row by row */
    FC_CHECK_COV_UPPER      /* its upper triangle, packed row by row */
} fc_check;

/* The C type of a field's values. */
typedef enum fc_ctype { FC_DOUBLE = 0, FC_INT, FC_LONG } fc_ctype;

/* One field of a twin's state: `count` values of `type` at `offset` in the twin's struct. */
typedef struct fc_field {
    const char *name;
    size_t offset;
    int type;       /* fc_ctype */
    int count;
    int check;      /* fc_check */
    double high;    /* FC_CHECK_COUNT: the largest count; FC_CHECK_INDEX: the bound, exclusive */
} fc_field;

/* A twin's state: its fields in order. */
typedef struct fc_layout {
    const char *twin;   /* the twin's prefix: "fc_kf" */
    const fc_field *fields;
    int n_fields;
} fc_layout;

/* One layout by the twin's prefix (NULL for an unknown one): fc_state_tables.c. Each layout by
 * name, FC_<TWIN>_LAYOUT, is declared in fc_state_layouts.h (generated). */
const fc_layout *fc_state_layout(const char *twin);

/* The number of doubles of a saved state. */
long fc_state_size(const fc_layout *layout);
/* The twin's state as doubles (fc_state_size of them). */
void fc_state_save(const fc_layout *layout, const void *twin, double *out);
/* 0 when every value of `in` passes its field's check (and an integer field's value fits its
 * type); else -1 with why (the field, its value and what is allowed) written into why. */
int fc_state_check(const fc_layout *layout, const double *in, char *why, size_t size);
/* Take checked values into the twin's state fields (its other fields are left as they are). */
void fc_state_load(const fc_layout *layout, void *twin, const double *in);

#endif /* FC_STATE_H */
