/* fc_paper_kf.h: the papers' two-state [angle, bias] Kalman filter for roll and for pitch
 * (fusion_core/papers/kalman.py, PaperKalmanFilter), the C twin. Gui et al. 2015 eq. 5-26, Das &
 * Mary eq. 16-27. Its equations are public: the recommended filter (fc_kf.c) is built on them. */
#ifndef FC_PAPER_KF_H
#define FC_PAPER_KF_H

#include "fc_core.h"
#include "fc_params.h"

typedef struct fc_paper_kf {
    fc_paper_kf_params params;
    fc_base base;
    /* PaperKalmanFilter.STATE */
    double roll, pitch, bias_x, bias_y;
    double P_roll[4], P_pitch[4];  /* [P00, P01, P10, P11] of each axis */
    double gain_roll[2], gain_pitch[2];  /* the last update's gains (diagnostics) */
    fc_estimate last;
    double r_step;  /* this step's measurement variance (R_loop_time) */
    /* derived from params (PaperKalmanFilter._configure) */
    double q_angle, q_bias, r, r_loop, gate_low2, gate_high2;
    int trapezoid;
} fc_paper_kf;

void fc_paper_kf_init(fc_paper_kf *f, const fc_paper_kf_params *params);
void fc_paper_kf_configure(fc_paper_kf *f);
void fc_paper_kf_reset(fc_paper_kf *f);
fc_status fc_paper_kf_step(fc_paper_kf *f, const double acc[3], const double gyro[3], double dt,
                           fc_estimate *out);
long fc_paper_kf_run(fc_paper_kf *f, long n, const double *acc, const double *gyro,
                     const double *dt, fc_estimate *out, unsigned char *rejected);
fc_estimate fc_paper_kf_estimate(const fc_paper_kf *f);
/* After a restore of the state fields (fc_state.h): recompute what follows from them. */
void fc_paper_kf_restored(fc_paper_kf *f);

/* The tilt stage: the steps of one sample, for a filter that drives them (the position filters;
 * PaperKalmanFilter's methods of the same names). */
void fc_paper_kf_propagate(fc_paper_kf *f, const double prev[3], const double g[3], double dt);
int fc_paper_kf_accel_trusted(const fc_paper_kf *f, double norm2);
void fc_paper_kf_correct(fc_paper_kf *f, double ax, double ay, double az);
void fc_paper_kf_correct_innovation(fc_paper_kf *f, double y_roll, double y_pitch);
void fc_paper_kf_correct_bias(fc_paper_kf *f, double z_x, double z_y, double r);
void fc_paper_kf_took_sample(fc_paper_kf *f, const double g[3]);

/* An update's gain rule: K and the new P from P and R (fc_paper_kf_measurement_gain, or the
 * recommended filter's angle-only rule). */
typedef void (*fc_kf_gain_rule)(const double P[4], double r, double K[2], double out[4]);

/* The roll and the pitch filter updated together (papers/kalman.py's RollPitchAxes, shared
 * with the recommended filter, fc_kf.c): their states by pointer. One covariance while
 * P_roll == P_pitch (the same numbers as twice), axis by axis otherwise. */
typedef struct fc_roll_pitch_axes {
    double *roll, *pitch, *bias_x, *bias_y;
    double *P_roll, *P_pitch;         /* [4] each */
    double *gain_roll, *gain_pitch;   /* [2] each */
} fc_roll_pitch_axes;
void fc_roll_pitch_predict_covariances(fc_roll_pitch_axes a, double dt, double q_angle,
                                       double q_bias);
void fc_roll_pitch_update_angles(fc_roll_pitch_axes a, double r, double y_roll, double y_pitch,
                                 fc_kf_gain_rule gain);
void fc_roll_pitch_correct_bias(fc_roll_pitch_axes a, double z_x, double z_y, double r);

/* The equations (papers/kalman.py's functions of the same names): F P F' + Q; the gain and
 * covariance of an angle measurement; a direct bias measurement (P updated in place). */
void fc_paper_kf_predict_covariance(const double P[4], double dt, double q_angle, double q_bias,
                                    double out[4]);
void fc_paper_kf_measurement_gain(const double P[4], double r, double K[2], double out[4]);
void fc_paper_kf_bias_update(double *angle, double *bias, double P[4], double y, double r);

#endif /* FC_PAPER_KF_H */
