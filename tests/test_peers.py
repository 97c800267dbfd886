"""The public filters run beside ours (testbenches.peers) are named apart from the registry's
estimators: a table or a --peers list must never show two different filters under one name."""

from __future__ import annotations

import pytest

from fusion_core.registry import KEYS, REGISTRY
from testbenches.peers import AHEAD_PEERS, PEERS


def test_no_peer_has_an_estimators_name() -> None:
    names = {*PEERS, *AHEAD_PEERS}
    assert not names & set(KEYS)
    assert not {n.replace("-", "_") for n in names} & {e.cls.__name__ for e in REGISTRY}


def test_vqf_on_samples_of_the_rate_at_an_instant_is_half_a_sample_ahead() -> None:
    """VQF integrates each gyro sample over the interval before it: on a part that samples the
    rate at an instant, without noise or errors, its output is half a sample ahead of the
    motion, and turned back by half a sample it is several times closer to the truth, turned
    ahead further off (why the battery turns ours ahead over the part's delay and not VQF's:
    docs/results/battery/index.md)."""
    pytest.importorskip("vqf")
    from fusion_core.sensor import SENSOR_PARAMS
    from testbenches import battery
    from testbenches.broad.metric import (
        gravity_from_quat,
        gravity_from_roll_pitch,
        inclination_rmse_deg,
    )
    from testbenches.peers import _vqf_batch, up_ahead

    perfect = {p.name: 0.0 for p in SENSOR_PARAMS
               if p.name.endswith(("_psd", "_instability", "_std"))}
    perfect.update(calibration="perfect", dlpf_cfg=-1, bits=0)
    rate = 50.0
    classes = {**battery.SENSOR_CLASSES,
               "perfect": battery.SensorClass("perfect", "no errors", rate, perfect)}
    with pytest.MonkeyPatch.context() as m:
        m.setattr(battery, "SENSOR_CLASSES", classes)
        t, truth, sample = battery.part_samples("handheld_fast", "perfect", 0)
    out = _vqf_batch(sample["acc"], sample["gyro"], rate, "the test")
    up, rate_vec = gravity_from_quat(out["quat6D"]), sample["gyro"] - out["bias"]
    true_up = gravity_from_roll_pitch(truth["roll"], truth["pitch"])
    scored = t >= battery.MOTIONS["handheld_fast"].rest + battery.SETTLE_S

    def rmse(shift: float) -> float:  # turned ahead by shift samples
        return inclination_rmse_deg(up_ahead(up, rate_vec, shift / rate), true_up, scored)

    assert rmse(-0.5) < rmse(0.0) / 3.0 and rmse(0.5) > rmse(0.0)
