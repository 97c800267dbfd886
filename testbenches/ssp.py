"""SSP export: the three FMUs of a testbench and their connections as one SSP file (SSP 1.0).

`export_ssp` writes SystemStructure.ssd (components plant, sensor, estimator; the plant's truth
wired to the sensor's inputs, the sensor's samples to the estimator's inputs), the FMUs under
resources/, and the parameters as resources/parameters.ssv bound at system level (names
component.variable). `simulate` runs it with fmpy.ssp.simulation.simulate_ssp.

Alignment. fmpy's SSP master is Jacobi: every FMU steps on the values the connections carried at
the previous communication point, and connectors start at 0. So, against our Gauss-Seidel master
(docs/interface.md), the sensor sees the plant one step late and the estimator the sensor one step
late: the estimator's output in row k (labelled with the step's start time) is the master's
estimate of step k - 2. The first two samples reaching the estimator are all-zero (the connectors'
start values): the first is rejected (dt = 0; 1 invalid sample) and the second skipped (no
gravity to start from). With a noise-free sensor the shifted traces are bit-identical
(tests/test_testbench.py); with noise they differ because the sensor's first noise draw goes to
the zero sample.

fmpy 0.3.32's SSP reader sets Boolean parameters to true whatever their value and does not map
enumeration item names; export only Real and Integer parameters for it (other tools read the SSV
as the standard says).
"""

from __future__ import annotations

import argparse
import zipfile
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

from fmpy import read_model_description

from fusion_core import ESTIMATORS
from fusion_core.scenarios import SCENARIOS, get_scenario
from fusion_core.sensor import SENSOR_PARAMS

from .fmus import DEFAULT_FMU_DIR, ESTIMATOR_FMUS, PLANT_FMU, SENSOR_FMU, fmu_path
from .master import SAMPLE, SENSOR_IN
from .options import parse_params

NS = (
    'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
    'xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
    'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"'
)


def _connectors(path: Path) -> str:
    md = read_model_description(str(path))
    rows = []
    for v in md.modelVariables:
        if v.causality in ("input", "output"):
            kind = {"Real": "ssc:Real", "Integer": "ssc:Integer", "Boolean": "ssc:Boolean"}[v.type]
            rows.append(f'<ssd:Connector name={quoteattr(v.name)} kind="{v.causality}"><{kind}/>'
                        "</ssd:Connector>")
    return "\n          ".join(rows)


def _ssv(params: dict[str, Any]) -> str:
    rows = []
    for name, value in params.items():
        if isinstance(value, bool):
            entry = f'<ssv:Boolean value="{str(value).lower()}"/>'
        elif isinstance(value, int):
            entry = f'<ssv:Integer value="{value}"/>'
        elif isinstance(value, float):
            entry = f'<ssv:Real value="{value!r}"/>'
        else:
            entry = f"<ssv:Enumeration value={quoteattr(str(value))}/>"
        rows.append(f"<ssv:Parameter name={quoteattr(name)}>{entry}</ssv:Parameter>")
    body = "\n    ".join(rows)
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssv:ParameterSet {NS} version="1.0" '
            f'name="testbench">\n  <ssv:Parameters>\n    {body}\n  </ssv:Parameters>\n'
            "</ssv:ParameterSet>\n")


def _item(choices: dict[str, tuple[str, ...] | None], name: str, value: Any) -> Any:
    """An enumeration parameter's item name as its value 1..n; other values as they are."""
    items = choices.get(name)
    return items.index(value) + 1 if items and isinstance(value, str) else value


