/* fc_noise.c: see fc_noise.h; the twin of fusion_core/noise.py. */
#include "fc_noise.h"

#include <math.h>

#define FC_PI_NOISE 3.141592653589793

uint64_t fc_splitmix64(uint64_t x)
{
    uint64_t z = x + UINT64_C(0x9E3779B97F4A7C15);
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

uint64_t fc_stream_key(uint64_t seed, uint64_t stream)
{
    return fc_splitmix64(seed ^ fc_splitmix64(stream));
}

static double uniform(uint64_t u)  /* in (0, 1), never 0 */
{
    return ((double)(u >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

static double normal(uint64_t per_sample, int c)  /* channel c of one sample */
{
    double u1 = uniform(fc_splitmix64(per_sample ^ (uint64_t)(2 * c)));
    double u2 = uniform(fc_splitmix64(per_sample ^ (uint64_t)(2 * c + 1)));
    return sqrt(-2.0 * log(u1)) * cos(2.0 * FC_PI_NOISE * u2);
}

void fc_normals(uint64_t key, uint64_t k, int n, double *out)
{
    uint64_t per_sample = fc_splitmix64(key ^ k);
    for (int c = 0; c < n; c++) {
        out[c] = normal(per_sample, c);
    }
}

void fc_normals_used(uint64_t key, uint64_t k, int n, const unsigned char *used, double *out)
{
    uint64_t per_sample = fc_splitmix64(key ^ k);
    for (int c = 0; c < n; c++) {
        out[c] = used[c] ? normal(per_sample, c) : 0.0;
    }
}
