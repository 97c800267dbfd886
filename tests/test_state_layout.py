"""The rule for the C twin's structs (fusion_core/native/fc_state.h): no pointer anywhere; a
saved state is the layout's fields only, and a twin set up from its parameters takes them and
continues bit for bit, so nothing outside the layout carries what the samples made; the layout
holds every field of the Python class's STATE; and the two twins refuse the same values."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest
from helpers import KEYS, state_numbers, with_number

from fusion_core import native
from fusion_core.presets import preset_params
from fusion_core.registry import CLASSES, FILTER, create
from fusion_core.state import BASE_STATE

pytestmark = pytest.mark.skipif(not native.available(),
                                reason=f"the C twin is unavailable: {native.reason()}")

TWIN_STRUCTS = (*(cls.TWIN for cls in CLASSES), "fc_sensor")
PAPER = {FILTER: "paper"}
OPTIONS: dict[str, list[dict]] = {
    "cf": [{}, {"gyro_sampling": "mean"}, {**PAPER, "gyro_sampling": "point"}],
    "mgcf": [{}, {**PAPER, "schedule": "experimental"}, {**PAPER, "schedule": "fixed"}],
    "kf": [{}, {"gyro_sampling": "mean"}, {**PAPER, "gyro_sampling": "point"}],
    "ukf": [{}, {"gyro_sampling": "mean"}, {**PAPER, "norm_noise": 0.0}],
    "poskf": [{}, {**PAPER, "qr_form": "diagonal"}],
}
"""Options that change what configure derives, besides the two presets (the papers' filters
chosen by "filter": "paper"); an estimator not named here is checked with its presets."""


def _pointers(ffi, ctype, path: str) -> list[str]:
    """The pointer members reachable in a C type (through structs and arrays)."""
    if ctype.kind == "pointer":
        return [path]
    if ctype.kind == "array":
        return _pointers(ffi, ctype.item, path + "[]")
    if ctype.kind == "struct":
        return [p for name, field in ctype.fields
                for p in _pointers(ffi, field.type, f"{path}.{name}")]
    return []


@pytest.mark.parametrize("struct", TWIN_STRUCTS)
def test_no_twin_struct_holds_a_pointer(struct: str) -> None:
    _, ffi = native.lib_and_ffi()
    assert _pointers(ffi, ffi.typeof(struct), struct) == []


def _layout(prefix: str):
    lib, ffi = native.lib_and_ffi()
    layout = lib.fc_state_layout(prefix.encode())
    assert layout != ffi.NULL
    fields = [(ffi.string(layout.fields[i].name).decode(), int(layout.fields[i].count))
              for i in range(layout.n_fields)]
    return layout, fields


ATTITUDE_CLASSES = [c for c in CLASSES if not c.HAS_POSITION]
"""The classes whose twins hold their Python STATE field by field (not the position filters,
whose nested filters and queue take another form in C)."""


@pytest.mark.parametrize("cls", ATTITUDE_CLASSES, ids=lambda c: c.__name__)
def test_the_c_layout_holds_every_state_field_of_the_python_class(cls: type) -> None:
    _, fields = _layout(cls.TWIN)
    names = [n.split("[")[0] for n, _ in fields]
    expected = [f"base.{n}" for n in BASE_STATE] + list(cls.STATE)
    assert list(dict.fromkeys(names)) == expected
    est = cls()
    for _ in range(50):
        est.step((0.1, 0.2, 9.8), (0.01, 0.02, 0.03), 0.01)
    sizes = {}
    for n, count in fields:
        sizes[n.split("[")[0]] = sizes.get(n.split("[")[0], 0) + count
    for name in cls.STATE:
        value = state_numbers(getattr(est, "_P" if name == "P" else name))
        assert sizes[name] == len(value), name


def _samples(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = 0.01 * np.arange(n)
    acc = np.stack([np.sin(0.5 * t), 2.0 * np.cos(0.3 * t), 9.5 + 0 * t], axis=1)
    acc += rng.normal(0.0, 0.3, acc.shape)
    gyro = np.stack([0.4 * np.cos(0.5 * t), -0.3 * np.sin(0.3 * t), 0.05 + 0 * t], axis=1)
    rest = (t > 1.0) & (t < 3.5)
    acc[rest] = (0.0, 0.0, 9.80665)
    gyro[rest] = (0.004, -0.003, 0.002)
    return acc, gyro


def _configs(key: str) -> list[dict]:
    return [preset_params("paper", key), *OPTIONS.get(key, [{}])]


@pytest.mark.parametrize("key", KEYS)
def test_a_twin_set_up_from_its_parameters_continues_bit_for_bit_from_the_layout(key: str
                                                                                  ) -> None:
    """Restore the way a native FMU does: T_init(params), fc_state_load, T_restored."""
    lib, ffi = native.lib_and_ffi()
    acc, gyro = _samples(600, 3)
    a, g = ffi.new("double[3]"), ffi.new("double[3]")
    out_a, out_b = ffi.new("fc_estimate *"), ffi.new("fc_estimate *")
    for params in _configs(key):
        est = create(key, params)
        prefix = type(est).TWIN
        layout, _ = _layout(prefix)
        size = lib.fc_state_size(layout)
        step = getattr(lib, f"{prefix}_step")
        for at in (0, 40, 150, 320, 500):
            twin = native.new_twin(est)
            for k in range(at):
                a[0:3], g[0:3] = acc[k].tolist(), gyro[k].tolist()
                step(twin, a, g, 0.01, out_a)
            saved = ffi.new("double[]", size)
            lib.fc_state_save(layout, twin, saved)
            why = ffi.new("char[]", 256)
            assert lib.fc_state_check(layout, saved, why, 256) == 0, ffi.string(why)
            fresh = native.new_twin(create(key, params))
            lib.fc_state_load(layout, fresh, saved)
            getattr(lib, f"{prefix}_restored")(fresh)
            for k in range(at, 600):
                a[0:3], g[0:3] = acc[k].tolist(), gyro[k].tolist()
                sa, sb = step(twin, a, g, 0.01, out_a), step(fresh, a, g, 0.01, out_b)
                assert sa == sb and bytes(ffi.buffer(out_a)) == bytes(ffi.buffer(out_b)), (
                    params, at, k)


EXTREMES = (math.nan, math.inf, -1.0, 0.5, 2.0, 3.2, 1.6, 6.0, 1e80, -1e80, 2.0**53 + 2, 0.0)


@pytest.mark.parametrize("cls", [c for c in ATTITUDE_CLASSES if "Unscented" not in c.__name__],
                         ids=lambda c: c.__name__)
def test_both_twins_refuse_the_same_values(cls: type) -> None:
    """A field of a running filter set to an extreme value: Python's set_state refuses it exactly
    when the C layout's check does (the fields these classes hold alike in both twins: not the
    UKFs' covariance, a matrix in Python and a packed triangle in C)."""
    lib, ffi = native.lib_and_ffi()
    key = cls.__name__
    prefix = cls.TWIN
    layout, fields = _layout(prefix)
    size = lib.fc_state_size(layout)
    est = cls()
    acc, gyro = _samples(200, 1)
    for k in range(200):
        est.step(acc[k], gyro[k], 0.01)
    snapshot = est.get_state()
    rng = random.Random(key)
    positions = []  # (python field, element index, C position)
    at = 0
    for name, count in fields:
        base = name.split("[")[0].removeprefix("base.")
        start = int(name.split("[")[1].split(":")[0].rstrip("]")) if "[" in name else 0
        positions += [(base, start + i, at + i) for i in range(count)]
        at += count
    disagreements = []
    why = ffi.new("char[]", 256)
    for field, element, position in positions:
        for value in EXTREMES:
            state = {**snapshot, "state": dict(snapshot["state"])}
            old = state["state"][field]
            if isinstance(old, list):
                state["state"][field] = with_number(old, element, value)
            else:
                state["state"][field] = value
            try:
                cls().set_state(state)
                python_ok = True
            except ValueError:
                python_ok = False
            doubles = ffi.new("double[]", size)
            lib.fc_state_save(layout, native.new_twin(est), doubles)
            doubles[position] = float(value)
            c_ok = lib.fc_state_check(layout, doubles, why, 256) == 0
            if python_ok != c_ok:
                disagreements.append((field, element, value, python_ok, c_ok))
    rng.shuffle(disagreements)
    assert not disagreements, disagreements[:5]
