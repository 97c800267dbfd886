"""The command line refuses numbers that cannot make a run, before any run starts, with the
option's name and what it allows (a campaign with no workers would wait forever, a negative
duration or retry count would record every run as failed, zero seeds would report nothing)."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from testbenches.__main__ import main
from testbenches.montecarlo.runner import execute
from testbenches.options import (
    counts_pair,
    jitter_fraction,
    non_negative_float,
    non_negative_int,
    positive_float,
    positive_int,
)


@pytest.mark.parametrize(("kind", "good", "bad"), [
    (positive_int, {"1": 1, "700": 700}, ["0", "-3", "2.5", "x", ""]),
    (non_negative_int, {"0": 0, "2": 2}, ["-1", "1.0", "two"]),
    (positive_float, {"60": 60.0, "0.5": 0.5}, ["0", "-5", "nan", "inf", "x"]),
    (non_negative_float, {"0": 0.0, "0.03": 0.03}, ["-0.01", "nan", "inf"]),
    (jitter_fraction, {"0": 0.0, "0.2": 0.2}, ["1", "1.5", "-0.1", "nan"]),
    (counts_pair, {"16384,131": (16384.0, 131.0), "2048,16.4": (2048.0, 16.4)},
     ["16384", "16384,0", "a,b", "1,2,3", "inf,131"]),
])
def test_each_number_type_takes_what_it_allows_and_names_it_otherwise(kind, good, bad):
    for text, value in good.items():
        assert kind(text) == value
    for text in bad:
        with pytest.raises(argparse.ArgumentTypeError, match=rf"{text!r}: allowed"):
            kind(text)


@pytest.mark.parametrize("argv", [
    ["run", "--seeds", "0"],
    ["run", "--duration", "-1"],
    ["run", "--jitter", "1.5"],
    ["run", "--jobs", "0"],
    ["campaign", "--workers", "0"],
    ["campaign", "--retries", "-1"],
    ["campaign", "--batch-size", "0"],
    ["campaign", "--duration", "0"],
    ["budget", "--seeds", "0"],
    ["estimate", "--counts", "16384", "x.csv"],
    ["noise", "--counts", "16384,-1", "x.csv"],
])
def test_the_commands_refuse_them_before_running(argv, capsys):
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    option = argv[1]
    assert f"argument {option}: {argv[2]!r}: allowed" in capsys.readouterr().err


def test_a_campaign_without_workers_is_refused_before_a_cluster_starts(tmp_path):
    with pytest.raises(ValueError, match="workers and batch_size of at least 1"):
        execute([], tmp_path, "local", workers=0)
    with pytest.raises(ValueError, match="retries of at least 0"):
        execute([], tmp_path, "local", retries=-1)


def test_every_commands_out_refuses_a_file_before_it_runs(tmp_path):
    """--out is a folder in every command that writes one: a file of that name is refused by
    the option (mkdir raised FileExistsError after the work, as a traceback), and the file is
    left as it was."""
    import argparse

    from testbenches.cli import _parser

    parser = _parser("imu-fusion")
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    with_out = [name for name, p in sub.choices.items()  # build-fmus: its own check, below
                if name != "build-fmus" and any("--out" in a.option_strings for a in p._actions)]
    assert {"estimate", "run", "broad", "noise", "tune", "calibrate", "battery", "campaign",
            "mechanisms", "budget", "crosscheck"} <= set(with_out)
    file = tmp_path / "taken"
    file.write_text("keep")
    for name in with_out:
        out = next(a for a in sub.choices[name]._actions if "--out" in a.option_strings)
        with pytest.raises(argparse.ArgumentTypeError, match="is a file: the outputs go to a "
                           "folder"):
            out.type(str(file))
        assert out.type(str(tmp_path / "new")) == tmp_path / "new"
    assert file.read_text() == "keep"
    assert main(["build-fmus", "--out", str(file)]) == 2
    assert file.read_text() == "keep"


def test_a_sensor_file_that_is_not_there_is_said_so(tmp_path):
    """--sensor naming a JSON file that does not exist: "no such file", not an errno's text."""
    from testbenches.options import load_sensor

    with pytest.raises(ValueError, match=r"sensor file .*none\.json: no such file$"):
        load_sensor(tmp_path / "none.json")


def test_every_command_that_draws_takes_no_plots_alike():
    """--no-plots (and --no-plot) in every command that writes a PNG, from one definition
    (testbenches.options.add_no_plots): calibrate lacked it, four spelt it their own way."""
    import argparse

    from testbenches.cli import _parser

    parser = _parser("imu-fusion")
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name in ("estimate", "run", "broad", "noise", "tune", "calibrate", "battery",
                 "campaign", "budget"):
        action = next((a for a in sub.choices[name]._actions if "--no-plots" in a.option_strings),
                      None)
        assert action is not None, f"{name} has no --no-plots"
        assert action.option_strings == ["--no-plots", "--no-plot"], name
        assert action.help.startswith("skip "), name


def test_an_option_is_not_taken_by_a_prefix_of_its_name(capsys):
    """argparse took `estimate --sensor 0.02` for --sensor-delay 0.02 (a delay of 20 ms, with
    no word) and `--ref FILE` for --reference: every command takes its options by their whole
    names only."""
    example = str(Path(__file__).resolve().parents[1] / "examples" / "tilt_motion.csv")
    for prefix in ("--sensor", "--ref", "--est"):
        with pytest.raises(SystemExit):
            main(["estimate", example, prefix, "0.02"])
        assert f"unrecognized arguments: {prefix} 0.02" in capsys.readouterr().err
