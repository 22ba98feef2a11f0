"""``handsynth build-db`` on the real command: builds, resumes after SIGKILL, refuses bad options."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
from click.testing import CliRunner

from handsynth.cli._main import cli
from handsynth.db import build_databases, database_path, open_database, verify
from handsynth.errors import DatabaseError
from handsynth.models import HandShape

SMALL = ["--count", "150", "--render-size", "120x80", "--seed", "2"]


def _run(*args):
    return CliRunner().invoke(cli, ["build-db", *args], catch_exceptions=False)


def test_build_db_writes_databases_that_open(tmp_path):
    shapes = "standard,L1.050_W0.900_P1.000_T1.100"
    res = _run("--out", str(tmp_path), "--shapes", shapes, "--workers", "1", *SMALL)
    assert res.exit_code == 0, res.output
    assert "2 built" in res.output
    for shape in (HandShape(), HandShape(length=1.05, width=0.9, thumb=1.1)):
        db = open_database(database_path(tmp_path, shape))
        assert len(db) == 150
        assert db.meta["shape_name"] == shape.name
        assert db.meta["pose_set"] == {"name": "paper", "count": 150, "seed": 2}
        assert db.meta["features"]["render_size"] == [120, 80]
    again = _run("--out", str(tmp_path), "--shapes", shapes, "--workers", "1", *SMALL)
    assert "0 built, 2 verified and kept" in again.output


def test_progress_line_is_one_carriage_return_updated_line(tmp_path):
    res = CliRunner().invoke(cli, ["build-db", "--out", str(tmp_path), "--shapes", "standard",
                                   "--workers", "1", *SMALL], catch_exceptions=False)
    assert res.exit_code == 0
    err = res.stderr
    assert err.count("\n") == 1 and err.endswith("\n")
    assert err.count("\r") >= 2
    last = err.rsplit("\r", 1)[-1]
    assert "100.0%" in last and "150/150 entries" in last and "ETA" in last and "entries/s" in last


def test_default_database(tmp_path):
    t = time.perf_counter()
    res = _run("--out", str(tmp_path), "--default", "-q")
    assert res.exit_code == 0, res.output
    assert time.perf_counter() - t < 30
    db = open_database(database_path(tmp_path, HandShape()))
    assert len(db) == 3000 and db.meta["pose_set"]["name"] == "paper"


@pytest.mark.parametrize("args, word", [
    (["--shapes", "L1.0_bogus"], "L1.0_bogus"),
    (["--render-size", "120"], "--render-size"),
    (["--workers", "0"], "--workers"),
    (["--count", "0"], "count"),
    (["--seed", "-3"], "seed"),
])
def test_bad_options_give_one_line_errors(tmp_path, args, word):
    res = _run("--out", str(tmp_path), *args)
    assert res.exit_code == 2
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("handsynth: error:") and word in lines[0]


def test_killed_build_resumes_to_the_same_bytes(tmp_path):
    shapes = [HandShape(), HandShape(length=0.95), HandShape(width=1.1), HandShape(palm=1.05)]
    opts = {"count": 600, "render_size": (120, 80), "seed": 5}
    killed, clean = tmp_path / "killed", tmp_path / "clean"
    cmd = [sys.executable, "-c", "from handsynth.cli import main; main()", "build-db", "-q",
           "--out", str(killed), "--shapes", ",".join(s.name for s in shapes), "--workers", "1",
           "--count", "600", "--render-size", "120x80", "--seed", "5"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    first = database_path(killed, shapes[0])
    deadline = time.monotonic() + 60
    while not first.exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.01)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the build finished before it could be killed"
    finished = sorted(killed.glob("*.h5"))
    assert first in finished and len(finished) < len(shapes)
    build_databases(clean, shapes, workers=1, **opts)
    # nothing a reader accepts is incomplete: every accepted file is the finished one
    for path in killed.iterdir():
        try:
            verify(path)
        except DatabaseError:
            assert ".tmp-" in path.name or path.suffix != ".h5"
            continue
        assert path.read_bytes() == (clean / path.name).read_bytes()
    res = _run("--out", str(killed), "--shapes", ",".join(s.name for s in shapes),
               "--workers", "1", "-q", "--count", "600", "--render-size", "120x80", "--seed", "5")
    assert res.exit_code == 0, res.output
    assert f"{len(finished)} verified and kept" in res.output
    assert sorted(p.name for p in killed.iterdir()) == sorted(p.name for p in clean.iterdir())
    for path in clean.iterdir():
        assert (killed / path.name).read_bytes() == path.read_bytes()
