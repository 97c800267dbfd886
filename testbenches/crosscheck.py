"""`imu-fusion crosscheck`: the native FMUs and their results in the FMI Cross-Check layout,
checked by fmpy's own cross-check validation.

The chain is the testbench's: the plant's truth feeds the sensor, the sensor's samples feed
every estimator. For each model this writes, as an exporting tool does,

    fmus/<2.0|3.0>/cs/<platform>/imu-fusion-fmu/<version>/<Model>/
        <Model>.fmu  <Model>_in.csv  <Model>_ref.csv  <Model>_ref.opt  README.md

with the reference computed by fusion_core (the Python reference, not the FMU's binary), and,
as an importing tool does, fmpy simulating the FMU on `_in.csv`:

    results/<2.0|3.0>/cs/<platform>/fmpy/<fmpy version>/imu-fusion-fmu/<version>/<Model>/
        <Model>_out.csv  <Model>_cc.sh  <Model>_cc.log  README.md  passed

`passed` is written where fmpy's `validate_result` finds the result within its bands around the
reference. Then fmpy's `validate_repo` checks the whole tree (file layout, model descriptions,
CSV files, reference options, results) and the command exits 1 on any problem. fmpy's checker
reads FMI 1.0 and 2.0 trees only: the FMI 3.0 FMUs are laid out and compared the same way, and
the report says that the tree validation left them out.
"""

from __future__ import annotations

import argparse
import platform
import shlex
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fmu_src.variables import items_in_description

TOOL = "imu-fusion-fmu"
IMPORTER = "fmpy"
STEP = 0.01
"""The communication step and the sample period [s]."""
DURATION = 10.0
"""The simulated time [s]: 1000 samples of the plant's default scenario."""
PLATFORMS = {"fmi2": "linux64", "fmi3": "x86_64-linux"}
VERSIONS = {"fmi2": "2.0", "fmi3": "3.0"}


@dataclass
class Checked:
    """One model's cross-check: where its files went and what the comparison found."""

    model: str
    version: str
    fmu_dir: Path
    result_dir: Path
    problem: str | None = None
    outputs: list[str] = field(default_factory=list)


def _times(n: int) -> np.ndarray:
    return np.arange(n + 1) * STEP


def _typed(variable: Any) -> Any:
    """A variable's start value as Python reads it (fmpy gives strings)."""
    if variable.type == "Real" or variable.type.startswith("Float"):
        return float(variable.start)
    items = items_in_description(variable.description)
    if variable.type in ("Integer", "Int32") and items:
        return items[int(variable.start) - 1]  # the item's name is the choice fusion_core takes
    if variable.type == "Boolean":
        return variable.start in ("true", "1", True)
    if variable.type.startswith("Int") or variable.type == "Integer":
        return int(variable.start)
    return variable.start


def _description(fmu: Path) -> Any:
    from fmpy import read_model_description

    return read_model_description(str(fmu))


def _start_row(md: Any, names: list[str]) -> list[float]:
    """The outputs before the first step: their start values (what fmpy records at t = 0)."""
    by_name = {v.name: v for v in md.modelVariables}
    return [float(by_name[n].start) for n in names]


def _outputs(md: Any) -> list[str]:
    return [v.name for v in md.modelVariables if v.causality == "output"]


def _parameters(md: Any) -> dict[str, Any]:
    return {v.name: _typed(v) for v in md.modelVariables
            if v.causality == "parameter" and v.start is not None}


# ----- the references: fusion_core, sample by sample as the FMU steps ------------------------

def plant_reference(md: Any, n: int) -> dict[str, np.ndarray]:
    """ImuPlant: the scenario's truth at each communication point."""
    from fusion_core.scenarios import get_scenario
    from fusion_core.synthetic import TRUTH_NAMES

    trajectory = get_scenario(int(_parameters(md)["scenario"])).trajectory()
    rows = np.array([trajectory.truth_at(float(t)) for t in _times(n)])
    return {name: rows[:, i] for i, name in enumerate(TRUTH_NAMES)}


def sensor_reference(md: Any, inputs: dict[str, np.ndarray], n: int) -> dict[str, np.ndarray]:
    """ImuSensor: ImuSensorModel with the FMU's start values, one sample per step of the inputs
    at its start."""
    from fmu_src.testbench_models import INPUTS_AT
    from fusion_core.sensor import ImuSensorModel

    # the sensor model's own parameters (inputs_at is the FMU's: its default, the end of the
    # step, gives the sample of the step's inputs over h, as here)
    model = ImuSensorModel(**{k: v for k, v in _parameters(md).items() if k != INPUTS_AT.name})
    names = _outputs(md)
    rows = [_start_row(md, names)]
    times = _times(n)
    for k in range(n):
        acc, gyro, dt = model.sample(
            tuple(inputs[f"omega_{a}"][k] for a in "xyz"),
            tuple(inputs[f"f_{a}"][k] for a in "xyz"), STEP)
        bias = model.gyro_bias
        values = {"acc_x": acc[0], "acc_y": acc[1], "acc_z": acc[2], "gyro_x": gyro[0],
                  "gyro_y": gyro[1], "gyro_z": gyro[2], "dt": dt, "true_bias_x": bias[0],
                  "true_bias_y": bias[1], "true_bias_z": bias[2],
                  "last_step": times[k + 1] - times[k]}  # the step fmpy passed
        rows.append([values[name] for name in names])
    table = np.array(rows)
    return {name: table[:, i] for i, name in enumerate(names)}


