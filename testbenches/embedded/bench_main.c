/* Every estimator's C twin on a microcontroller, against the desktop build's outputs
 * (testbenches.embedded). The recordings and the desktop's estimates are compiled in
 * (bench_data.h, generated); each estimator runs over each recording with its recommended
 * parameters, timed by SysTick on QEMU's instruction clock, and its outputs are compared with
 * the desktop's. The libm functions the twins call are compared with glibc's on tables of
 * arguments, so that a difference can be traced to the function that gives it. One line per
 * result on the semihosting console, parsed by the host. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "bench_data.h" /* with every twin's header and BENCH_RUN_ALL, from the registry */

void bench_ticks_start(void);
uint64_t bench_ticks(void);

static fc_estimate out[BENCH_N];
static unsigned char rejected[BENCH_N];

/* ticks for a loop of exactly 4 * n instructions: the instructions per tick of this board */
static uint64_t calibration_ticks(uint32_t n)
{
    uint64_t t0 = bench_ticks();
    __asm volatile("1: nop\n nop\n subs %0, %0, #1\n bne 1b" : "+r"(n) : : "cc");
    return bench_ticks() - t0;
}

static double field(const fc_estimate *e, int k)
{
    switch (k) {
    case 0: return (double)e->roll;
    case 1: return (double)e->pitch;
    case 2: case 3: case 4: return (double)e->bias[k - 2];
    case 5: case 6: case 7: return (double)e->pos[k - 5];
    default: return (double)e->vel[k - 8];
    }
}

/* the largest difference from the desktop per output group (roll, pitch, bias, pos, vel), the
 * samples that differ at all, and the first of them */
static void compare(int rec, int est, const char *name, uint64_t ticks, unsigned size)
{
    double worst[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
    long differ = 0, first = -1;
    static const int group[11] = {0, 1, 2, 2, 2, 3, 3, 3, 4, 4, 4};
    for (long i = 0; i < BENCH_N; i++) {
        int same = 1;
        for (int k = 0; k < 11; k++) {
            double want = bench_expected[rec][est][i][k];
            double got = field(&out[i], k);
            double d = fabs(got - want);
            if (!(got == want) && !(isnan(got) && isnan(want))) {
                same = 0;
                if (!(d <= worst[group[k]])) {
                    worst[group[k]] = d;
                }
            }
        }
        if (!same) {
            differ++;
            if (first < 0) {
                first = i;
            }
        }
    }
    printf("RESULT %s %s %lu %u %.6e %.6e %.6e %.6e %.6e %ld %ld\n", bench_recordings[rec],
           name, (unsigned long)ticks, size, worst[0], worst[1], worst[2], worst[3], worst[4],
           differ, first);
}

#define RUN(T, NAME, EST)                                                                    \
    do {                                                                                     \
        T f;                                                                                 \
        T##_params p;                                                                        \
        T##_params_default(&p);                                                              \
        T##_init(&f, &p);                                                                    \
        uint64_t t0 = bench_ticks();                                                         \
        T##_run(&f, BENCH_N, &bench_acc[rec][0][0], &bench_gyro[rec][0][0], bench_dt[rec],   \
                out, rejected);                                                              \
        uint64_t t1 = bench_ticks();                                                         \
        compare(rec, EST, NAME, t1 - t0, (unsigned)sizeof(T));                               \
    } while (0)

static double call(int fn, double x, double y)
{
    switch (fn) {
    case 0: return sin(x);
    case 1: return cos(x);
    case 2: return tan(x);
    case 3: return asin(x);
    case 4: return atan2(x, y);
    case 5: return exp(x);
    case 6: return log(x);
    case 7: return pow(x, y);
    case 8: return hypot(x, y);
    case 9: return sqrt(x);
    default: return atan(x);
    }
}

int main(void)
{
    bench_ticks_start();
    printf("CAL %lu %lu\n", (unsigned long)calibration_ticks(1000000u), 4000000ul);
    for (int rec = 0; rec < BENCH_RECORDINGS; rec++) {
        BENCH_RUN_ALL();
    }
#if !(defined(FC_REAL_FLOAT) && FC_REAL_FLOAT) /* the float build calls the float functions */
    for (int fn = 0; fn < BENCH_LIBM_FUNCTIONS; fn++) {
        long differ = 0;
        double worst_ulp = 0.0;
        for (int i = 0; i < BENCH_LIBM_N; i++) {
            double want = bench_libm[fn][i][2];
            double got = call(fn, bench_libm[fn][i][0], bench_libm[fn][i][1]);
            if (!(got == want)) {
                double ulp = fabs(got - want) / (nextafter(fabs(want), INFINITY) - fabs(want));
                differ++;
                if (ulp > worst_ulp) {
                    worst_ulp = ulp;
                }
            }
        }
        printf("LIBM %s %ld %d %.3g\n", bench_libm_names[fn], differ, BENCH_LIBM_N, worst_ulp);
    }
#endif
    printf("DONE\n");
    return 0;
}
