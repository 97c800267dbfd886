"""ImuPlant FMU: the true motion of the testbench (fusion_core.scenarios) as an FMI 2.0
co-simulation FMU.

After doStep(t, h) the outputs are the truth at t+h of the scenario chosen by the Integer
parameter `scenario`, and from setupExperiment on until the first step its truth at the start
time (a Jacobi master passes them on before any step): Z-Y-X Euler angles, body rates
consistent with them (inverse Euler-rate kinematics), the specific force R^T (a + g e_z) in the
body frame, position and velocity.
"""

from typing import Any

from fmu_src.slave import FmuSlave
from fmu_src.testbench_models import PlantModel, plant_start
from fmu_src.variables import Variable, real_output, variable_table
from fusion_core.scenarios import SCENARIO_BY_ID, SCENARIOS

_ENUM = ", ".join(f"{s.id} = {s.name} ({s.description})" for s in SCENARIOS.values())
_AXIS = {"x": "x (forward)", "y": "y (left)", "z": "z (up)"}
_OUTPUTS = (
    ("roll", "rad", "deg", "True roll phi (Z-Y-X Euler)"),
    ("pitch", "rad", "deg", "True pitch theta (Z-Y-X Euler)"),
    ("yaw", "rad", "deg", "True yaw psi (Z-Y-X Euler)"),
    *((f"omega_{a}", "rad/s", "deg/s", f"True body angular rate about {_AXIS[a]}") for a in "xyz"),
    *((f"f_{a}", "m/s2", None, f"True specific force along body {_AXIS[a]}") for a in "xyz"),
    *((f"pos_{a}", "m", None, f"True position along world {a} (z up)") for a in "xyz"),
    *((f"vel_{a}", "m/s", None, f"True velocity along world {a}") for a in "xyz"),
)




class ImuPlant(FmuSlave):
    """True IMU motion of the testbench scenarios (fusion_core.scenarios)."""

    description = (
        "Testbench plant: analytic IMU motion with exact truth (Euler angles, body rates from "
        "the Euler-rate kinematics, specific force, position, velocity). Scenarios after the "
        "seed papers: Gui et al. and Duong Quoc et al. (tilt, two-axis, moderate dynamics), "
        "Das & Mary (vibration), Safitri et al. (2 m translation)."
    )
    VARIABLES = variable_table("ImuPlant", lambda: (
        Variable("scenario", "parameter", "Integer", f"Motion: {_ENUM}", 0,
                 variability="fixed", low=min(SCENARIO_BY_ID), high=max(SCENARIO_BY_ID)),
        *(real_output(name, unit, text + "; the value at the end of the last step, and before "
                      "the first step the chosen scenario's value at the start time "
                      "(calculated in initialisation)",
                      plant_start()[name], display, depends_on=("scenario",))
          for name, unit, display, text in _OUTPUTS),
    ))

    def create_model(self, params: dict[str, Any]) -> PlantModel:
        return PlantModel(params)
