"""ImuSensor FMU: the MEMS IMU error model (fusion_core.sensor) as an FMI 2.0 co-simulation FMU.

Inputs: the plant's true body rates omega_* [rad/s] and specific force f_* [m/s2], set before
doStep(t, h). Outputs after doStep(t, h): the IMU sample of those inputs, acc_* [m/s2], gyro_*
[rad/s] and dt [s], and the gyro's true bias at that sample (true_bias_*, the truth for the
estimators' bias outputs). The parameter inputs_at says when the inputs hold: at t+h (end, a
Gauss-Seidel master: dt is h) or at t (start, a Jacobi master: the inputs are the plant's
outputs of the step before, so the sample covers the step before, and dt is that step's h).
A realistic MPU-6050-class IMU by default (fusion_core.sensor); seeded and reproducible.
"""

from typing import Any

from fmu_src.slave import FmuSlave
from fmu_src.testbench_models import INPUTS_AT, SensorModel
from fmu_src.variables import parameter_variable, real_input, real_output, variable_table
from fusion_core import G
from fusion_core.sensor import SENSOR_PARAMS

_AXIS = {"x": "x (forward)", "y": "y (left)", "z": "z (up)"}


class ImuSensor(FmuSlave):
    """MEMS IMU error model: noise, per-run bias, bias instability and random walk, scale and
    cross-axis errors, digital low-pass filter, saturation, quantisation, jitter."""

    description = (
        "Testbench sensor: a 6-axis MEMS IMU error model, by default a realistic MPU-6050 "
        "(0.005 deg/s/sqrt(Hz), 400 ug/sqrt(Hz), the errors a start-up calibration leaves, bias "
        "instability, gyro scale and cross-axis errors, DLPF, +-2000 deg/s, +-16 g, 16 bit); "
        "seeded. One sample per doStep; gyro_sampling says whether the gyro sample is a point "
        "value or an interval mean."
    )
    VARIABLES = variable_table("ImuSensor", lambda: (
        *(real_input(f"omega_{a}", "rad/s", f"True body angular rate about {_AXIS[a]}",
                     display_unit="deg/s") for a in "xyz"),
        *(real_input(f"f_{a}", "m/s2", f"True specific force along body {_AXIS[a]}",
                     G if a == "z" else 0.0) for a in "xyz"),
        *(real_output(f"acc_{a}", "m/s2", f"Accelerometer sample along body {_AXIS[a]}, taken "
                      "at the end of the last step", G if a == "z" else 0.0) for a in "xyz"),
        *(real_output(f"gyro_{a}", "rad/s", f"Gyro sample about body {_AXIS[a]}, taken at the "
                      "end of the last step", 0.0, "deg/s") for a in "xyz"),
        real_output("dt", "s", "Time since the previous sample as the sensor reports it (the "
                    "step size, plus timestamp jitter if any); 0 before the first step, which "
                    "marks the outputs' start values as no sample (every estimator refuses "
                    "dt <= 0 and counts it), so a master that passes them on before the first "
                    "step (Jacobi) plants no false sample", 0.0),
        *(real_output(f"true_bias_{a}", "rad/s", f"The gyro's true total bias about {_AXIS[a]} "
                      "at the last sample (truth for the estimators' bias outputs)", 0.0,
                      "deg/s") for a in "xyz"),
        real_output("last_step", "s", "The communication step size h of the last doStep (0 "
                    "before the first): with inputs_at = start, the interval the next sample "
                    "covers"),
        *(parameter_variable(p) for p in SENSOR_PARAMS),
        INPUTS_AT,
    ))

    def create_model(self, params: dict[str, Any]) -> SensorModel:
        return SensorModel(params)
