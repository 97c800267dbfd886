"""MkDocs hook: `<!-- params: KEY -->` in a page becomes the table of that estimator's own
parameters (`<!-- params: input -->`: the input stage's, which every estimator shares), read
from its class when the site is built (so the table is never stale), and the
navigation's Estimators section lists every estimator of the registry, estimators/<key>.md
after the overview (titled by the page's heading)."""

from __future__ import annotations

import re
from typing import Any

MARK = re.compile(r"<!-- params: (\w+) -->")


def _cell(text: Any) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _range(spec: Any) -> str:
    if spec.choices:
        return ", ".join(f"`{c}`" for c in spec.choices)
    if spec.low is None or spec.high is None:
        return ""
    left = "(" if spec.low_open else "["
    right = ")" if spec.high_open else "]"
    return f"{left}{spec.low:g}, {spec.high:g}{right}"


def params_table(key: str) -> str:
    """The markdown table of estimator key's own parameters (the recommended class's PARAMS),
    or for "input" those of the input stage every estimator shares (base.COMMON_PARAMS)."""
    from fusion_core import registry
    from fusion_core.base import COMMON_PARAMS

    specs = COMMON_PARAMS if key == "input" else registry.estimator_class(key).PARAMS
    rows = ["| parameter | default | unit | allowed | description |", "|---|---|---|---|---|"]
    for spec in specs:
        name = spec.name
        default = f"{spec.default:.6g}" if isinstance(spec.default, float) else repr(spec.default)
        rows.append(f"| `{name}` | `{_cell(default)}` | {_cell(spec.unit or '')} | "
                    f"{_cell(_range(spec))} | {_cell(spec.description or '')} |")
    return "\n".join(rows)


def on_config(config: Any, **_: Any) -> Any:
    """Every registry estimator's page in the Estimators section of the navigation."""
    from fusion_core.registry import KEYS

    for section in config["nav"] or []:
        if isinstance(section, dict) and "Estimators" in section:
            pages = section["Estimators"]
            listed = {p if isinstance(p, str) else next(iter(p.values())) for p in pages}
            pages += [f"estimators/{key}.md" for key in KEYS
                      if f"estimators/{key}.md" not in listed]
    return config


def on_page_markdown(markdown: str, **_: Any) -> str:
    return MARK.sub(lambda m: params_table(m.group(1)), markdown)
