/* Step fusion_core's Kalman filter from C, as firmware would: one IMU sample per call.
 * cc -std=c99 -O2 -ffp-contract=off -Ifusion_core/native examples/embedded_kf.c \
 *    fusion_core/native/fc_core.c fusion_core/native/fc_paper_kf.c fusion_core/native/fc_kf.c \
 *    -lm -o embedded_kf */
#include <math.h>
#include <stdio.h>

#include "fc_kf.h"

int main(void)
{
    fc_kf kf;                    /* all the filter's state: no globals, no malloc */
    fc_kf_params p;
    fc_kf_params_default(&p);    /* the recommended values */
    p.input.gyro_sampling = FC_GYRO_SAMPLING_MEAN;  /* an integrating IMU */
    fc_kf_init(&kf, &p);
    for (int i = 0; i < 500; i++) {              /* 5 s at 100 Hz, tilted 10 deg in roll */
        double acc[3] = {0.0, 9.80665 * sin(0.1745), 9.80665 * cos(0.1745)};
        double gyro[3] = {0.002, -0.001, 0.0};   /* rad/s, a small bias */
        fc_estimate e;
        if (fc_kf_step(&kf, acc, gyro, 0.01, &e) > FC_SKIPPED) {
            continue;            /* rejected (NaN, bad dt, ...): the state is untouched */
        }
        if (i % 100 == 99) {
            printf("t=%.2f s  roll=%.3f deg  pitch=%.3f deg\n", (i + 1) * 0.01,
                   e.roll * 57.29578, e.pitch * 57.29578);
        }
    }
    return 0;
}
