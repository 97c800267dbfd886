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
    from fusion_core.sensor import SENSOR_PRESETS
    from testbenches import battery
    from testbenches.broad.metric import gravity_from_roll_pitch, inclination_rmse_deg
    from testbenches.peers import run_vqf_ahead

    rate = 50.0
    error_free = {**SENSOR_PRESETS["ideal"], "gyro_psd": 0.0, "acc_psd": 0.0, "bits": 0}
    classes = {**battery.SENSOR_CLASSES,
               "error_free": battery.SensorClass("error_free", "no errors", rate, error_free)}
    with pytest.MonkeyPatch.context() as m:
        m.setattr(battery, "SENSOR_CLASSES", classes)
        t, truth, sample = battery.part_samples("handheld_fast", "error_free", 0)
    true_up = gravity_from_roll_pitch(truth["roll"], truth["pitch"])
    scored = t >= battery.MOTIONS["handheld_fast"].rest + battery.SETTLE_S

    def rmse(shift: float) -> float:  # VQF's output turned ahead by shift samples
        up = run_vqf_ahead(sample["acc"], sample["gyro"], rate, shift / rate)
        return inclination_rmse_deg(up, true_up, scored)

    assert rmse(-0.5) < rmse(0.0) / 3.0 and rmse(0.5) > rmse(0.0)