def export_ssp(
    estimator: str,
    scenario: str | int,
    out: Path | str,
    seed: int = 0,
    params: dict[str, Any] | None = None,
    sensor_params: dict[str, Any] | None = None,
    fmu_dir: Path | str = DEFAULT_FMU_DIR,
) -> Path:
    """Write plant + sensor + estimator FMUs and their connections as an SSP file."""
    if estimator not in ESTIMATOR_FMUS:
        raise ValueError(f"unknown estimator {estimator!r}: allowed {', '.join(ESTIMATOR_FMUS)}")
    sc = get_scenario(scenario)
    names = {"plant": PLANT_FMU, "sensor": SENSOR_FMU, "estimator": ESTIMATOR_FMUS[estimator]}
    paths = {c: fmu_path(n, fmu_dir) for c, n in names.items()}
    components = "\n      ".join(
        f'<ssd:Component name="{c}" type="application/x-fmu-sharedlibrary" '
        f'source="resources/{names[c]}.fmu">\n        <ssd:Connectors>\n          '
        f"{_connectors(paths[c])}\n        </ssd:Connectors>\n      </ssd:Component>"
        for c in names
    )
    wires = [("plant", n, "sensor", n) for n in SENSOR_IN]
    wires += [("sensor", n, "estimator", n) for n in SAMPLE]
    connections = "\n      ".join(
        f'<ssd:Connection startElement="{a}" startConnector="{b}" endElement="{c}" '
        f'endConnector="{d}"/>' for a, b, c, d in wires
    )
    values: dict[str, Any] = {"plant.scenario": sc.id, "sensor.seed": seed}
    # an enumeration's item name as its value 1..n, the form an SSV parameter takes
    sensor_choices = {p.name: p.choices for p in SENSOR_PARAMS if p.choices}
    est_choices = {p.name: p.choices for p in ESTIMATORS[estimator].param_specs().values()
                   if p.choices}
    values.update({f"sensor.{k}": _item(sensor_choices, k, v)
                   for k, v in (sensor_params or {}).items()})
    values.update({f"estimator.{k}": _item(est_choices, k, v) for k, v in (params or {}).items()})
    ssd = f"""<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription {NS} version="1.0" name="{names['estimator']}_{sc.name}">
  <ssd:System name="testbench">
    <ssd:ParameterBindings>
      <ssd:ParameterBinding source="resources/parameters.ssv"/>
    </ssd:ParameterBindings>
    <ssd:Elements>
      {components}
    </ssd:Elements>
    <ssd:Connections>
      {connections}
    </ssd:Connections>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0.0" stopTime="{sc.duration!r}"/>
</ssd:SystemStructureDescription>
"""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", ssd)
        z.writestr("resources/parameters.ssv", _ssv(values))
        for c, p in paths.items():
            z.write(p, f"resources/{names[c]}.fmu")
    return out


def simulate(ssp: Path | str, stop_time: float, step_size: float = 0.01) -> Any:
    """Run an exported SSP with fmpy's SSP master, its parameter set applied."""
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import read_ssv

    parameters = read_ssv(str(ssp), resource="resources/parameters.ssv")
    return simulate_ssp(str(ssp), stop_time=stop_time, step_size=step_size,
                        parameter_set=parameters)


def add_ssp_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    ssp = sub.add_parser("export-ssp", help="write a testbench as an SSP file")
    ssp.add_argument("--estimator", required=True, choices=list(ESTIMATOR_FMUS))
    ssp.add_argument("--scenario", required=True, choices=list(SCENARIOS))
    ssp.add_argument("--seed", type=int, default=0, help="sensor noise seed (0)")
    ssp.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                     help="estimator FMU parameter (repeatable)")
    ssp.add_argument("--noise-free", action="store_true", help="a sensor without noise")
    ssp.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR, help="built FMUs (dist)")
    ssp.add_argument("out", type=Path, help="the SSP file to write")
    ssp.set_defaults(func=cmd_export_ssp)


def cmd_export_ssp(args: argparse.Namespace) -> int:
    from .contract import NOISE_FREE

    path = export_ssp(args.estimator, args.scenario, args.out, args.seed,
                      parse_params(args.param), NOISE_FREE if args.noise_free else None,
                      args.fmu_dir)
    print(f"wrote {path}")
    return 0
