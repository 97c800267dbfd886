"""The command line refuses numbers that cannot make a run, before any run starts, with the
option's name and what it allows (a campaign with no workers would wait forever, a negative
duration or retry count would record every run as failed, zero seeds would report nothing)."""

from __future__ import annotations

import argparse

import pytest

from testbenches.__main__ import main
from testbenches.montecarlo.runner import execute
from testbenches.options import (
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
