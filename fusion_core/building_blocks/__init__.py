"""Real-sensor building blocks that every estimator shares, beside its paper's own equations.

The seed papers assume a calibrated sensor whose accelerometer measures gravity and whose gyro
sample is a point value. Real MEMS IMUs break each assumption in a known way, and each block
below answers one of them the same way in every estimator:

- sampling: the gyro sampling rule (GYRO_SAMPLING_PARAM): point samples or interval means;
- gate: the accelerometer-magnitude gate (ACC_GATE_PARAMS), skipping the correction when |a| is
  far from g, the gates of the bias learning (BIAS_GATE_PARAM, BIAS_INNOVATION_PARAM) and the
  angle's variance after a gross innovation (GROSS_INNOVATION_PARAM);
- prefilter: the accelerometer pre-filter (ACC_LOWPASS_PARAM, lowpass_specific_force): the
  specific force low-passed in a frame that turns with the gyro, so linear acceleration averages
  out (Laidig & Seel 2023, VQF);
- rest: rest detection for a zero-angular-rate bias update (REST_PARAMS, RestState, rest_step;
  VQF's detector);
- motion_bias: the complementary filters' bias learned in motion until the first rest
  (MOTION_BIAS_PARAM, motion_bias_ki; Mahony et al.'s integral term);
- adaptive_noise: more process noise while the sensor turns (the gyro's scale-factor error),
  more measurement noise while it accelerates (the linear acceleration the pre-filter has not
  removed, fusion_core.measured_vector), the raw sample where it measures none; correction_time
  for the complementary filters;
- attitude: quaternion propagation of the Euler-angle filters (quat_from_roll_pitch), free of the
  pitch +-90 deg singularity of the Euler rates;
- faces: the nearest face (FACES, nearest_face): per-axis tilt filters run in the sensor frame
  turned by the right-angle rotation that brings the axis nearest to up onto z, so that a sensor
  resting on any face is the level case for them.

This package's namespace holds every block's names.

An accelerometer sample whose norm is zero (or that base.Estimator.step took as no reading)
carries no gravity direction: every block below skips it, and so does every correction.
"""

from __future__ import annotations

from .adaptive_noise import (
    ADAPTIVE_NOISE_PARAMS,
    COMPLEMENTARY_ADAPTIVE_PARAMS,
    CONSTANT_NOISE,
    MAX_CORRECTION_TIME_PARAM,
    PREFILTER_FULL,
    RECOMMENDED_GYRO_SCALE_STD,
    RECOMMENDED_SCALE_TIME,
    SLOWEST_CORRECTION,
    adaptive_noise_constants,
    adaptive_prefilter_time,
    complementary_adaptive,
    correction_time,
)
from .attitude import (
    corrected_quat,
    quat_from_roll_pitch,
    tilt_innovation,
)
from .faces import (
    FACE_SWITCH_COS,
    FACES,
    nearest_face,
)
from .gate import (
    ACC_GATE_PARAMS,
    BIAS_GATE,
    BIAS_GATE_PARAM,
    BIAS_INNOVATION,
    BIAS_INNOVATION_PARAM,
    GROSS_INNOVATION,
    GROSS_INNOVATION_PARAM,
    bias_band2,
    gate_bounds2,
)
from .motion_bias import (
    MOTION_BIAS_GAIN,
    MOTION_BIAS_PARAM,
    motion_bias_ki,
)
from .prefilter import (
    ACC_LOWPASS_PARAM,
    lowpass_specific_force,
)
from .rest import (
    REST_MEAN_TAU,
    REST_PARAMS,
    REST_START,
    RestState,
    bias_at_rest,
    complementary_rest,
    first_rest,
    rest_alignment,
    rest_mean_share,
    rest_start,
    rest_step,
    uncalibrated_first_rest,
    zero_rate_psd_param,
    zero_rate_sample,
)
from .sampling import (
    GYRO_SAMPLING_PARAM,
    REAL_GYRO_DENSITY,
    ZERO3,
    Vec3,
    body_rotation,
    on_the_mark,
)

__all__ = [
    "ACC_GATE_PARAMS",
    "ACC_LOWPASS_PARAM",
    "ADAPTIVE_NOISE_PARAMS",
    "BIAS_GATE",
    "BIAS_GATE_PARAM",
    "BIAS_INNOVATION",
    "BIAS_INNOVATION_PARAM",
    "COMPLEMENTARY_ADAPTIVE_PARAMS",
    "CONSTANT_NOISE",
    "FACES",
    "FACE_SWITCH_COS",
    "GROSS_INNOVATION",
    "GROSS_INNOVATION_PARAM",
    "GYRO_SAMPLING_PARAM",
    "MAX_CORRECTION_TIME_PARAM",
    "MOTION_BIAS_GAIN",
    "MOTION_BIAS_PARAM",
    "PREFILTER_FULL",
    "REAL_GYRO_DENSITY",
    "RECOMMENDED_GYRO_SCALE_STD",
    "RECOMMENDED_SCALE_TIME",
    "REST_MEAN_TAU",
    "REST_PARAMS",
    "REST_START",
    "SLOWEST_CORRECTION",
    "ZERO3",
    "RestState",
    "Vec3",
    "adaptive_noise_constants",
    "adaptive_prefilter_time",
    "bias_at_rest",
    "bias_band2",
    "body_rotation",
    "complementary_adaptive",
    "complementary_rest",
    "corrected_quat",
    "correction_time",
    "first_rest",
    "gate_bounds2",
    "lowpass_specific_force",
    "motion_bias_ki",
    "nearest_face",
    "on_the_mark",
    "quat_from_roll_pitch",
    "rest_alignment",
    "rest_mean_share",
    "rest_start",
    "rest_step",
    "tilt_innovation",
    "uncalibrated_first_rest",
    "zero_rate_psd_param",
    "zero_rate_sample",
]
