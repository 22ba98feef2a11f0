"""The root command: one error style for every bad option, no silently missing command."""

import subprocess
import sys

import pytest
from click.testing import CliRunner

from handsynth.cli import _main
from handsynth.cli._main import COMMAND_MODULES, cli


def _run(*args):
    return CliRunner().invoke(cli, list(args), prog_name="handsynth")


def _one_error_line(res, *words):
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1, res.output
    assert lines[0].startswith("handsynth: error: ")
    for w in words:
        assert w in lines[0]
    assert "Traceback" not in res.output and "Usage:" not in res.output


@pytest.mark.parametrize("args, words", [
    (("nosuch",), ["No such command", "'nosuch'"]),
    (("build-db", "--count", "abc"), ["handsynth build-db", "--count", "'abc'"]),
    (("build-db", "--no-such-option"), ["--no-such-option"]),
    (("estimate", "--fps", "fast"), ["handsynth estimate", "--fps"]),
    (("joints", "estimate"), ["handsynth joints estimate", "RECORDING"]),
    (("eval", "--hand", "robot"), ["--hand", "robot"]),
])
def test_bad_options_give_one_error_line(args, words):
    _one_error_line(_run(*args), *words)


def test_library_errors_use_the_same_line(tmp_path):
    missing = tmp_path / "none.csv"
    _one_error_line(_run("joints", "estimate", str(missing)), "none.csv")


def test_every_command_module_registers_a_command():
    assert len(cli.commands) >= len(COMMAND_MODULES)
    names = set(cli.commands)
    for mod in COMMAND_MODULES:
        assert mod.replace("_", "-") in names


def test_a_missing_command_module_is_an_import_error(monkeypatch):
    monkeypatch.setattr(_main, "COMMAND_MODULES", (*COMMAND_MODULES, "renamed_away"))
    with pytest.raises(ModuleNotFoundError, match="renamed_away"):
        _main._register()


def test_help_and_version_exit_zero():
    assert _run("--help").exit_code == 0
    res = _run("--version")
    assert res.exit_code == 0 and "version" in res.output


@pytest.mark.parametrize("message, renamed", [
    ("ProtocolOptions.frames must be an integer >= 2, got 1", "--frames must be an integer >= 2, got 1"),
    ("EvalOptions.count (--count) must be an integer >= 1, got 0",
     "--count must be an integer >= 1, got 0"),
    ("count must be at most 5,000,000 poses", "--count must be at most 5,000,000 poses"),
    ("count: bad", "--count: bad"),
    ("counts must be", None),                   # a whole name only
    ("the count must be", None),                # at the start only
    ("ProtocolOptions.frames_x must be", None),
])
def test_a_library_name_at_the_start_of_a_message_becomes_the_option(message, renamed):
    names = {"ProtocolOptions.frames": "--frames", "EvalOptions.count": "--count", "count": "--count"}
    assert _main.renamed_message(message, names) == renamed


def test_a_command_with_option_names_names_the_option_the_user_typed():
    import click

    from handsynth.errors import InvalidInputError, InvalidShapeError

    @cli.command("test-option-names")
    @click.option("--points", type=int)
    @_main.option_names({"SomethingOptions.n_points": "--points"})
    def command(points):
        if points < 0:
            raise InvalidShapeError(f"SomethingOptions.n_points must be >= 0, got {points}")
        raise InvalidInputError(f"something else named SomethingOptions.n_points, got {points}")

    try:
        res = _run("test-option-names", "--points", "-1")
        _one_error_line(res, "handsynth: error: --points must be >= 0, got -1")
        res = _run("test-option-names", "--points", "2")  # not at the start: left as it was
        _one_error_line(res, "something else named SomethingOptions.n_points, got 2")
    finally:
        cli.commands.pop("test-option-names")


def test_the_entry_point_loads_nothing_heavy_before_main():
    # Ctrl-C can only be turned into one line once main() runs: before it, nothing big loads
    code = ("import sys, handsynth.cli; "
            "print(sorted(m for m in ('numpy', 'mujoco', 'cv2', 'click') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


def test_ctrl_c_while_the_commands_load_is_one_line():
    # the KeyboardInterrupt a Ctrl-C raises, injected where the commands' imports begin
    code = ("import builtins\n"
            "real = builtins.__import__\n"
            "def fake(name, *a, **k):\n"
            "    if name == 'click':\n"
            "        raise KeyboardInterrupt\n"
            "    return real(name, *a, **k)\n"
            "builtins.__import__ = fake\n"
            "from handsynth.cli import main\n"
            "main(['--version'])\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 1
    assert proc.stderr.strip() == "handsynth: error: aborted", proc.stderr
    assert proc.stdout == ""


def test_the_package_names_load_when_used():
    code = ("import sys, handsynth; before = 'mujoco' in sys.modules; "
            "shape = handsynth.HandShape(); "
            "print(before, type(shape).__name__, 'PoseLookup' in dir(handsynth))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "HandShape", "True"], out.stdout + out.stderr
    with pytest.raises(AttributeError, match="no attribute 'PoseLookups'"):
        import handsynth
        handsynth.PoseLookups  # noqa: B018


def test_python_m_handsynth_runs_the_command_line():
    res = subprocess.run([sys.executable, "-m", "handsynth", "--version"], capture_output=True,
                         text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.startswith("handsynth, version ")
