/* fc_kf.h: the recommended two-state [angle, bias] Kalman filter for roll and for pitch
 * (fusion_core/kalman.py, AngleBiasKalmanFilter), the C twin. Gui et al. 2015 eq. 5-26, Das &
 * Mary eq. 16-27 (fc_paper_kf.h) with the mechanisms for real sensors of the Python class's
 * docstring. */
#ifndef FC_KF_H
#define FC_KF_H

#include "fc_core.h"
#include "fc_params.h"

typedef struct fc_kf {
    fc_kf_params params;
    fc_base base;
    /* AngleBiasKalmanFilter.STATE */
    double roll, pitch, bias_x, bias_y;
    double P_roll[4], P_pitch[4];   /* [P00, P01, P10, P11] of each axis */
    double bias_z, P_z;
    double meas[FC_MEAS_SIZE];  /* the measured vector (acc_lowpass > 0; measured_vector) */
    double rest[8];
    double q_att[4];
    int face;
    double gain_roll[2], gain_pitch[2];  /* the last update's gains (diagnostics) */
    fc_estimate last;
    double r_step;  /* this step's measurement variance (the measured vector's noise) */
    double q_step;  /* this step's angle process noise (propagate) */
    /* derived from params (AngleBiasKalmanFilter._configure) */
    double q_angle, q_bias, r, gate_low2, gate_high2, acc_tau;
    double q_rotation, dist_tau;  /* AngleBiasKalmanFilter._adaptive */
    fc_meas_constants measure;  /* AngleBiasKalmanFilter._measure */
    double longest2, rail_var;
    double rest_time, rest_gyro, rest_acc, gyro_var, rest_bias_bound;
    double bias_lo2, bias_hi2;
    int trapezoid;
} fc_kf;

void fc_kf_init(fc_kf *f, const fc_kf_params *params);
void fc_kf_configure(fc_kf *f);
void fc_kf_reset(fc_kf *f);
fc_status fc_kf_step(fc_kf *f, const double acc[3], const double gyro[3], double dt,
                     fc_estimate *out);
long fc_kf_run(fc_kf *f, long n, const double *acc, const double *gyro, const double *dt,
               fc_estimate *out, unsigned char *rejected);
fc_estimate fc_kf_estimate(const fc_kf *f);
/* After a restore of the state fields (fc_state.h): recompute what follows from them. */
void fc_kf_restored(fc_kf *f);

#endif /* FC_KF_H */
