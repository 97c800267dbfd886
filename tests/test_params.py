"""Parameters: every out-of-range value is refused with a ValueError naming it."""

from __future__ import annotations

import math

import pytest
from helpers import KEYS, estimator_class, make, noisy_two_axis_recording

from fusion_core import Param
from fusion_core.registry import ENTRY


def invalid_values(spec: Param) -> list[object]:
    """Values that spec must refuse: off its choices, not a bool, NaN, beyond each bound."""
    if spec.choices is not None:
        return ["no-such-choice", spec.choices[0].upper() + "_", 1.0, None]
    if spec.kind is bool:
        return [2, -1, 0.5, "yes", None]
    values: list[object] = [math.nan, "1.0", None, [1.0]]
    if spec.low is not None:
        values += [spec.low - 1.0, -math.inf]
        if spec.low_open:
            values.append(spec.low)
    if spec.high is not None:
        values += [spec.high + 1.0, math.inf]
        if spec.high_open:
            values.append(spec.high)
    if spec.kind is int:
        values.append(spec.default + 0.5)
    return values


@pytest.mark.parametrize("key", KEYS)
def test_every_invalid_parameter_value_raises_value_error_naming_it_its_value_and_range(
    key: str,
) -> None:
    cls = estimator_class(key)
    problems = []
    checked = 0
    for name, spec in cls.param_specs().items():
        for value in invalid_values(spec):
            checked += 1
            try:
                cls(**{name: value})
            except ValueError as err:
                message = str(err)
                missing = [
                    part for part in (name, repr(value), spec.allowed()) if part not in message
                ]
                if missing:
                    problems.append(f"{name}={value!r}: message {message!r} lacks {missing}")
            else:
                problems.append(f"{name}={value!r} was accepted")
    print(f"\n{key}: {checked} invalid values checked")
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("key", KEYS)
def test_every_default_is_inside_its_own_allowed_range(key: str) -> None:
    specs = estimator_class(key).param_specs()
    for name, spec in specs.items():
        assert spec.validate(spec.default) == spec.default, name
    assert make(key).params == {name: spec.default for name, spec in specs.items()}


@pytest.mark.parametrize("key", KEYS)
def test_unknown_parameter_raises_value_error_naming_it(key: str) -> None:
    with pytest.raises(ValueError, match="no_such_param"):
        make(key, no_such_param=1.0)


@pytest.mark.parametrize("key", KEYS)
def test_set_param_refuses_an_out_of_range_value_and_keeps_the_old_one(key: str) -> None:
    est = make(key, max_dt=0.5)
    with pytest.raises(ValueError, match="max_dt"):
        est.set_param("max_dt", -1.0)
    assert est.params["max_dt"] == 0.5


@pytest.mark.parametrize("key", KEYS)
def test_max_dt_below_one_second_accepts_ordinary_samples(key: str) -> None:
    """max_dt = 0.05 s at 100 Hz: every sample (dt = 0.01 s) is valid and processed."""
    rec = noisy_two_axis_recording(1.0)
    out = make(key, max_dt=0.05).run(rec["acc_meas"], rec["gyro_meas"], rec["dt"])
    rejected = int(out["rejected"].sum())
    assert rejected == 0, f"{rejected} of {len(out['rejected'])} valid samples rejected"


@pytest.mark.parametrize("key", KEYS)
def test_what_a_class_declares_of_its_parameters_and_biases_holds(key: str) -> None:
    """SCANNED names tunable parameters of the class (what `tune` fits by default), and the
    axes whose bias it learns in motion (the contract scores them) are outputs it estimates."""
    cls = estimator_class(key)
    specs = cls.param_specs()
    # a class at its paper's values (no reference beside it) scans nothing
    assert cls.SCANNED or ENTRY[key].reference is None
    assert all(specs[name].tunable for name in cls.SCANNED)
    assert all(f"bias_{'xyz'[axis]}" not in cls.ZERO_BIAS for axis in cls.BIAS_IN_MOTION)
