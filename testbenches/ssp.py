"""SSP export: the three FMUs of a testbench and their connections as one SSP file (SSP 1.0),
which the co-simulation engines users run load as exported (libcosim, Ecos, fmu-manipulation-
toolbox's fmucontainer; fmpy's SSP master too).

`export_ssp` writes SystemStructure.ssd (components plant, sensor, estimator; the plant's truth
wired to the sensor's inputs, the sensor's samples to the estimator's inputs), the FMUs under
resources/ (the native FMI 2.0 or 3.0 FMUs by default, the pythonfmu FMUs on request) and each
component's parameters as resources/<component>.ssv, bound to that component in a parameter
set named PARAMETER_SET. Why so:
- libcosim and Ecos apply component-level bindings only (a system-level one, names
  component.variable, they ignore without a word);
- Ecos applies the parameter sets of the name its init is given, so every component's set has
  the same name;
- neither loads a connection to a connector of the system itself (SSP 1.0 allows one, with
  no endElement), so the system has no connectors: a host reads the components' outputs
  (container.container_from_ssp exposes the estimator's as the container's outputs).
A choice parameter is an Integer (its item's value, 1..n).

Alignment. Every engine that runs an SSP is a Jacobi master: each FMU steps on the values the
connections carried at the previous communication point, so the estimator's output after the
step at t is the estimate of the sample of the truth at t - h (master.CHAIN_DELAY, 2 steps).
libcosim and Ecos pass the FMUs' outputs after initialisation on first: the plant's truth at the
start and the sensor's start values, whose dt = 0 the estimator refuses. fmpy's SSP master
starts its connectors at 0 instead: the first sample is refused (dt = 0) and the second, a
sample of no force, initialises nothing.
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
PARAMETER_SET = "testbench"
"""The name of every component's parameter set (Ecos: `init(parameter_set=PARAMETER_SET)`)."""
SSP_KINDS = ("native", "pythonfmu")
"""Which FMUs an SSP packs: the native ones (FMI 2.0 or 3.0, nothing needed in the host) or
the pythonfmu ones (FMI 2.0, a Python with numpy in the host)."""
SSC_TYPE = {"Real": "ssc:Real", "Float64": "ssc:Real", "Integer": "ssc:Integer",
            "Int32": "ssc:Integer", "Int64": "ssc:Integer", "Boolean": "ssc:Boolean"}
"""The SSP connector type of each FMI 2.0 and 3.0 variable type the FMUs have."""


def _connector(name: str, kind: str, fmi_type: str) -> str:
    return (f'<ssd:Connector name={quoteattr(name)} kind="{kind}"><{SSC_TYPE[fmi_type]}/>'
            "</ssd:Connector>")


def _connectors(path: Path, bound: set[str]) -> str:
    """A component's connectors: its inputs and outputs, and the parameters bound to it."""
    md = read_model_description(str(path))
    rows = [_connector(v.name, v.causality, v.type) for v in md.modelVariables
            if v.causality in ("input", "output") or (v.causality == "parameter"
                                                      and v.name in bound)]
    return "\n          ".join(rows)


def _ssv(name: str, params: dict[str, Any]) -> str:
    """A parameter set called name holding params (names of the component's variables)."""
    rows = []
    for key, value in params.items():
        if isinstance(value, bool):
            entry = f'<ssv:Boolean value="{str(value).lower()}"/>'
        elif isinstance(value, int):
            entry = f'<ssv:Integer value="{value}"/>'
        else:
            entry = f'<ssv:Real value="{float(value)!r}"/>'
        rows.append(f"<ssv:Parameter name={quoteattr(key)}>{entry}</ssv:Parameter>")
    body = "\n    ".join(rows)
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n<ssv:ParameterSet {NS} version="1.0" '
            f"name={quoteattr(name)}>\n  <ssv:Parameters>\n    {body}\n  </ssv:Parameters>\n"
            "</ssv:ParameterSet>\n")


def _item(choices: dict[str, tuple[str, ...] | None], name: str, value: Any) -> Any:
    """A choice parameter's item name as its value 1..n; other values as they are."""
    items = choices.get(name)
    return items.index(value) + 1 if items and isinstance(value, str) else value


def ssp_fmus(estimator: str, fmu_dir: Path | str, kind: str = "native", fmi: int = 2
             ) -> dict[str, Path]:
    """The three FMUs an SSP of `estimator` packs, by component name."""
    if kind not in SSP_KINDS:
        raise ValueError(f"FMU kind {kind!r}: allowed {', '.join(SSP_KINDS)}")
    if fmi not in (2, 3) or (kind == "pythonfmu" and fmi != 2):
        raise ValueError(f"FMI {fmi}: the native FMUs are FMI 2 or 3, the pythonfmu ones FMI 2")
    folder = Path(fmu_dir) / "native" / f"fmi{fmi}" if kind == "native" else Path(fmu_dir)
    names = {"plant": PLANT_FMU, "sensor": SENSOR_FMU, "estimator": ESTIMATOR_FMUS[estimator]}
    missing = [n for n in names.values() if not (folder / f"{n}.fmu").is_file()]
    if missing:
        raise FileNotFoundError(
            f"no {kind} FMU {', '.join(missing)} in {folder}: build them first (python "
            f"build_fmu.py --out {fmu_dir}{' --kind pythonfmu' if kind == 'pythonfmu' else ''})")
    return {c: fmu_path(n, folder) for c, n in names.items()}


