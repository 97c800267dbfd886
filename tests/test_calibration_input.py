"""The calibration at every estimator's input (fusion_core.calibration): what it computes, that
it comes before the mounting, its refusals, and its file."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import KEYS, make

from fusion_core import registry
from fusion_core.calibration import (
    CALIBRATION_PARAMS,
    MAX_CONDITION,
    Calibration,
    condition_number,
)

PART = Calibration(
    acc_matrix=(1.023, 0.004, -0.002, 0.003, 0.981, 0.006, -0.005, 0.002, 1.012),
    acc_offset=(0.12, -0.07, 0.21),
    gyro_matrix=(1.028, 0.003, 0.001, -0.004, 0.982, 0.002, 0.002, -0.003, 1.004),
    gyro_offset=(0.011, -0.018, 0.006),
)


def recording(n: int = 800, seed: int = 2) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    acc = np.array([0.4, -0.3, 9.7]) + 0.2 * rng.standard_normal((n, 3))
    gyro = 0.2 * rng.standard_normal((n, 3))
    return acc, gyro, np.full(n, 0.01)


@pytest.mark.parametrize("filter_", ["recommended", "paper"])
@pytest.mark.parametrize("key", KEYS)
def test_a_calibrated_filter_sees_what_a_plain_one_sees_of_calibrated_samples(
        key: str, filter_: str) -> None:
    """The parameters do what Calibration.apply does to the arrays (up to the rounding of the
    two orders of operations: the filter's outputs agree to 1e-9 rad)."""
    acc, gyro, dt = recording()
    pre = {"filter": "paper"} if filter_ == "paper" else {}
    cal_acc, cal_gyro = PART.apply(acc, gyro)
    inside = registry.create(key, {**pre, **PART.params()}).run(acc, gyro, dt, backend="python")
    outside = registry.create(key, pre).run(cal_acc, cal_gyro, dt, backend="python")
    for name in ("roll", "pitch", "bias"):
        assert np.max(np.abs(inside[name] - outside[name])) < 1e-9, name
    plain = registry.create(key, pre).run(acc, gyro, dt, backend="python")
    assert np.max(np.abs(plain["roll"] - inside["roll"])) > 1e-3  # it changed something


def test_the_calibration_comes_before_the_mounting() -> None:
    acc, gyro, dt = recording()
    mount = {"mount_yaw": 0.7, "mount_roll": 0.2}
    mounted = make("kf", **mount, **PART.params()).run(acc, gyro, dt, backend="python")
    cal_acc, cal_gyro = PART.apply(acc, gyro)
    expected = make("kf", **mount).run(cal_acc, cal_gyro, dt, backend="python")
    assert np.max(np.abs(mounted["roll"] - expected["roll"])) < 1e-9


def test_the_default_is_no_calibration_and_every_estimator_has_it() -> None:
    for key in KEYS:
        for filter_ in ({}, {"filter": "paper"}):
            specs = registry.estimator_class(key, filter_).param_specs()
            for p in CALIBRATION_PARAMS:
                assert specs[p.name] == p
    assert Calibration().params() == {p.name: p.default for p in CALIBRATION_PARAMS}
    assert Calibration.from_params(PART.params()) == PART


def test_a_bad_matrix_is_refused_naming_the_entry_or_the_matrix_and_the_bound() -> None:
    with pytest.raises(ValueError, match=r"'gyro_cal_zz'=0.0 is out of range: allowed "
                                         r"\[0.8, 1.25\]"):
        make("ukf", gyro_cal_zz=0.0)
    with pytest.raises(ValueError, match=r"'acc_cal_xy'=nan is out of range"):
        make("kf", acc_cal_xy=math.nan)
    with pytest.raises(ValueError, match=r"acc_cal_yy=nan is not finite"):
        Calibration(acc_matrix=(1.0, 0, 0, 0, math.nan, 0, 0, 0, 1.0))
    with pytest.raises(ValueError, match=r"entry gyro_cal_xy=0.5 is out of range: allowed "
                                         r"\[-0.2, 0.2\]"):
        Calibration(gyro_matrix=(1.0, 0.5, 0, 0, 1.0, 0, 0, 0, 1.0))
    with pytest.raises(ValueError, match="fixed after construction"):
        make("kf").set_param("gyro_cal_xx", 1.01)


def test_no_matrix_the_ranges_allow_is_singular_or_badly_conditioned() -> None:
    """All 512 corners of the entries' box (diagonal 0.8 or 1.25, off it +-0.2) and 2000
    matrices inside it."""
    import itertools
    import random

    corners = [(d[0], o[0], o[1], o[2], d[1], o[3], o[4], o[5], d[2])
               for d in itertools.product((0.8, 1.25), repeat=3)
               for o in itertools.product((-0.2, 0.2), repeat=6)]
    rng = random.Random(1)
    inside = [tuple(rng.uniform(0.8, 1.25) if i in (0, 4, 8) else rng.uniform(-0.2, 0.2)
                    for i in range(9)) for _ in range(2000)]
    assert max(condition_number(m) for m in corners + inside) < MAX_CONDITION


def test_the_file_round_trips_and_says_what_is_wrong(tmp_path) -> None:
    path = tmp_path / "calibration.json"
    PART.write(path)
    doc = json.loads(path.read_text())
    assert doc["acc_cal"]["matrix"][1] == [0.003, 0.981, 0.006]
    assert Calibration.read(path) == PART
    doc["gyro_cal"]["offset"] = [0.0, 0.0]
    path.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="gyro_cal must hold a 3x3 matrix and 3 offsets"):
        Calibration.read(path)
    path.write_text(json.dumps({"acc_cal": {"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 0]],
                                            "offset": [0, 0, 0]}}))
    with pytest.raises(ValueError, match=r"calibration.json: calibration acc_cal: entry "
                                         r"acc_cal_zz=0.0 is out of range"):
        Calibration.read(path)


@pytest.mark.parametrize(("doc", "says"), [
    ({"acc_cal": {"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "offset": [0, 0, 0]},
      "gyro_call": {}}, "unknown entry 'gyro_call': a calibration file holds acc_cal and "
     "gyro_cal"),
    ({"acc_cal": {"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}},
     "acc_cal must be {\"matrix\": 3x3 numbers, \"offset\": 3 numbers} and nothing else; it "
     "holds 'matrix'"),
    ({"gyro_cal": {"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "offset": [0, 0, 0],
                   "scale": 2}}, "it holds 'matrix', 'offset', 'scale'"),
    ({"gyro_cal": {"matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "offset": [0.3, 0, 0]},
      "units": {"acc": "m/s2", "gyro": "deg/s"}}, "the file's offsets are in m/s2 (acc) and "
     "rad/s (gyro)"),
])
def test_a_calibration_file_is_checked_against_its_schema(tmp_path, doc, says) -> None:
    """A misspelt entry, a missing or extra key, offsets in another unit: each refused by
    name, never read as no calibration."""
    path = tmp_path / "calibration.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ValueError) as err:
        Calibration.read(path)
    assert says in str(err.value)
