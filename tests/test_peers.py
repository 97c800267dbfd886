"""The public filters run beside ours (testbenches.peers) are named apart from the registry's
estimators: a table or a --peers list must never show two different filters under one name."""

from __future__ import annotations

from fusion_core.registry import KEYS, REGISTRY
from testbenches.peers import AHEAD_PEERS, PEERS


def test_no_peer_has_an_estimators_name() -> None:
    names = {*PEERS, *AHEAD_PEERS}
    assert not names & set(KEYS)
    assert not {n.replace("-", "_") for n in names} & {e.cls.__name__ for e in REGISTRY}
