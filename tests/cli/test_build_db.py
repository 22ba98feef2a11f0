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
    res = _run("--out", str(tmp_path), "--default", "-q")
    assert res.exit_code == 0, res.output
    assert "warning" not in res.output
    db = open_database(database_path(tmp_path, HandShape()))
    assert len(db) == 3000 and db.meta["pose_set"]["name"] == "paper"


def test_the_default_database_says_which_file_it_replaces(tmp_path):
    # another database of the standard hand (here 150 small poses; the documented 20,448) shares
    # the default's file name; --default replaced it without a word
    assert _run("--out", str(tmp_path), "--shapes", "standard", "--workers", "1", "-q",
                *SMALL).exit_code == 0
    res = _run("--out", str(tmp_path), "--default", "-q")
    assert res.exit_code == 0, res.output
    warning = [line for line in res.output.splitlines() if "warning" in line]
    assert len(warning) == 1 and "built again, replacing an existing file" in warning[0]
    assert "in the file but" in warning[0] and "is expected" in warning[0]
    again = _run("--out", str(tmp_path), "--default", "-q")
    assert again.exit_code == 0 and "warning" not in again.output


@pytest.mark.parametrize("args, word", [
    (["--shapes", "L1.0_bogus"], "L1.0_bogus"),
    (["--render-size", "120"], "--render-size"),
    (["--workers", "0"], "--workers"),
    (["--count", "0"], "--count must be an integer >= 1, got 0"),
    (["--seed", "-3"], "--seed must be an integer >= 0, got -3"),
    (["--render-size", "8x8"], "--render-size must be (width, height)"),
    (["--render-size", ""], "--render-size must be WIDTHxHEIGHT"),  # was: the default size
    (["--shapes", "standard,standard"], "--shapes must be distinct"),
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


# --------------------------------------------------------------------------- faults (issue 16)

_CLI = [sys.executable, "-c", "from handsynth.cli import main; main()"]


def _bare_env():
    env = dict(os.environ)
    env.pop("MUJOCO_GL", None)  # as in a user's shell
    return env


def test_a_damaged_file_is_rebuilt_not_a_crash(tmp_path):
    # item 2: a zero-filled tail made every rerun crash instead of rebuilding
    args = ["--out", str(tmp_path), "--shapes", "standard", "--workers", "1", "-q", *SMALL]
    assert _run(*args).exit_code == 0
    path = database_path(tmp_path, HandShape())
    good = path.read_bytes()
    path.write_bytes(good[: len(good) // 2] + bytes(len(good) - len(good) // 2))
    res = _run(*args)
    assert res.exit_code == 0, res.output
    assert "rebuilt L1.000_W1.000_P1.000_T1.000" in res.output and "file checksum" in res.output
    assert path.read_bytes() == good


def test_a_full_disk_is_one_error_line_not_a_segfault(full_disk):
    # item 3: exit 139 (h5py raised RuntimeError on the full disk, then crashed)
    res = subprocess.run([*_CLI, "build-db", "--out", str(full_disk), "--shapes", "standard",
                          "--count", "3000", "--workers", "1", "-q"], capture_output=True,
                         text=True, env=_bare_env(), timeout=120)
    assert res.returncode == 2, res.stderr[-3000:]
    assert res.stderr.count("\n") == 1 and "Traceback" not in res.stderr
    assert res.stderr.startswith("handsynth: error: cannot write the database")
    assert "no space left" in res.stderr
    assert [p.name for p in full_disk.iterdir()] == [".handsynth-build.lock"]


def test_a_read_only_folder_names_the_real_reason(read_only_folder):
    # item 4: the cleanup's unlink raised and hid the real error
    res = _run("--out", str(read_only_folder), "--shapes", "standard", "--workers", "1", *SMALL)
    assert res.exit_code == 2
    assert "read-only" in res.output and "Traceback" not in res.output


@pytest.mark.parametrize("args, word", [
    (["--count", "1000000000"], "--count must be at most 5,000,000"),
    (["--workers", "4096"], "--workers must be at most the"),
])
def test_upper_bounds_are_clear_errors(tmp_path, args, word):
    # item 16: a memory-error traceback, and 29 processes on 2 cores
    res = _run("--out", str(tmp_path), "--shapes", "standard", *args)
    assert res.exit_code == 2 and word in res.output, res.output
    assert not list(tmp_path.glob("*.h5"))


def _children(pid: int) -> list[int]:
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                out.append(int(entry))
    return out


def _running(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _start_build(folder, *extra, **popen):
    cmd = [*_CLI, "build-db", "-q", "--out", str(folder), "--shapes", "standard,L1.100_W1.000_P1.000_T1.000",
           "--workers", "2", "--count", "20000", "--render-size", "120x80", *extra]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=_bare_env(), **popen)
    deadline = time.monotonic() + 60
    while len(_children(proc.pid)) < 3 and time.monotonic() < deadline:  # 2 workers + tracker
        time.sleep(0.02)
    return proc


@pytest.mark.slow
def test_killing_the_parent_ends_the_workers(tmp_path):
    # item 5: SIGKILL of the build-db parent left its workers and the resource tracker running
    proc = _start_build(tmp_path)
    children = _children(proc.pid)
    assert len(children) >= 2, "the workers did not start"
    time.sleep(0.5)
    proc.kill()
    proc.communicate()
    deadline = time.monotonic() + 10
    while any(_running(c) for c in children) and time.monotonic() < deadline:
        time.sleep(0.05)
    alive = [c for c in children if _running(c)]
    for c in alive:
        os.kill(c, signal.SIGKILL)
    assert alive == []


@pytest.mark.slow
@pytest.mark.parametrize("delay_s", [0.2, 0.5, 0.9])
def test_ctrl_c_during_start_up_is_one_line(tmp_path, delay_s):
    # item 18: Ctrl-C while the workers start (importing their modules) printed
    # interleaved tracebacks
    # the default Ctrl-C action, even when this test runs in a background job (which ignores it)
    proc = _start_build(tmp_path, start_new_session=True,
                        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(delay_s)
    os.killpg(proc.pid, signal.SIGINT)  # as a terminal does: the whole process group
    _, err = proc.communicate(timeout=60)
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err[-3000:]
    assert err.strip() == "handsynth: error: aborted"
    assert proc.returncode == 1


@pytest.mark.slow
def test_a_second_build_of_the_same_folder_is_refused(tmp_path):
    # item 17: two runs with different parameters both reported success
    first = _start_build(tmp_path)
    try:
        res = _run("--out", str(tmp_path), "--shapes", "standard", "--workers", "1", *SMALL)
        assert res.exit_code == 2
        assert "is in use by another build" in res.output and f"pid {first.pid}" in res.output
    finally:
        first.kill()
        first.communicate()


def test_help_states_the_default_render_size():
    from handsynth.db import DEFAULT_RENDER_SIZE

    res = CliRunner().invoke(cli, ["build-db", "--help"])
    assert res.exit_code == 0
    w, h = DEFAULT_RENDER_SIZE
    assert f"[default: {w}x{h}]" in " ".join(res.output.split())


def test_an_empty_out_folder_is_refused_not_the_current_folder(tmp_path, monkeypatch):
    # before: --out '' built every database into the current folder
    monkeypatch.chdir(tmp_path)
    res = _run("--out", "", "--shapes", "standard", "--count", "3")
    assert res.exit_code == 2 and res.output == "handsynth: error: --out must name a folder, got ''\n"
    assert list(tmp_path.iterdir()) == []
