/* fc_plant.h: the testbench plant (fusion_core/scenarios.py and synthetic.Trajectory), the C
 * twin: the exact truth of a scenario at any time, from its signals (fc_scenarios.h). */
#ifndef FC_PLANT_H
#define FC_PLANT_H

#define FC_TRUTH_SIZE 15  /* synthetic.TRUTH_NAMES */

/* The truth of scenario `id` at time t, in synthetic.TRUTH_NAMES' order: roll, pitch, yaw [rad],
 * omega [rad/s] (3), specific force [m/s^2] (3), position [m] (3), velocity [m/s] (3).
 * Returns 0, or -1 for an unknown scenario. */
int fc_plant_truth(int id, double t, double out[FC_TRUTH_SIZE]);
/* The truth at n times t[i], row i of out [n][FC_TRUTH_SIZE]; 0, or -1 for an unknown scenario. */
int fc_plant_run(int id, long n, const double *t, double *out);

#endif /* FC_PLANT_H */
