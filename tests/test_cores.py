"""The cores this process may use: the default count of workers everywhere."""

import os

import pytest

from handsynth._cores import usable_cores
from handsynth.db import build_databases, learning_workers
from handsynth.errors import InvalidInputError
from handsynth.models import HandShape
from handsynth.render import CameraMount


def test_the_affinity_not_the_machine_counts(monkeypatch):
    # a container's cpuset leaves this process 3 of the machine's 64 cores
    monkeypatch.setattr(os, "cpu_count", lambda: 64)
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {5, 9, 12}, raising=False)
    assert usable_cores() == 3
    assert learning_workers(4000) == 3
    with pytest.raises(InvalidInputError, match="at most the 3 CPU cores this process may use"):
        build_databases("unused", [HandShape()], CameraMount.paper(), workers=4)


def test_without_an_affinity_every_core_counts(monkeypatch):
    monkeypatch.delattr(os, "sched_getaffinity", raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 12)
    assert usable_cores() == 12
    assert learning_workers(4000) == 8  # at most 8 render learning sets
    monkeypatch.setattr(os, "cpu_count", lambda: None)  # unknown
    assert usable_cores() == 1
