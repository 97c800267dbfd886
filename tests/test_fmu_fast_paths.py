"""FmuSlave's fast paths (fmi2SetReal on inputs, fmi2GetReal, fmi2GetInteger; issue 6) against
the full guarded path they short-cut: the same values, the same log messages, never an
exception out of a callback; and the estimator model's per-step work.

The slaves run in this process, without building an FMU: pythonfmu's C++ wrapper only turns each
FMI call into one call of these Python methods (the built FMUs are compared with fusion_core in
test_fmu_runtime.py, test_fmu_state.py and test_fmu_bad_input.py).
"""

from __future__ import annotations

import math
from functools import partial
from typing import Any

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from pythonfmu import Fmi2Slave

import fusion_core
from fmu_src.estimator import EstimatorSlave
from fmu_src.host import INPUTS
from fmu_src.slave import FmuSlave
from fusion_core import synthetic
from fusion_core.scenarios import get_scenario


class FastCf(EstimatorSlave):
    """The ComplementaryFilter FMU's slave (Integer choice parameters)."""

    key = "cf"
    description = "fast-path test: complementary filter"


class FastPoskf(EstimatorSlave):
    """The PositionKalmanFilter FMU's slave (position outputs)."""

    key = "poskf"
    description = "fast-path test: position filter"


SLAVES = {"cf": FastCf, "poskf": FastPoskf}


def new_slave(key: str, running: bool = True) -> FmuSlave:
    slave = SLAVES[key](instance_name=f"fast-path-{key}")
    if running:
        slave.exit_initialization_mode()
    return slave


def vrs_of(slave: FmuSlave, *names: str) -> list[int]:
    by_name = {v.name: vr for vr, v in slave.vars.items()}
    return [by_name[n] for n in names]


def logs(slave: FmuSlave) -> list[tuple[int, str]]:
    """The slave's log so far: status and first line of each message (a traceback's frames
    name the calling method, which differs between the two paths by design)."""
    return [(int(m.status), m.msg.splitlines()[0]) for m in slave.log_queue]


