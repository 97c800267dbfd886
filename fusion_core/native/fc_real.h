/* fc_real: the twins' real type, chosen when they are compiled.
 *
 * double by default: the Python reference's floats, so that the twins agree with it bit for bit.
 * With FC_REAL_FLOAT defined to 1, float, for a microcontroller whose FPU is single precision
 * (a Cortex-M4F): every variable and parameter is a float, each libm call the float one (fc_sin
 * is sinf), and the build adds -fsingle-precision-constant so that a literal does not pull an
 * expression into double (testbenches.embedded measures what float costs in accuracy). The
 * twins call libm through these names only.
 */
#ifndef FC_REAL_H
#define FC_REAL_H

#include <math.h>

#if defined(FC_REAL_FLOAT) && FC_REAL_FLOAT
typedef float fc_real;
#define fc_sin sinf
#define fc_cos cosf
#define fc_tan tanf
#define fc_asin asinf
#define fc_atan atanf
#define fc_atan2 atan2f
#define fc_sqrt sqrtf
#define fc_hypot hypotf
#define fc_exp expf
#define fc_log logf
#define fc_pow powf
#define fc_fabs fabsf
#define fc_floor floorf
#define fc_copysign copysignf
#define fc_nearbyint nearbyintf
#define fc_remainder remainderf
#else
typedef double fc_real;
#define fc_sin sin
#define fc_cos cos
#define fc_tan tan
#define fc_asin asin
#define fc_atan atan
#define fc_atan2 atan2
#define fc_sqrt sqrt
#define fc_hypot hypot
#define fc_exp exp
#define fc_log log
#define fc_pow pow
#define fc_fabs fabs
#define fc_floor floor
#define fc_copysign copysign
#define fc_nearbyint nearbyint
#define fc_remainder remainder
#endif

#endif /* FC_REAL_H */