def estimator_reference(key: str, md: Any, inputs: dict[str, np.ndarray], n: int
                        ) -> dict[str, np.ndarray]:
    """An estimator: fusion_core's Python step with the recommended values (the FMU's start
    values), one sample per step."""
    from fusion_core import registry

    acc = np.column_stack([inputs[f"acc_{a}"][:n] for a in "xyz"])
    gyro = np.column_stack([inputs[f"gyro_{a}"][:n] for a in "xyz"])
    out = registry.create(key).run(acc, gyro, inputs["dt"][:n], backend="python")
    columns: dict[str, np.ndarray] = {"roll": out["roll"], "pitch": out["pitch"],
                                      "invalid_samples": np.cumsum(out["rejected"])}
    for vector in ("bias", "pos", "vel"):
        if vector in out:
            for i, a in enumerate("xyz"):
                columns[f"{vector}_{a}"] = out[vector][:, i]
    names = _outputs(md)
    start = dict(zip(names, _start_row(md, names), strict=True))
    return {name: np.concatenate(([start[name]], columns[name])) for name in names}


# ----- the files ---------------------------------------------------------------------------------

def write_csv(path: Path, columns: dict[str, np.ndarray]) -> None:
    """A cross-check CSV: time first, one column per variable, full precision."""
    names = list(columns)
    table = np.column_stack([_times(len(columns[names[0]]) - 1), *(columns[n] for n in names)])
    np.savetxt(path, table, delimiter=",", header=",".join(["time", *names]), comments="",
               fmt="%.17g")


def read_csv(path: Path) -> np.ndarray:
    return np.genfromtxt(path, delimiter=",", names=True, deletechars="")


def _readme(model: str, version: str, md: Any) -> str:
    return (f"# {model}\n\n{md.description}\n\nExported by {TOOL} {version} (native, "
            f"FMI {md.fmiVersion} co-simulation, from the C twin of fusion_core). The reference "
            f"`{model}_ref.csv` is fusion_core's Python reference over {DURATION:g} s at "
            f"{STEP:g} s steps, one IMU sample per step; `{model}_in.csv` holds the inputs "
            "(for the sensor the plant's reference, for the estimators the sensor's).\n")


def check_model(model: str, kind: str, fmu: Path, root: Path,
                inputs: dict[str, np.ndarray] | None, ref: dict[str, np.ndarray]) -> Checked:
    """Lay out one FMU with its reference, simulate it with fmpy, compare, write the result."""
    import fmpy
    from fmpy import simulate_fmu
    from fmpy.cross_check import validate_result

    from fmu_src.model_description import project_version

    md = _description(fmu)
    version = project_version()
    fmi = VERSIONS[kind]
    fmu_dir = root / "fmus" / fmi / "cs" / PLATFORMS[kind] / TOOL / version / model
    result_dir = (root / "results" / fmi / "cs" / PLATFORMS[kind] / IMPORTER / fmpy.__version__
                  / TOOL / version / model)
    fmu_dir.mkdir(parents=True, exist_ok=True)
    result_dir.mkdir(parents=True, exist_ok=True)
    (fmu_dir / f"{model}.fmu").write_bytes(fmu.read_bytes())
    write_csv(fmu_dir / f"{model}_ref.csv", ref)
    (fmu_dir / f"{model}_ref.opt").write_text(
        f"StepSize,{STEP!r}\nStartTime,0.0\nStopTime,{DURATION!r}\nRelTol,1e-06\n")
    (fmu_dir / "README.md").write_text(_readme(model, version, md))
    simulate: dict[str, Any] = {"stop_time": DURATION, "output_interval": STEP,
                                "output": list(ref), "fmi_type": "CoSimulation"}
    if inputs is not None:
        write_csv(fmu_dir / f"{model}_in.csv", inputs)
        simulate["input"] = read_csv(fmu_dir / f"{model}_in.csv")
    result = simulate_fmu(str(fmu_dir / f"{model}.fmu"), **simulate)
    out = result_dir / f"{model}_out.csv"
    write_csv(out, {name: result[name] for name in ref})
    command = (f"fmpy simulate {model}.fmu "
               + (f"--input-file {model}_in.csv " if inputs is not None else "")
               + f"--stop-time {DURATION:g} --output-interval {STEP:g} "
               f"--output-file {model}_out.csv")
    (result_dir / f"{model}_cc.sh").write_text(
        f"#!/bin/sh\n# run in {fmu_dir.relative_to(root)}\n{command}\n")
    problem = validate_result(result=read_csv(out),
                              reference=read_csv(fmu_dir / f"{model}_ref.csv"),
                              t_start=0.0, t_stop=DURATION)
    largest = max(float(np.max(np.abs(result[name] - ref[name]))) for name in ref)
    (result_dir / f"{model}_cc.log").write_text(
        f"fmpy {fmpy.__version__} simulated {model}.fmu ({md.fmiVersion}) on "
        f"{platform.platform()}\nvalidate_result: {problem or 'passed'}\n"
        f"largest difference from the reference over every output: {largest:.3g}\n")
    (result_dir / "README.md").write_text(
        f"# {model}\n\nImported with fmpy {fmpy.__version__} (`simulate_fmu`, co-simulation, "
        f"communication step {STEP:g} s), compared with fmpy's `validate_result`.\n")
    if problem is None:
        (result_dir / "passed").write_text("")
    return Checked(model, fmi, fmu_dir, result_dir, problem, list(ref))


