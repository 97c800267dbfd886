"""The battery of motions and parts (testbenches.battery): its motions are the physics they
say, each filter gets the parameters its sensor's noise gives, and the Dask run gives the
numbers the in-process run gives."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from fusion_core.kalman import RECOMMENDED_INIT_BIAS_STD
from fusion_core.presets import noise_preset
from fusion_core.sensor import CALIBRATION
from fusion_core.types import DEG, G
from testbenches import battery
from testbenches.battery import MOTIONS, SENSOR_CLASSES


def _truth(name: str, rate: float = 200.0) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    m = MOTIONS[name]
    t = np.arange(round((m.rest + min(m.duration, 60.0)) * rate) + 1) / rate
    return t, m.trajectory().truth(t)


def test_the_pendulums_accelerometer_reads_along_its_arm() -> None:
    """Only the swing's departure from a harmonic one (g (sin a - a), 0.06 g at 40 deg) and
    the slow pitch sway push the specific force off the arm (the sensor's z axis)."""
    t, x = _truth("pendulum")
    moving = t >= MOTIONS["pendulum"].rest + MOTIONS["pendulum"].fade
    across = np.hypot(x["f"][moving, 0], x["f"][moving, 1])
    assert across.max() < 0.08 * G
    assert np.degrees(np.abs(x["roll"][moving])).max() == pytest.approx(40.0, abs=0.5)


@pytest.mark.parametrize("name", list(MOTIONS))
def test_a_motion_rests_and_then_sets_in_without_a_jolt(name: str) -> None:
    """The rest is still and level; fading the motion in adds no specific force beyond what
    the motion itself reaches (a fade too short for large positions jolts by several g)."""
    m = MOTIONS[name]
    t, x = _truth(name)
    norm = np.linalg.norm(x["f"], axis=1)
    rest = t < m.rest
    assert np.allclose(norm[rest], G) and np.allclose(x["omega"][rest], 0.0)
    fade = (t >= m.rest) & (t < m.rest + m.fade)
    after = t >= m.rest + m.fade
    if fade.any():
        assert np.abs(norm[fade] - G).max() <= np.abs(norm[after] - G).max() + 0.05 * G


def test_the_slow_rotation_turns_from_power_up_and_never_rests() -> None:
    t, x = _truth("slow_rotation", 100.0)
    rate = np.linalg.norm(x["omega"], axis=1)
    assert MOTIONS["slow_rotation"].rest == 0.0
    assert rate[t > 0.0].min() > 0.0
    assert np.degrees(rate.max()) == pytest.approx(40.0 * 2 * math.pi * 0.02, rel=1e-3)


@pytest.mark.parametrize("name", list(SENSOR_CLASSES))
def test_each_filter_gets_what_its_sensors_noise_gives(name: str) -> None:
    c = SENSOR_CLASSES[name]
    params = battery.filter_params(c)
    gyro_density = math.sqrt(c.value("gyro_psd"))
    assert params["kf"]["Q_angle"] == pytest.approx(gyro_density ** 2)
    assert params["ukf"]["gyro_psd"] == pytest.approx(gyro_density ** 2)
    for key in battery.filter_keys():
        assert params[key]["gyro_range"] == c.value("gyro_range")
    acc_std = params["cf"]["acc_noise"] * G  # one sample's noise at the class's rate
    density_part = math.sqrt(c.value("acc_psd") * c.rate)
    assert density_part <= acc_std <= 1.2 * density_part
    assert {**noise_preset(gyro_density, math.sqrt(c.value("acc_psd")), acc_std,
                           c.value("gyro_range"))["mgcf"],
            "sensor_delay": params["mgcf"]["sensor_delay"]} == params["mgcf"]
    # the gyro's delay of the part's low-pass setting, as the datasheet's table gives it:
    # DLPF_CFG 4 (21 Hz) on the worse part, 0 (the register's reset value) on the others
    for key in battery.filter_keys():
        assert params[key]["sensor_delay"] == (8.3e-3 if name == "worse" else 0.98e-3)
    bias_std = max(CALIBRATION[c.value("calibration")][0])  # what the part starts with
    for key in ("kf", "ukf"):
        assert params[key]["init_bias_std"] == max(bias_std, RECOMMENDED_INIT_BIAS_STD)


@pytest.mark.parametrize("name", list(SENSOR_CLASSES))
def test_a_known_scale_is_the_classs_own_spread_of_gyro_scale_factors(name: str) -> None:
    """--known-scale changes gyro_scale_std alone, to the sensor model's spread for the class;
    without it every class gets the recommended value."""
    from fusion_core.building_blocks.adaptive_noise import RECOMMENDED_GYRO_SCALE_STD

    c = SENSOR_CLASSES[name]
    default, known = battery.filter_params(c), battery.filter_params(c, known_scale=True)
    for key in battery.filter_keys():
        assert default[key].get("gyro_scale_std", RECOMMENDED_GYRO_SCALE_STD) == \
            RECOMMENDED_GYRO_SCALE_STD
        assert known[key]["gyro_scale_std"] == c.value("gyro_scale_std")
        rest = {n: v for n, v in known[key].items() if n != "gyro_scale_std"}
        assert rest == {n: v for n, v in default[key].items() if n != "gyro_scale_std"}


def test_a_worse_parts_known_scale_lets_the_kf_follow_a_runner() -> None:
    """A runner's torso turns back and forth for minutes while its bounce hides the tilt: the
    worse part's 2 % scale errors add up, and a kf told of them (gyro_scale_std, from the
    datasheet) corrects them from the accelerometer sooner; with the recommended 0.5 % it
    trusts the gyro too long, on every part."""
    for seed in range(3):
        default = battery.part_rmse("running", "worse", seed, ["kf"], vqf=False)["kf"]
        known = battery.part_rmse("running", "worse", seed, ["kf"], vqf=False,
                                  setup=battery.Setup(known_scale=True))["kf"]
        assert known < 0.9 * default


@pytest.mark.heavy  # parts that never rest
def test_an_uncalibrated_part_that_never_rests_learns_its_bias_with_its_prior() -> None:
    """The slow roll from power-up on parts as delivered (turn-on gyro biases of degrees per
    second, no rest to measure them): with the prior the part's class gives, the UKF learns its
    three biases from the accelerometer and every part stays within 5 deg; with a calibrated
    part's prior it learns them more slowly, and the mean and the worst part are worse (8 parts:
    2.2 and 3.1 deg against 3.0 and 6.1)."""
    from fusion_core.kalman import RECOMMENDED_INIT_BIAS_STD as CALIBRATED

    wide = [battery.part_rmse("slow_rotation", "mpu6050_raw", seed, ["ukf"], vqf=False)["ukf"]
            for seed in range(8)]
    narrow = [battery.part_rmse("slow_rotation", "mpu6050_raw", seed, ["ukf"],
                                {"ukf": {"init_bias_std": CALIBRATED}}, vqf=False)["ukf"]
              for seed in range(8)]
    assert max(wide) < 5.0
    assert np.mean(wide) < np.mean(narrow) and max(wide) < max(narrow)


def test_a_second_of_absurd_samples_leaves_the_kf_no_bias_it_cannot_unlearn() -> None:
    """A slow roll that never rests, and one second of absurd samples 10 s in (mpu6050_glitch):
    they scramble the kf's attitude and its measured vector alike, and as the vector refills
    the attitude drifts back to gravity. Learned as a gyro bias on a horizontal axis and carried
    to z by a face switch, that drift stayed to the end of the run, since bias_z is observed
    only at rest (10 parts: 6.2 deg RMSE from 60 s on, 17.6 on part 7). The bias gate on the
    vector's own norm waits until the vector has let the disturbance go (here 2.0 deg; the UKF,
    which observes its three biases from the tilt, 0.1)."""
    from fusion_core.registry import create
    from testbenches.broad.metric import gravity_from_roll_pitch, inclination_rmse_deg

    params = battery.filter_params(SENSOR_CLASSES["mpu6050_glitch"])["kf"]
    late = []
    for seed in range(10):
        t, truth, sample = battery.part_samples("slow_rotation", "mpu6050_glitch", seed)
        o = create("kf", params).run(sample["acc"], sample["gyro"], sample["dt"])
        late.append(inclination_rmse_deg(gravity_from_roll_pitch(o["roll"], o["pitch"]),
                                         gravity_from_roll_pitch(truth["roll"], truth["pitch"]),
                                         t >= 60.0))
    assert np.mean(late) < 3.0


def test_the_worse_part_clips_where_the_better_one_does_not() -> None:
    """The classes' ranges are the sensor model's: on the clipping motion the worse part's
    gyro sits at its +-1000 deg/s far more often."""
    from fusion_core.sensor import ImuSensorModel

    _, x = _truth("clipping", 200.0)
    share = {}
    for name in ("better", "worse"):
        c = SENSOR_CLASSES[name]
        g = ImuSensorModel(**c.params).run(x["omega"], x["f"], 1.0 / 200.0)["gyro"]
        share[name] = float(np.mean(np.abs(g) >= 0.999 * c.value("gyro_range")))
    assert share["worse"] > 3 * share["better"]
    assert SENSOR_CLASSES["worse"].value("gyro_range") == pytest.approx(1000 * DEG)


@pytest.mark.heavy
def test_the_command_on_a_local_cluster_gives_the_in_process_numbers(tmp_path, capsys) -> None:
    pytest.importorskip("vqf")
    pytest.importorskip("dask.distributed")
    from testbenches.cli import main

    status = main(["battery", "--motion", "pendulum,disturbed", "--sensor", "worse", "--parts",
                   "2", "--out", str(tmp_path), "--no-plots"])
    assert status == 0
    got = json.loads((tmp_path / "battery.json").read_text())["rmse_deg"]
    here = battery.run_battery(["pendulum", "disturbed"], ["worse"], 2, scheduler=None)
    assert got == here
    for name in ("pendulum", "disturbed"):
        page = (tmp_path / f"{name}.md").read_text()
        assert "| worse |" in page and "VQF" in page
    assert "[pendulum](pendulum.md)" in capsys.readouterr().out


def test_every_motion_has_its_page_in_the_docs_navigation() -> None:
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    nav = (root / "mkdocs.yml").read_text()
    for name in MOTIONS:
        assert (root / "docs" / "results" / "battery" / f"{name}.md").is_file(), name
        assert f"results/battery/{name}.md" in nav, name


def test_a_sensor_without_quantisation_adds_no_converter_noise() -> None:
    """bits 0 turns quantisation off: one sample's accelerometer noise is then its white noise
    alone, not a step of twice the range."""
    from testbenches.battery import SensorClass

    c = SensorClass("ideal_adc", "no converter", 100.0, {"bits": 0})
    std = battery.filter_params(c)["cf"]["acc_noise"] * G
    assert std == pytest.approx(math.sqrt(c.value("acc_psd") * c.rate))


def test_a_param_reaches_every_filter_that_has_it_and_an_unknown_one_is_refused(tmp_path,
                                                                               capsys) -> None:
    """`battery --param`: a value goes to the filters that have the parameter (the Kalman
    filters' gyro_psd, not the complementary filters'), changes their numbers and no other's,
    and is written to battery.json; a name no filter has, or a value out of range, is refused in
    one line before any run, saying what is allowed."""
    pytest.importorskip("vqf")
    from testbenches.cli import main

    assert battery.filter_overrides({"gross_innovation": 0.3}) == {
        "kf": {"gross_innovation": 0.3}, "ukf": {"gross_innovation": 0.3}}
    with pytest.raises(ValueError, match=r"no attitude filter has it; they have .*scale_time"):
        battery.filter_overrides({"gross_innovatoin": 0.3})
    with pytest.raises(ValueError, match=r"--param, cf: .*scale_time"):
        battery.filter_overrides({"scale_time": -1.0})
    status = main(["battery", "--motion", "clipping", "--sensor", "mpu6050_glitch", "--parts", "1",
                   "--out", str(tmp_path), "--no-plots", "--scheduler", "local",
                   "--param", "gyro_psd=1e-4"])
    assert status == 0
    report = json.loads((tmp_path / "battery.json").read_text())
    assert report["params"] == {"gyro_psd": 1e-4}
    got = report["rmse_deg"]["clipping"]["mpu6050_glitch"]
    default = battery.run_battery(["clipping"], ["mpu6050_glitch"], 1, scheduler=None)
    default = default["clipping"]["mpu6050_glitch"]
    assert got["kf"] != default["kf"] and got["ukf"] != default["ukf"]
    assert (got["cf"], got["mgcf"], got["vqf"]) == (default["cf"], default["mgcf"], default["vqf"])
    assert main(["battery", "--param", "nope=1", "--out", str(tmp_path)]) != 0
    assert "no attitude filter has it" in capsys.readouterr().err


def test_a_class_at_another_rate_is_the_same_part_sampled_at_that_rate() -> None:
    """`--rate`: "NAME@RATEHz" is the class with every sensor parameter as it is and only the
    rate changed; its filters get one sample's noise at that rate, its parts as many samples
    per second; an unknown class or a rate out of range is refused saying what is allowed."""
    base = SENSOR_CLASSES["worse"]
    fast = battery.sensor_class(battery.at_rate("worse", 1000.0))
    assert fast.name == "worse@1000Hz" and fast.rate == 1000.0
    assert fast.params == base.params and fast.glitch == base.glitch
    assert "sampled at 1000 Hz" in fast.what
    assert battery.sensor_class("worse") is base
    slow_noise = battery.filter_params(base)["cf"]["acc_noise"]
    fast_noise = battery.filter_params(fast)["cf"]["acc_noise"]
    assert fast_noise > 4.0 * slow_noise  # 20 times the rate: about sqrt(20) times the noise
    t, _, sample = battery.part_samples("pendulum", "worse@1000Hz", 0)
    assert np.diff(t)[0] == pytest.approx(1e-3)
    assert len(sample["acc"]) == len(t)
    with pytest.raises(ValueError, match=r"unknown sensor class 'wurse@100Hz': allowed better"):
        battery.sensor_class("wurse@100Hz")
    with pytest.raises(ValueError, match=r"allowed 10 to 10000 Hz"):
        battery.sensor_class("worse@5Hz")


def test_the_rate_table_counts_each_rate_and_gives_vqfs_error() -> None:
    """One line per motion, a column per rate: the best of ours over VQF, kf's and ukf's (the
    worse) in brackets, and VQF's mean RMSE; the last line counts per column."""
    cell = {"cf": [1.0, 1.0], "mgcf": [2.0, 2.0], "kf": [0.8, 0.8], "ukf": [0.9, 0.9],
            "vqf": [1.0, 1.0]}
    behind = {**cell, "cf": [1.2, 1.2], "kf": [1.1, 1.1], "ukf": [1.3, 1.3]}
    results = {"pendulum": {"a@50Hz": cell, "a@1000Hz": behind},
               "running": {"a@50Hz": cell, "a@1000Hz": cell}}
    table = battery.rate_table(results)
    assert "| pendulum | kf 0.80 (0.90); VQF 1.000 | kf 1.10 (1.30); VQF 1.000 |" in table
    assert table.endswith("Of 2 motions, the best of ours is ahead of VQF in 2 (a@50Hz), "
                          "1 (a@1000Hz); kf and ukf are within 5 % of it or ahead in 2, 1.")


@pytest.mark.heavy
def test_the_command_runs_a_class_at_each_rate_given(tmp_path) -> None:
    pytest.importorskip("vqf")
    from testbenches.cli import main

    status = main(["battery", "--motion", "pendulum", "--sensor", "better", "--rate", "100,400",
                   "--parts", "1", "--out", str(tmp_path), "--no-plots", "--scheduler", "local"])
    assert status == 0
    report = json.loads((tmp_path / "battery.json").read_text())
    assert list(report["rmse_deg"]["pendulum"]) == ["better@100Hz", "better@400Hz"]
    assert report["sensor_classes"]["better@400Hz"]["rate"] == 400.0
    here = battery.run_battery(["pendulum"], ["better@400Hz"], 1, scheduler=None)
    assert report["rmse_deg"]["pendulum"]["better@400Hz"] == here["pendulum"]["better@400Hz"]
    with pytest.raises(SystemExit):
        main(["battery", "--rate", "100,fast", "--out", str(tmp_path)])


def test_the_known_scale_table_compares_each_cell_and_counts_both_ways() -> None:
    """Each cell: the worse of kf's and ukf's mean over VQF's, as recommended -> known; the last
    line counts the aims' cells both ways (a tie with VQF is not ahead, 1.05 is within)."""
    def cell(kf: float, ukf: float, cf: float) -> dict[str, list[float]]:
        return {"cf": [cf, cf], "kf": [kf, kf], "ukf": [ukf, ukf], "vqf": [1.0, 1.0]}

    recommended = {"running": {"better": cell(1.2, 1.1, 1.0), "worse": cell(1.05, 1.0, 0.9)}}
    known = {"running": {"better": cell(0.9, 0.95, 1.0), "worse": cell(1.5, 1.4, 1.3)}}
    text = battery.setup_table(recommended, known, battery.Setup(known_scale=True))
    head, _rule, row, _, counts = text.split("\n")
    assert head == "| motion | better (0.2 %) | worse (2 %) |"
    assert row == "| running | 1.20 -> 0.95 | 1.05 -> 1.50 |"
    assert counts == ("Of 2 cells, the best of ours is ahead of VQF in 1 as recommended and 1 "
                      "with the class's spread; kf and ukf are within 5 % of it in 1 and 1.")
    text = battery.setup_table(recommended, known, battery.Setup(calibrated_first=True))
    head, _rule, row, _, counts = text.split("\n")
    assert head == "| motion | better | worse |"
    assert counts.startswith("Of 2 cells, the best of ours is ahead of VQF in 1 as recommended "
                             "and 1 calibrated first;")


def test_a_part_calibrated_first_gives_every_filter_and_vqf_its_calibration() -> None:
    """Calibrated first, the filters run with the part's own calibration (the calibrate
    command's matrices, testbenches.calibrate.part) and VQF on the samples that calibration
    conditions: the same numbers as running each by hand that way. The worse part's gyro
    matrix (2 % scale, 1.3 % cross-axis errors) is most of a runner's error, in ours and in
    VQF alike."""
    from fusion_core.registry import create
    from testbenches.broad.metric import gravity_from_roll_pitch, inclination_rmse_deg
    from testbenches.calibrate.part import part_calibration
    from testbenches.estimate import conditioned
    from testbenches.peers import PEERS

    pytest.importorskip("vqf")
    motion, sensor, seed = "running", "worse", 1
    setup = battery.Setup(calibrated_first=True)
    got = battery.part_rmse(motion, sensor, seed, ["kf"], setup=setup)
    raw = battery.part_rmse(motion, sensor, seed, ["kf"])
    s, m = battery.SENSOR_CLASSES[sensor], battery.MOTIONS[motion]
    t, truth, sample = battery.part_samples(motion, sensor, seed)
    calibration = part_calibration(s.params, seed)
    assert any(k.startswith("gyro_") for k in calibration)
    up = gravity_from_roll_pitch(truth["roll"], truth["pitch"])
    scored = t >= m.rest + battery.SETTLE_S
    out = create("kf", {**battery.filter_params(s)["kf"], **calibration}).run(
        sample["acc"], sample["gyro"], sample["dt"])
    assert got["kf"] == inclination_rmse_deg(gravity_from_roll_pitch(out["roll"], out["pitch"]),
                                             up, scored)
    acc, gyro = conditioned(sample["acc"], sample["gyro"], calibration)
    assert got["vqf"] == inclination_rmse_deg(PEERS["vqf"](acc, gyro, s.rate), up, scored)
    assert got["kf"] < 0.6 * raw["kf"] and got["vqf"] < 0.8 * raw["vqf"]