def export_ssp(
    estimator: str,
    scenario: str | int,
    out: Path | str,
    seed: int = 0,
    params: dict[str, Any] | None = None,
    sensor_params: dict[str, Any] | None = None,
    fmu_dir: Path | str = DEFAULT_FMU_DIR,
    kind: str = "native",
    fmi: int = 2,
) -> Path:
    """Write plant + sensor + estimator FMUs, their connections and each component's
    parameters (the scenario, the sensor's seed and parameters, the estimator's) as an SSP."""
    if estimator not in ESTIMATOR_FMUS:
        raise ValueError(f"unknown estimator {estimator!r}: allowed {', '.join(ESTIMATOR_FMUS)}")
    sc = get_scenario(scenario)
    paths = ssp_fmus(estimator, fmu_dir, kind, fmi)
    sensor_choices = {p.name: p.choices for p in SENSOR_PARAMS if p.choices}
    est_choices = {p.name: p.choices for p in ESTIMATORS[estimator].param_specs().values()
                   if p.choices}
    values: dict[str, dict[str, Any]] = {
        "plant": {"scenario": sc.id},
        # every engine that runs an SSP steps Jacobi: the sensor's inputs hold at a step's
        # start (container.container_from_ssp sets it per container)
        "sensor": {"seed": seed, "inputs_at": 2, **{k: _item(sensor_choices, k, v)
                                                    for k, v in (sensor_params or {}).items()}},
        "estimator": {k: _item(est_choices, k, v) for k, v in (params or {}).items()},
    }
    components = "\n      ".join(_component(c, paths[c], values[c]) for c in paths)
    wires = [("plant", n, "sensor", n) for n in SENSOR_IN]
    wires += [("sensor", n, "estimator", n) for n in SAMPLE]
    lines = [f'<ssd:Connection startElement="{a}" startConnector="{b}" endElement="{c}" '
             f'endConnector="{d}"/>' for a, b, c, d in wires]
    ssd = f"""<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription {NS} version="1.0" name="{ESTIMATOR_FMUS[estimator]}_{sc.name}">
  <ssd:System name="testbench">
    <ssd:Elements>
      {components}
    </ssd:Elements>
    <ssd:Connections>
      {chr(10).join("      " + r for r in lines).lstrip()}
    </ssd:Connections>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0.0" stopTime="{sc.duration!r}"/>
</ssd:SystemStructureDescription>
"""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", ssd)
        for c, p in paths.items():
            z.writestr(f"resources/{c}.ssv", _ssv(PARAMETER_SET, values[c]))
            z.write(p, f"resources/{p.name}")
    return out


def _component(name: str, path: Path, values: dict[str, Any]) -> str:
    binding = (f'\n        <ssd:ParameterBindings>\n          <ssd:ParameterBinding '
               f'source="resources/{name}.ssv"/>\n        </ssd:ParameterBindings>'
               if values else "")
    return (f'<ssd:Component name="{name}" type="application/x-fmu-sharedlibrary" '
            f'source="resources/{path.name}">\n        <ssd:Connectors>\n          '
            f"{_connectors(path, set(values))}\n        </ssd:Connectors>{binding}\n"
            "      </ssd:Component>")


def simulate(ssp: Path | str, stop_time: float, step_size: float = 0.01) -> Any:
    """Run an exported SSP with fmpy's SSP master, each component's parameter set applied
    (fmpy applies a set whose names are component.variable)."""
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import read_ssv

    parameters = None
    for component in ("plant", "sensor", "estimator"):
        try:
            own = read_ssv(str(ssp), resource=f"resources/{component}.ssv")
        except KeyError:
            continue
        for p in own.parameters:
            p.name = f"{component}.{p.name}"
        if parameters is None:
            parameters = own
        else:
            parameters.parameters += own.parameters
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
    ssp.add_argument("--kind", choices=SSP_KINDS, default="native",
                     help="the FMUs it packs: native (nothing needed in the host; default) or "
                     "pythonfmu (FMI 2 only)")
    ssp.add_argument("--fmi", type=int, choices=(2, 3), default=2,
                     help="FMI version of the native FMUs (2)")
    ssp.add_argument("--container", choices=("sequential", "parallel"),
                     help="also build OUT with .fmu for .ssp: one FMU holding the three "
                     "(fmu-manipulation-toolbox's fmucontainer), stepping them sequential "
                     "(Gauss-Seidel) or parallel (Jacobi)")
    ssp.add_argument("out", type=Path, help="the SSP file to write")
    ssp.set_defaults(func=cmd_export_ssp)


def cmd_export_ssp(args: argparse.Namespace) -> int:
    from .contract import NOISE_FREE

    path = export_ssp(args.estimator, args.scenario, args.out, args.seed,
                      parse_params(args.param), NOISE_FREE if args.noise_free else None,
                      args.fmu_dir, args.kind, args.fmi)
    print(f"wrote {path}")
    if args.container:
        from .container import container_from_ssp

        fmu = container_from_ssp(path, path.with_suffix(".fmu"),
                                 sequential=args.container == "sequential", fmi=args.fmi)
        print(f"wrote {fmu} ({args.container} container)")
    return 0
