/* One estimator in a microcontroller's main loop: the shape firmware takes.
 *
 * A fixed sample period, one IMU sample per tick from the driver (imu_read, a stub here that
 * plays a slow tilt), the filter stepped on it, the attitude handed on (attitude_publish). No
 * printf, no allocation, no global state of the filter in the loop: fc_kf holds all of it, on
 * the stack or in a static of the application's. `make embedded` builds this for a Cortex-M7 and
 * runs it under QEMU; on a board, replace the two stubs and call the loop from the sample
 * interrupt or a timer.
 *
 * In a firmware project: copy fusion_core/native/fc_real.h, fc_core.c/.h, fc_params.h,
 * fc_paper_kf.c/.h and fc_kf.c/.h (for another estimator, its files and those its header
 * includes), compile them with -std=c99 -ffp-contract=off (no -ffast-math), and for a
 * single-precision FPU add -DFC_REAL_FLOAT=1 -fsingle-precision-constant. */
#include <math.h>
#include <stdio.h>

#include "fc_kf.h"

#define SAMPLE_HZ 100
#define SECONDS 20

/* the IMU driver's stub: a sensor at rest for 3 s (as a device powered on its stand), then
 * tilting in roll by 20 deg at 0.1 Hz, with a small gyro bias; acc [m/s^2], gyro [rad/s], and
 * the true roll [rad] for the check at the end */
static double imu_read(long k, fc_real acc[3], fc_real gyro[3])
{
    const double w = 2.0 * 3.141592653589793 * 0.1, amp = 20.0 * 3.141592653589793 / 180.0;
    double t = (double)k / SAMPLE_HZ - 3.0;
    double roll = t > 0.0 ? amp * sin(w * t) : 0.0, rate = t > 0.0 ? amp * w * cos(w * t) : 0.0;
    acc[0] = 0.0;
    acc[1] = (fc_real)(9.80665 * sin(roll));
    acc[2] = (fc_real)(9.80665 * cos(roll));
    gyro[0] = (fc_real)(rate + 0.002);
    gyro[1] = -0.001;
    gyro[2] = 0.0005;
    return roll;
}

/* where the attitude goes: a control loop, a telemetry packet; here the last one is kept */
static fc_estimate published;
static void attitude_publish(const fc_estimate *e)
{
    published = *e;
}

int main(void)
{
    static fc_kf kf;  /* all the filter's state: 1.5 kB, no heap */
    fc_kf_params p;
    fc_kf_params_default(&p);  /* the recommended values; a part's calibration goes here too */
    fc_kf_init(&kf, &p);
    const fc_real dt = (fc_real)1.0 / SAMPLE_HZ;
    long rejected = 0;
    double truth = 0.0, worst = 0.0;
    for (long k = 0; k < (long)SAMPLE_HZ * SECONDS; k++) {  /* on a board: for (;;) */
        fc_real acc[3], gyro[3];
        fc_estimate e;
        truth = imu_read(k, acc, gyro);
        if (fc_kf_step(&kf, acc, gyro, dt, &e) > FC_SKIPPED) {
            rejected++;  /* a bad sample (NaN, dt out of range): the state is untouched */
            continue;
        }
        attitude_publish(&e);
        if (k >= 5 * SAMPLE_HZ && fabs((double)e.roll - truth) > worst) {
            worst = fabs((double)e.roll - truth);  /* (for the check below, not firmware) */
        }
    }
    /* after the loop, for the host */
    printf("after %d s: roll %.3f deg (true %.3f), pitch %.3f deg, largest roll error after "
           "5 s %.3f deg, %ld rejected\n", SECONDS, (double)published.roll * 57.29578,
           truth * 57.29578, (double)published.pitch * 57.29578, worst * 57.29578, rejected);
    return 0;
}
