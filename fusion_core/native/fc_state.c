/* fc_state.c: see fc_state.h; the checks are fusion_core/state.py's, value for value. */
#include "fc_state.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define FC_STATE_BOUND 1e75              /* state.STATE_BOUND */
#define FC_STATE_UNIT_TOL 1e-6           /* state.UNIT_TOLERANCE */
#define FC_STATE_SYMMETRY_TOL 1e-9       /* state.SYMMETRY_TOLERANCE */
#define FC_STATE_CORRELATION_TOL 1e-3    /* state.CORRELATION_TOLERANCE */
#define FC_STATE_COUNT_MAX 9007199254740992.0  /* state.COUNT_MAX, 2^53 */
#define FC_STATE_PI 3.141592653589793

long fc_state_size(const fc_layout *layout)
{
    long n = 0;
    int i;
    for (i = 0; i < layout->n_fields; i++) {
        n += layout->fields[i].count;
    }
    return n;
}

void fc_state_save(const fc_layout *layout, const void *twin, double *out)
{
    const unsigned char *base = (const unsigned char *)twin;
    int i, j;
    for (i = 0; i < layout->n_fields; i++) {
        const fc_field *f = &layout->fields[i];
        for (j = 0; j < f->count; j++) {
            if (f->type == FC_INT) {
                int v;
                memcpy(&v, base + f->offset + j * sizeof v, sizeof v);
                *out++ = (double)v;
            } else if (f->type == FC_LONG) {
                long v;
                memcpy(&v, base + f->offset + j * sizeof v, sizeof v);
                *out++ = (double)v;
            } else {
                memcpy(out++, base + f->offset + j * sizeof(double), sizeof(double));
            }
        }
    }
}

static const char *allowed(const fc_field *f)
{
    switch (f->check) {
    case FC_CHECK_NONNEG: return "finite, 0 to 1e75";
    case FC_CHECK_ANGLE: return "an angle in [-pi, pi]";
    case FC_CHECK_HALF_ANGLE: return "an angle in [-pi/2, pi/2]";
    case FC_CHECK_FLAG: return "0 or 1";
    case FC_CHECK_COUNT: return "a count";
    case FC_CHECK_INDEX: return "an index into its table";
    default: return "finite, within +-1e75";
    }
}

/* 0 when x passes the field's check of one value, else -1 */
static int check_value(const fc_field *f, double x)
{
    double top;
    if (!isfinite(x) || fabs(x) > FC_STATE_BOUND) {
        return -1;
    }
    /* an integer field's value must fit its type: below TYPE_MAX + 1, which is exact as a double
     * (a 64-bit LONG_MAX rounds to 2^63 already) */
    if (f->type == FC_INT && (x != floor(x) || x < (double)INT_MIN ||
                              x >= (double)INT_MAX + 1.0)) {
        return -1;
    }
    if (f->type == FC_LONG && (x != floor(x) || x < (double)LONG_MIN ||
                               x >= (double)LONG_MAX + 1.0)) {
        return -1;
    }
    switch (f->check) {
    case FC_CHECK_NONNEG: return x >= 0.0 ? 0 : -1;
    case FC_CHECK_ANGLE: return fabs(x) <= FC_STATE_PI ? 0 : -1;
    case FC_CHECK_HALF_ANGLE: return fabs(x) <= 0.5 * FC_STATE_PI ? 0 : -1;
    case FC_CHECK_FLAG: return x == 0.0 || x == 1.0 ? 0 : -1;
    case FC_CHECK_COUNT:
        top = f->high > 0.0 ? f->high : FC_STATE_COUNT_MAX;
        return x >= 0.0 && x == floor(x) && x <= top ? 0 : -1;
    case FC_CHECK_INDEX: return x >= 0.0 && x == floor(x) && x < f->high ? 0 : -1;
    default: return 0;
    }
}

/* The size n of a covariance field (0 when its count fits none up to `most`). */
static int matrix_size(const fc_field *f, int most)
{
    int n;
    for (n = 1; n <= most; n++) {
        if ((f->check == FC_CHECK_COV && n * n == f->count) ||
            (f->check != FC_CHECK_COV && n * (n + 1) / 2 == f->count)) {
            return n;
        }
    }
    return 0;
}

