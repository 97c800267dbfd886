/* fc_plant.c: see fc_plant.h; the twin of the signals of fusion_core/synthetic.py and
 * scenarios.swelling_sine (their SCALAR form) and of Trajectory._evaluate, line by line. */
#include "fc_plant.h"

#include <math.h>

#include "fc_core.h"
#include "fc_scenarios.h"

/* one signal node at time t: value, first and second derivative */
static void signal(int index, double t, double out[3])
{
    const fc_signal_node *n = &FC_NODES[index];
    const double *p = n->p;
    switch (n->kind) {
    case 0: {  /* constant(value) */
        double z = 0.0;
        out[0] = z + p[0];
        out[1] = z;
        out[2] = z;
        return;
    }
    case 1: {  /* sine(amplitude, w, phase, offset) */
        double amplitude = p[0], w = p[1], phase = p[2], offset = p[3];
        double arg = w * t + phase;
        double s = sin(arg), c = cos(arg);
        out[0] = offset + amplitude * s;
        out[1] = amplitude * w * c;
        out[2] = -amplitude * w * w * s;
        return;
    }
    case 2: {  /* add(children): 0 + s1 + s2 + ... from left to right */
        double v = 0.0, dv = 0.0, ddv = 0.0, c[3];
        for (int i = 0; i < n->n_children; i++) {
            signal(FC_CHILDREN[n->first_child + i], t, c);
            v = v + c[0];
            dv = dv + c[1];
            ddv = ddv + c[2];
        }
        out[0] = v;
        out[1] = dv;
        out[2] = ddv;
        return;
    }
    case 3: {  /* min_jerk(start, d, t0, duration) */
        double start = p[0], d = p[1], t0 = p[2], duration = p[3];
        double x = (t - t0) / duration;
        double s = 0.0 > x ? 0.0 : x;  /* min(max(x, 0), 1) */
        s = 1.0 < s ? 1.0 : s;
        int inside = t > t0 && t < t0 + duration;
        out[0] = start + d * (s * s * s * (10.0 + s * (-15.0 + 6.0 * s)));
        out[1] = inside ? d * (s * s * (30.0 + s * (-60.0 + 30.0 * s))) / duration : 0.0;
        out[2] = inside ? d * (s * (60.0 + s * (-180.0 + 120.0 * s))) / pow(duration, 2.0) : 0.0;
        return;
    }
    case 4: {  /* product(u, v) */
        double u[3], v[3];
        signal(FC_CHILDREN[n->first_child], t, u);
        signal(FC_CHILDREN[n->first_child + 1], t, v);
        out[0] = u[0] * v[0];
        out[1] = u[1] * v[0] + u[0] * v[1];
        out[2] = u[2] * v[0] + 2.0 * u[1] * v[1] + u[0] * v[2];
        return;
    }
    default: {  /* 5: swelling_sine(peak, w, we, phase) */
        double peak = p[0], w = p[1], we = p[2], phase = p[3];
        double env = we * t, arg = w * t + phase;
        double ce = cos(env), se = sin(env);
        double e = 0.5 * (1.0 - ce), de = 0.5 * we * se, dde = 0.5 * pow(we, 2.0) * ce;
        double c = cos(arg), s = sin(arg);
        double ds = w * c, dds = -w * w * s;
        out[0] = peak * e * s;
        out[1] = peak * (de * s + e * ds);
        out[2] = peak * (dde * s + 2.0 * de * ds + e * dds);
        return;
    }
    }
}

static const fc_scenario_def *find(int id)
{
    for (int i = 0; i < FC_N_SCENARIOS; i++) {
        if (FC_SCENARIO_DEFS[i].id == id) {
            return &FC_SCENARIO_DEFS[i];
        }
    }
    return 0;
}

int fc_plant_truth(int id, double t, double out[FC_TRUTH_SIZE])  /* Trajectory._evaluate */
{
    const fc_scenario_def *sc = find(id);
    if (!sc) {
        return -1;
    }
    double r[3], q[3], y[3], px[3], py[3], pz[3];
    signal(sc->signal[0], t, r);
    signal(sc->signal[1], t, q);
    signal(sc->signal[2], t, y);
    signal(sc->signal[3], t, px);
    signal(sc->signal[4], t, py);
    signal(sc->signal[5], t, pz);
    double phi = r[0], dphi = r[1], theta = q[0], dtheta = q[1], psi = y[0], dpsi = y[1];
    double sphi = sin(phi), cphi = cos(phi);
    double sth = sin(theta), cth = cos(theta);
    double spsi = sin(psi), cpsi = cos(psi);
    double ax = px[2], ay = py[2], az = pz[2] + FC_G;
    double r00 = cpsi * cth, r01 = spsi * cth, r02 = -sth;
    double r10 = cpsi * sth * sphi - spsi * cphi;
    double r11 = spsi * sth * sphi + cpsi * cphi;
    double r12 = cth * sphi;
    double r20 = cpsi * sth * cphi + spsi * sphi;
    double r21 = spsi * sth * cphi - cpsi * sphi;
    double r22 = cth * cphi;
    const double truth[FC_TRUTH_SIZE] = {
        phi, theta, psi,
        dphi - dpsi * sth,
        dtheta * cphi + dpsi * sphi * cth,
        dpsi * cphi * cth - dtheta * sphi,
        r00 * ax + r01 * ay + r02 * az,
        r10 * ax + r11 * ay + r12 * az,
        r20 * ax + r21 * ay + r22 * az,
        px[0], py[0], pz[0], px[1], py[1], pz[1],
    };
    for (int i = 0; i < FC_TRUTH_SIZE; i++) {
        out[i] = truth[i];
    }
    return 0;
}

int fc_plant_run(int id, long n, const double *t, double *out)
{
    for (long i = 0; i < n; i++) {
        if (fc_plant_truth(id, t[i], out + FC_TRUTH_SIZE * i) != 0) {
            return -1;
        }
    }
    return 0;
}
