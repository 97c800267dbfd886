"""One side of an FMU state's trip between processes (tests/test_fmu_state_processes.py).

    python fmu_state_processes.py save JOBS.json      # run, save states, record what follows
    python fmu_state_processes.py restore JOBS.json   # restore each state, record what follows

Each job names an FMU, its parameters (set in initialisation mode), the samples, and the steps
after which a state is serialized. `save` runs the whole recording, writes each state's bytes to
STATE_DIR/<job>-<step>.bin and the outputs after every step to <job>.save.json; `restore`, in a
new process, instantiates the FMU with its start values only (the state carries the
parameters), deserializes and sets each state in turn, steps on to the end and writes the
outputs after every step to <job>.restore.json.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

from native_fmu import NativeFmu

from fmu_src.variables import item_value


def _value(fmu: NativeFmu, name: str, value: Any) -> Any:
    """A parameter value as the FMU takes it: a choice's item as its 1-based value."""
    return item_value(fmu.vars[name], value) if isinstance(value, str) else value


def _outputs(fmu: NativeFmu) -> list[float]:
    """Every output: the Real ones in one call, then the others."""
    outputs = [n for n, v in fmu.vars.items() if v.causality == "output"]
    real = [n for n in outputs if fmu.vars[n].type in ("Real", "Float64")]
    return fmu.get_reals(real) + [float(fmu.get(n)) for n in outputs if n not in real]


def _step(fmu: NativeFmu, job: dict[str, Any], k: int) -> None:
    fmu.step(0.01 * k, 0.01, **{name: values[k] for name, values in job["inputs"].items()})


def save(job: dict[str, Any], folder: Path) -> None:
    fmu = NativeFmu(Path(job["fmu"]), instance="saving")
    fmu.instantiate()
    fmu.start(**{k: _value(fmu, k, v) for k, v in job["params"].items()})
    outputs = []
    for k in range(job["steps"]):
        _step(fmu, job, k)
        outputs.append(_outputs(fmu))
        if k in job["save_at"]:
            blob = fmu.serialize(fmu.save())
            (folder / f"{job['name']}-{k}.bin").write_bytes(blob)
    (folder / f"{job['name']}.save.json").write_text(json.dumps(outputs))
    fmu.terminate()
    fmu.free()


def restore(job: dict[str, Any], folder: Path) -> None:
    fmu = NativeFmu(Path(job["fmu"]), instance="restoring")
    fmu.instantiate()
    fmu.start()
    runs = {}
    for at in job["save_at"]:
        try:
            fmu.restore(fmu.deserialize((folder / f"{job['name']}-{at}.bin").read_bytes()))
        except Exception:
            errors = [text for status, text in fmu.log if status >= 3]
            print(f"{job['name']}, state of step {at}: {errors[-1:]}", file=sys.stderr)
            raise
        outputs = []
        for k in range(at + 1, job["steps"]):
            _step(fmu, job, k)
            outputs.append(_outputs(fmu))
        runs[str(at)] = outputs
    (folder / f"{job['name']}.restore.json").write_text(json.dumps(runs))
    fmu.terminate()
    fmu.free()


def main(argv: list[str]) -> int:
    mode, jobs_file = argv
    jobs = json.loads(Path(jobs_file).read_text())
    folder = Path(jobs_file).parent
    for job in jobs:
        (save if mode == "save" else restore)(job, folder)
    return 0


if __name__ == "__main__":
    status = main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.flush()
    # Every result is written: leave without the exit handlers, where pythonfmu 0.7's wrapper
    # reads a static object its own destructor freed (valgrind: finalizePythonInterpreter, an
    # ELF destructor, reads a block freed in exit()), which now and then aborts the process
    # after its work is done (docs/guide/modelica-simulink.md, "Known pythonfmu 0.7 defect").
    # The native FMUs have no such defect; this helper runs both kinds.
    os._exit(status)