/* Where entry (i, j) of an n x n covariance field is stored (state.element_index): row by row
 * for FC_CHECK_COV; FC_CHECK_COV_LOWER holds row r as (r, 0..r), _UPPER as (r, r..n-1). */
static int element_index(int check, int n, int i, int j)
{
    int r = i < j ? i : j, c = i < j ? j : i;
    if (check == FC_CHECK_COV) {
        return i * n + j;
    }
    if (check == FC_CHECK_COV_LOWER) {
        return c * (c + 1) / 2 + r;
    }
    return r * n - r * (r - 1) / 2 + (c - r);
}

/* 0 when a field's values together pass its check (unit norm; a covariance's diagonal, symmetry
 * and Cauchy-Schwarz), else -1 with why */
static int check_whole(const fc_field *f, const double *x, char *why, size_t size)
{
    int n, i, j, k = f->check;
    if (k == FC_CHECK_UNIT) {
        double s = 0.0;
        for (i = 0; i < f->count; i++) {
            s += x[i] * x[i];
        }
        if (!(fabs(sqrt(s) - 1.0) <= FC_STATE_UNIT_TOL)) {
            snprintf(why, size, "state field %s has norm %.17g: a unit vector is required "
                     "(within 1e-06)", f->name, sqrt(s));
            return -1;
        }
        return 0;
    }
    if (k != FC_CHECK_COV && k != FC_CHECK_COV_LOWER && k != FC_CHECK_COV_UPPER) {
        return 0;
    }
    n = matrix_size(f, 16);
    if (n == 0) {
        snprintf(why, size, "state field %s: %d values are no covariance", f->name, f->count);
        return -1;
    }
    for (i = 0; i < n; i++) {
        double v = x[element_index(k, n, i, i)];
        if (v < 0.0) {
            snprintf(why, size, "state field %s has a negative variance %.17g on its diagonal",
                     f->name, v);
            return -1;
        }
    }
    for (i = 0; i < n; i++) {
        for (j = 0; j < i; j++) {
            double a = x[element_index(k, n, i, j)], b = x[element_index(k, n, j, i)];
            double root = sqrt(x[element_index(k, n, i, i)] * x[element_index(k, n, j, j)]);
            double scale = root;
            scale = fabs(a) > scale ? fabs(a) : scale;
            scale = fabs(b) > scale ? fabs(b) : scale;
            if (fabs(a - b) > FC_STATE_SYMMETRY_TOL * scale) {
                snprintf(why, size, "state field %s is not symmetric (%.17g against %.17g)",
                         f->name, a, b);
                return -1;
            }
            if (fabs(a) > (1.0 + FC_STATE_CORRELATION_TOL) * root) {
                snprintf(why, size, "state field %s is no covariance: its (%d, %d) entry %.17g "
                         "exceeds sqrt of the variances' product %.17g", f->name, i, j, a, root);
                return -1;
            }
        }
    }
    return 0;
}

int fc_state_check(const fc_layout *layout, const double *in, char *why, size_t size)
{
    int i, j;
    for (i = 0; i < layout->n_fields; i++) {
        const fc_field *f = &layout->fields[i];
        for (j = 0; j < f->count; j++) {
            if (check_value(f, in[j]) != 0) {
                if (f->count == 1) {
                    snprintf(why, size, "state field %s = %.17g is not allowed: %s", f->name,
                             in[j], allowed(f));
                } else {
                    snprintf(why, size, "state field %s[%d] = %.17g is not allowed: %s",
                             f->name, j, in[j], allowed(f));
                }
                return -1;
            }
        }
        if (check_whole(f, in, why, size) != 0) {
            return -1;
        }
        in += f->count;
    }
    return 0;
}

void fc_state_load(const fc_layout *layout, void *twin, const double *in)
{
    unsigned char *base = (unsigned char *)twin;
    int i, j;
    for (i = 0; i < layout->n_fields; i++) {
        const fc_field *f = &layout->fields[i];
        for (j = 0; j < f->count; j++) {
            double x = *in++;
            if (f->type == FC_INT) {
                int v = (int)x;
                memcpy(base + f->offset + j * sizeof v, &v, sizeof v);
            } else if (f->type == FC_LONG) {
                long v = (long)x;
                memcpy(base + f->offset + j * sizeof v, &v, sizeof v);
            } else {
                memcpy(base + f->offset + j * sizeof(double), &x, sizeof x);
            }
        }
    }
}