def same(a: Any, b: Any) -> bool:
    """Equal values of the same type, NaN equal to NaN."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and a == b


def same_values(x: dict[str, Any], y: dict[str, Any]) -> bool:
    return x.keys() == y.keys() and all(same(x[k], y[k]) for k in x)


# ----- the full path as it was before the fast paths (pythonfmu's methods under the guard) -----
def full_set_real(slave: FmuSlave, vrs: list[int], values: list[Any]) -> None:
    slave._guard(partial(Fmi2Slave.set_real, slave), "fmi2SetReal", vrs, values)


def full_get(slave: FmuSlave, kind: str, vrs: list[int]) -> list[Any]:
    getter = {"real": Fmi2Slave.get_real, "integer": Fmi2Slave.get_integer}[kind]
    try:
        return getter(slave, vrs)
    except Exception:
        slave._log_exception(f"fmi2Get{kind.capitalize()}{tuple(vrs)}")
        return [float("nan") if kind == "real" else 0] * len(vrs)


# ----- hypothesis strategies: what a host (or a broken host) may pass ---------------------------
N_VARIABLES = max(len(cls.VARIABLES) for cls in SLAVES.values())
value_references = st.integers(min_value=-2, max_value=N_VARIABLES + 2)
odd_values = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-3, max_value=5),
    st.booleans(),
    st.sampled_from([None, "1.5", "not a number", [], 10**400]),
)
calls = st.lists(
    st.tuples(st.lists(value_references, max_size=9), st.lists(odd_values, max_size=9)),
    min_size=1, max_size=6,
)


@settings(max_examples=150, deadline=None)
@given(key=st.sampled_from(sorted(SLAVES)), running=st.booleans(), calls=calls)
def test_set_real_gives_the_values_and_logs_of_the_full_path(key, running, calls):
    fast, full = new_slave(key, running), new_slave(key, running)
    for vrs, values in calls:
        fast.set_real(vrs, values)  # never raises: an exception would be fmi2Fatal
        full_set_real(full, vrs, values)
        assert same_values(fast._values, full._values)
    assert logs(fast) == logs(full)
    assert fast._model.get_state() == full._model.get_state()


@settings(max_examples=150, deadline=None)
@given(key=st.sampled_from(sorted(SLAVES)), vrs=st.lists(value_references, max_size=12))
def test_get_real_and_get_integer_give_what_the_full_path_gives(key, vrs):
    fast, full = new_slave(key), new_slave(key)
    for kind in ("real", "integer"):
        got = getattr(fast, f"get_{kind}")(vrs)
        expected = full_get(full, kind, vrs)
        assert type(got) is list and len(got) == len(vrs)  # the C++ wrapper reads a list
        assert all(same(a, b) for a, b in zip(got, expected, strict=True))
    assert logs(fast) == logs(full)


def test_fast_tables_cover_the_real_inputs_and_every_real_and_integer():
    slave = new_slave("poskf")
    kinds = {v.name: (v.causality, v.type) for v in slave.VARIABLES}
    assert sorted(slave._fast_inputs.values()) == sorted(INPUTS)
    assert {kinds[n][1] for n in slave._fast_reals.values()} == {"Real"}
    assert {kinds[n][1] for n in slave._fast_integers.values()} == {"Integer"}
    assert len(slave._fast_reals) + len(slave._fast_integers) == sum(
        t != "Boolean" for _, t in kinds.values())
    assert slave.get_integer(vrs_of(slave, "gyro_sampling", "invalid_samples")) == [1, 0]


def test_a_subclass_with_its_own_input_setter_always_gets_it_called():
    seen = []

    class Checked(FastCf):
        def _set_value(self, var, value):
            seen.append(var.name)
            super()._set_value(var, value)

    slave = Checked(instance_name="checked")
    assert slave._fast_inputs == {}
    slave.set_real(vrs_of(slave, "acc_x", "dt"), [1.0, 0.02])
    assert seen == ["acc_x", "dt"] and slave._values["dt"] == 0.02


def test_a_bad_sample_set_through_the_fast_path_is_rejected_by_the_estimator():
    slave = new_slave("cf")
    in_vr = vrs_of(slave, *INPUTS)
    out_vr = vrs_of(slave, "roll", "pitch")
    count_vr = vrs_of(slave, "invalid_samples")
    slave.set_real(in_vr, [0.0, 1.0, 9.7, 0.01, 0.0, 0.0, 0.01])
    assert slave.do_step(0.0, 0.01) is True
    first = slave.get_real(out_vr)
    slave.set_real(in_vr, [float("nan"), 1.0, 9.7, 0.01, 0.0, 0.0, 0.01])
    assert slave.do_step(0.01, 0.01) is True  # fmi2OK: the sample is counted, not fatal
    assert slave.get_real(out_vr) == first and slave.get_integer(count_vr) == [1]
    assert "rejected, the filter state is kept" in slave.log_queue[-1].msg
    slave.set_real(in_vr, [0.0, 1.0, 9.7, 0.01, 0.0, 0.0, 0.0])  # dt = 0
    slave.do_step(0.02, 0.01)
    assert slave.get_integer(count_vr) == [2]


def test_stepping_in_process_equals_fusion_core_and_every_state_is_a_copy():
    """Every doStep's outputs equal fusion_core's step (the model refills one output dict: the
    values must still be copied into the slave's table and into each FMU state)."""
    trajectory = get_scenario("moderate_dynamics").trajectory()
    rec = synthetic.record(trajectory, 3.0, 100.0, noise=synthetic.MPU6050, seed=3)
    for key in SLAVES:
        slave, core = new_slave(key), fusion_core.ESTIMATORS[key]()
        names = ["roll", "pitch", "bias_x", "bias_y", "bias_z"]
        if key == "poskf":
            names += ["pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z"]
        in_vr, out_vr = vrs_of(slave, *INPUTS), vrs_of(slave, *names)
        states = []
        for i, (acc, gyro, dt) in enumerate(
            zip(rec["acc_meas"].tolist(), rec["gyro_meas"].tolist(), rec["dt"].tolist(),
                strict=True)
        ):
            slave.set_real(in_vr, [*acc, *gyro, dt])
            assert slave.do_step(i * 0.01, 0.01)
            e = core.step(acc, gyro, dt)
            expected = [e.roll, e.pitch, *e.bias, *(e.pos or ()), *(e.vel or ())]
            assert slave.get_real(out_vr) == expected
            states.append((slave._get_fmu_state(), slave.get_real(out_vr)))
        for state, outputs in states[::50]:
            assert [state["values"][n] for n in names] == outputs
        assert np.isfinite(slave.get_real(out_vr)).all()