def run_crosscheck(fmu_dir: Path, out: Path, log: Callable[[str], None] = print
                   ) -> tuple[list[Checked], list[str], int]:
    """Every native FMU of fmu_dir/native/<fmi2|fmi3> through the cross-check; the checks, the
    problems fmpy's tree validation found (FMI 2.0) and the number of FMUs it validated."""
    from fmpy.cross_check.validate_vendor_repo import validate_repo

    from fusion_core import registry

    checked: list[Checked] = []
    n = round(DURATION / STEP)
    for kind in ("fmi2", "fmi3"):
        folder = fmu_dir / "native" / kind
        if not (folder / "ImuPlant.fmu").is_file():
            raise FileNotFoundError(f"no native {kind} FMUs in {folder}: build them with "
                                    f"`imu-fusion build-fmus --kind native --out {fmu_dir}`")
        truth = plant_reference(_description(folder / "ImuPlant.fmu"), n)
        checked.append(check_model("ImuPlant", kind, folder / "ImuPlant.fmu", out, None, truth))
        md = _description(folder / "ImuSensor.fmu")
        sensor_inputs = {v.name: truth[v.name] for v in md.modelVariables
                         if v.causality == "input"}
        samples = sensor_reference(md, sensor_inputs, n)
        checked.append(check_model("ImuSensor", kind, folder / "ImuSensor.fmu", out,
                                   sensor_inputs, samples))
        # the sample of step k is the sensor's output at its end: the estimator reads it at k
        est_inputs = {name: np.concatenate((samples[name][1:], samples[name][-1:]))
                      for name in ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "dt")}
        for key, name in registry.FMU_NAMES.items():
            fmu = folder / f"{name}.fmu"
            ref = estimator_reference(key, _description(fmu), est_inputs, n)
            checked.append(check_model(name, kind, fmu, out, est_inputs, ref))
        for c in checked[-2 - len(registry.FMU_NAMES):]:
            log(f"  {c.version}  {c.model:<34}{'passed' if c.problem is None else c.problem}")
    fmu_count, _, problems = validate_repo(str(out))
    fmi2 = sum(c.version == "2.0" for c in checked)  # validate_repo counts the 3.0 folders too
    return checked, problems, min(fmu_count, fmi2)


def add_crosscheck_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """The crosscheck subcommand."""
    from .options import out_folder

    p = sub.add_parser("crosscheck", help="the native FMUs and their results in the FMI "
                       "Cross-Check layout, validated by fmpy",
                       description=" ".join(__doc__.split("\n\n")[0].split()))
    p.add_argument("--fmu-dir", type=Path, default=Path("dist"),
                   help="where build-fmus put the FMUs (native/fmi2 and native/fmi3 under it)")
    p.add_argument("--out", type=out_folder, default=Path("reports/crosscheck"),
                   help="the cross-check tree (fmus/ and results/)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Lay out, simulate, compare, validate; exit status 1 on any problem."""
    print(f"cross-check of the native FMUs in {args.fmu_dir} into {args.out} "
          f"({DURATION:g} s at {STEP:g} s, fmpy simulating, fusion_core the reference)")
    checked, problems, fmu_count = run_crosscheck(args.fmu_dir, args.out)
    failed = [c for c in checked if c.problem is not None]
    print(f"fmpy validate_repo: {len(problems)} problems in the FMI 2.0 tree ({fmu_count} FMUs "
          "and their results; it reads FMI 1.0 and 2.0 trees only, so the FMI 3.0 FMUs were "
          "compared with validate_result alone)")
    for problem in problems:
        print(f"  {problem}")
    print(f"results: {len(checked) - len(failed)} of {len(checked)} passed")
    print("command: imu-fusion " + " ".join(shlex.quote(a) for a in sys.argv[1:]))
    return 1 if problems or failed else 0
