"""Adding an estimator is one module and one registry row: a toy filter registered in a
temporary registry (fusion_core.registry.register, in a fresh process, before any command
reads the registry) goes through the wiring every estimator goes through, without a line of
the project changed for it."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

TOY = textwrap.dedent('''
    """A toy estimator: roll and pitch from the gyro, pulled towards the accelerometer's tilt."""
    from typing import ClassVar

    from fusion_core.base import NEVER_ESTIMATED, Estimator
    from fusion_core.building_blocks import GYRO_SAMPLING_PARAM
    from fusion_core.kinematics import accel_roll_pitch, euler_step
    from fusion_core.state import ANGLE, HALF_ANGLE
    from fusion_core.types import Estimate, Param

    class ToyFilter(Estimator):
        """roll, pitch += gyro; then a share `gain` of the way to the accelerometer's tilt."""

        PARAMS = (Param("gain", 0.01, "Share of the accelerometer's tilt per sample",
                        low=0.0, high=1.0), GYRO_SAMPLING_PARAM)
        ZERO_BIAS: ClassVar[dict[str, str]] = {
            f"bias_{a}": f"{NEVER_ESTIMATED}: a toy" for a in "xyz"}
        GYRO_ONLY: ClassVar[dict[str, float] | None] = {"gain": 0.0}
        STATE = {"roll": ANGLE, "pitch": HALF_ANGLE}

        def _configure(self):
            self._gain = float(self._params["gain"])

        def _reset(self):
            self.roll = self.pitch = 0.0

        def _init(self, ax, ay, az, gx, gy, gz):
            self.roll, self.pitch = accel_roll_pitch(ax, ay, az)

        def _update(self, ax, ay, az, gx, gy, gz, dt):
            roll, pitch = euler_step(self.roll, self.pitch, gx, gy, gz, dt)
            acc_roll, acc_pitch = accel_roll_pitch(ax, ay, az)
            self.roll = roll + self._gain * (acc_roll - roll)
            self.pitch = pitch + self._gain * (acc_pitch - pitch)

        def _estimate(self):
            return Estimate(self.roll, self.pitch, (0.0, 0.0, 0.0))
''')

SCRIPT = textwrap.dedent('''
    import json, sys
    sys.path.insert(0, sys.argv[1])
    from fusion_core.registry import Bench, Entry, register
    from toy import ToyFilter

    register(Entry("toy", ToyFilter, None, title="toy filter", cites="none",
                   attitude_filter=False, fmu_text="A toy.", paper_row=None,
                   bench=Bench(step_us=10.0, native_us=1.0, vqf_ratio=10.0)))

    # every list of the project takes the toy, imported after the registration
    from fusion_core.presets import load_preset, noise_preset
    from fusion_core.registry import KEYS, create, estimator_class
    from fmu_src.estimator import estimator_variables
    from fmu_src.names import estimator_fmus
    from testbenches import contract
    from testbenches.cli import main
    from testbenches.docs_figures import estimators_table

    got = {}
    got["keys"] = list(KEYS)
    got["paper_class"] = estimator_class("toy", {"filter": "paper"}).__name__
    got["presets"] = [sorted(load_preset(p)) for p in ("recommended", "paper")]
    got["noise"] = sorted(noise_preset(1e-4, 1e-3, 0.05)["toy"])
    got["fmu"] = estimator_fmus().get("ToyFilter")
    got["variables"] = sorted(v.name for v in estimator_variables(ToyFilter))
    got["moderate_bound"] = contract.accuracy_limits("toy", "moderate_dynamics")
    got["static_bound"] = contract.accuracy_limits("toy", "static_level")
    got["table"] = "toy" in estimators_table({})
    out = create("toy").run([[0.0, 0.0, 9.80665]] * 200, [[0.1, 0.0, 0.0]] * 200, 0.01)
    got["roll"] = float(out["roll"][-1])
    got["estimate"] = main(["estimate", sys.argv[2], "--estimator", "toy", "--out",
                            sys.argv[3], "--no-plots"])
    print(json.dumps(got))
''')


def test_a_toy_estimator_in_a_temporary_registry_goes_through_the_wiring(tmp_path: Path) -> None:
    import json

    (tmp_path / "toy.py").write_text(TOY)
    proc = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(tmp_path), str(REPO / "examples" / "tilt_motion.csv"),
         str(tmp_path / "out")], cwd=REPO, capture_output=True, text=True, timeout=300,
        check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    assert got["keys"][-1] == "toy"
    assert got["paper_class"] == "ToyFilter"  # no reference: the paper preset runs the class
    assert all("toy" in p for p in got["presets"])
    assert got["noise"] == ["gyro_range"]  # no noise-derived value of its own
    assert got["fmu"] == "toy"
    assert {"roll", "pitch", "bias_x", "gain", "gyro_sampling", "dt"} <= set(got["variables"])
    assert got["moderate_bound"] is None and got["static_bound"] is not None
    assert got["table"]
    # 0.1 rad/s against a pull of 1 % per sample towards level, 199 steps after the first
    # sample: roll = 0.99 * 0.001 / 0.01 * (1 - 0.99^199)
    assert abs(got["roll"] - 0.099 * (1.0 - 0.99**199)) < 1e-9
    assert got["estimate"] == 0
    assert (tmp_path / "out" / "tilt_motion_toy.csv").is_file()


def test_a_taken_key_fmu_name_or_class_is_refused() -> None:

    from fusion_core.registry import ENTRY, KEYS, register

    with pytest.raises(ValueError, match="key and FMU name and class is already registered"):
        register(ENTRY["cf"])
    assert KEYS.count("cf") == 1  # nothing was added
