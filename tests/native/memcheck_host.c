/* A C host of the twins for memory checkers (tests/test_native.py runs it under valgrind):
 * each twin, recommended and the papers', with its defaults and with other options, over a
 * recording of motion, rest, a near-zero accelerometer stretch, NaN, inf, huge values and bad
 * dt, step by step and in one batch. Exit status 0 when every output is finite. */
#include <math.h>
#include <stdio.h>

#include "fc_cf.h"
#include "fc_kf.h"
#include "fc_mgcf.h"
#include "fc_paper_cf.h"
#include "fc_paper_kf.h"
#include "fc_paper_mgcf.h"
#include "fc_paper_poskf.h"
#include "fc_paper_ukf.h"
#include "fc_plant.h"
#include "fc_poskf.h"
#include "fc_sensor.h"
#include "fc_ukf.h"

#define N 4000

static void sample(int i, double acc[3], double gyro[3], double *dt)
{
    double t = i * 0.01;
    double roll = 0.6 * sin(0.7 * t), pitch = 0.4 * sin(0.45 * t + 0.3);
    acc[0] = -9.80665 * sin(pitch) + 0.3 * sin(13.0 * t);
    acc[1] = 9.80665 * sin(roll) * cos(pitch);
    acc[2] = 9.80665 * cos(roll) * cos(pitch);
    gyro[0] = 0.42 * cos(0.7 * t) + 0.01;
    gyro[1] = 0.18 * cos(0.45 * t + 0.3) - 0.006;
    gyro[2] = 0.2 * sin(0.1 * t);
    *dt = 0.01;
    if (i > 1000 && i < 1200) {  /* at rest */
        acc[0] = acc[1] = 0.0;
        acc[2] = 9.80665;
        gyro[0] = gyro[1] = gyro[2] = 0.003;
    }
    if (i > 1500 && i < 1550) {  /* free fall */
        acc[0] = acc[1] = acc[2] = 0.0;
    }
    switch (i % 97) {
    case 1: acc[0] = NAN; break;
    case 2: gyro[1] = INFINITY; break;
    case 3: *dt = -1.0; break;
    case 4: *dt = 0.0; break;
    case 5: acc[2] = 1e300; break;
    case 6: gyro[2] = 5000.0; break;
    case 7: *dt = 2.0; break;
    default: break;
    }
}

static double acc_all[N][3], gyro_all[N][3], dt_all[N];
static fc_estimate out[N];
static unsigned char rejected[N];

static int finite_estimate(const fc_estimate *e)
{
    return isfinite(e->roll) && isfinite(e->pitch) && isfinite(e->bias[0])
        && isfinite(e->bias[1]) && isfinite(e->bias[2]);
}

int main(void)
{
    int bad = 0;
    for (int i = 0; i < N; i++) {
        sample(i, acc_all[i], gyro_all[i], &dt_all[i]);
    }
    for (int variant = 0; variant < 2; variant++) {
        /* each twin step by step, then reset and in one batch (T_run); SETUP changes the
         * parameters of the second variant */
#define CHECK_TWIN(T, SETUP)                                                              \
        do {                                                                              \
            static T f;  /* a position filter's queue is large: not on the stack */      \
            T##_params p;                                                                 \
            T##_params_default(&p);                                                       \
            if (variant) {                                                                \
                SETUP;                                                                    \
            }                                                                             \
            T##_init(&f, &p);                                                             \
            for (int i = 0; i < N; i++) {                                                 \
                fc_estimate e;                                                            \
                T##_step(&f, acc_all[i], gyro_all[i], dt_all[i], &e);                     \
                bad += !finite_estimate(&e);                                              \
            }                                                                             \
            T##_reset(&f);                                                                \
            T##_run(&f, N, &acc_all[0][0], &gyro_all[0][0], dt_all, out, rejected);       \
            for (int i = 0; i < N; i++) {                                                 \
                bad += !finite_estimate(&out[i]);                                         \
            }                                                                             \
        } while (0)
        CHECK_TWIN(fc_cf, p.gyro_sampling = FC_CF_GYRO_SAMPLING_MEAN);
        CHECK_TWIN(fc_kf, p.acc_lowpass = 0.0);
        CHECK_TWIN(fc_mgcf, p.gyro_sampling = FC_MGCF_GYRO_SAMPLING_MEAN);
        /* a negative central weight: the general solve */
        CHECK_TWIN(fc_ukf, (p.alpha = 0.3, p.beta = 0.0));
        CHECK_TWIN(fc_poskf, p.zupt_window = 0.0);
        CHECK_TWIN(fc_paper_cf, p.gyro_sampling = FC_PAPER_CF_GYRO_SAMPLING_POINT);
        CHECK_TWIN(fc_paper_kf, p.R_loop_time = 0.0);
        CHECK_TWIN(fc_paper_mgcf, p.schedule = FC_PAPER_MGCF_SCHEDULE_FIXED);
        CHECK_TWIN(fc_paper_ukf, (p.alpha = 0.3, p.beta = 0.0, p.norm_noise = 0.0));
        CHECK_TWIN(fc_paper_poskf, p.qr_form = FC_PAPER_POSKF_QR_FORM_PIECEWISE_JERK);
#undef CHECK_TWIN
    }
    /* the sensor model: every parameter set's samples finite, saturated and quantised */
    static double s_acc[N][3], s_gyro[N][3], s_dt[N], s_bias[N][3];
    for (int variant = 0; variant < 2; variant++) {
        fc_sensor sensor;
        fc_sensor_params sp;
        fc_sensor_params_default(&sp);
        if (variant) {
            sp.gyro_sampling = FC_SENSOR_GYRO_SAMPLING_MEAN;
            sp.dlpf_cfg = 4;
            sp.jitter = 0.001;
            sp.calibration = FC_SENSOR_CALIBRATION_NONE;
        }
        fc_sensor_init(&sensor, &sp);
        for (int i = 0; i < N; i++) {
            dt_all[i] = 0.01;
        }
        fc_sensor_run(&sensor, N, &gyro_all[0][0], &acc_all[0][0], dt_all, &s_acc[0][0],
                      &s_gyro[0][0], s_dt, &s_bias[0][0]);
        for (int i = 0; i < N; i++) {
            for (int j = 0; j < 3; j++) {
                bad += !isfinite(s_acc[i][j]) || !isfinite(s_gyro[i][j]) || !isfinite(s_bias[i][j]);
            }
        }
    }
    /* the plant: every scenario's truth, past its end too */
    for (int id = 0; id < 9; id++) {
        double truth[FC_TRUTH_SIZE];
        for (int i = 0; i < 1000; i++) {
            bad += fc_plant_truth(id, i * 0.1, truth) != 0;
            for (int j = 0; j < FC_TRUTH_SIZE; j++) {
                bad += !isfinite(truth[j]);
            }
        }
    }
    printf("non-finite estimates: %d\n", bad);
    return bad != 0;
}
