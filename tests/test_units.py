"""Units: every FMU unit has integer SI exponents (FMI 2.0 BaseUnit), and the noise parameters
are power spectral densities whose old density names point to the new ones."""

from __future__ import annotations

import math

import pytest

import fusion_core
from fmu_src.model_description import UnitError, base_unit_attributes, display_factor
from fusion_core.sensor import SENSOR_PARAMS, ImuSensorModel
from fusion_core.types import DEG, RENAMED_PARAMS


@pytest.mark.parametrize(
    ("unit", "expected"),
    [
        ("rad2/s", {"rad": "2", "s": "-1"}),
        ("rad2/s3", {"rad": "2", "s": "-3"}),
        ("m2/s3", {"m": "2", "s": "-3"}),
        ("m2/s5", {"m": "2", "s": "-5"}),
        ("1", {}),
    ],
)
def test_power_spectral_density_units_have_integer_base_units(unit, expected):
    assert base_unit_attributes(unit) == expected


@pytest.mark.parametrize("unit", ["rad/(s.sqrt(Hz))", "rad/(s.sqrt(s))", "m/(s2.sqrt(Hz))"])
def test_a_half_power_unit_is_refused_with_the_way_out(unit):
    with pytest.raises(UnitError, match=r"non-integer SI exponents.*power spectral density"):
        base_unit_attributes(unit)


def test_psd_display_units_are_degrees_squared():
    assert display_factor("rad2/s", "deg2/s") == pytest.approx((1 / DEG) ** 2, rel=1e-15)
    assert display_factor("rad2/s3", "deg2/s3") == pytest.approx((1 / DEG) ** 2, rel=1e-15)


def _all_params():
    for key, cls in fusion_core.ESTIMATORS.items():
        for name, spec in cls.param_specs().items():
            yield key, name, spec
    for spec in SENSOR_PARAMS:
        yield "sensor", spec.name, spec


def test_every_parameter_unit_has_integer_exponents():
    for owner, name, spec in _all_params():
        if isinstance(spec.default, (int, float)) and not isinstance(spec.default, bool):
            base_unit_attributes(spec.unit)  # raises for a half power
            assert "sqrt" not in spec.unit, (owner, name)


def test_a_renamed_noise_parameter_names_its_successor():
    with pytest.raises(ValueError, match="gyro_noise is now gyro_psd, the density squared"):
        fusion_core.ESTIMATORS["ukf"](gyro_noise=0.05 * DEG)
    with pytest.raises(ValueError, match="acc_bias_walk is now acc_bias_psd"):
        ImuSensorModel(acc_bias_walk=1e-3)
    est = fusion_core.ESTIMATORS["poskf"]()
    with pytest.raises(ValueError, match="acc_noise is now acc_psd"):
        est.set_param("acc_noise", 0.004)
    # ukf keeps acc_noise (a dimensionless standard deviation): no hint, no error
    fusion_core.ESTIMATORS["ukf"](acc_noise=0.05)
    assert set(RENAMED_PARAMS.values()) <= {n for _, n, _ in _all_params()}


def test_the_sensor_psd_is_the_datasheet_density_squared():
    p = ImuSensorModel().params
    assert math.sqrt(p["gyro_psd"]) == pytest.approx(0.005 * DEG, rel=1e-15)
    assert math.sqrt(p["acc_psd"]) == pytest.approx(400e-6 * 9.80665, rel=1e-15)
