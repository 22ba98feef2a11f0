"""The import contracts: the flow models -> render -> db -> estimate -> ... -> cli is one-way.

The contracts live in ``pyproject.toml`` (``[tool.importlinter]``) and are
checked with import-linter; a second check here keeps private modules and
names inside the package that owns them.
"""

import ast
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "handsynth"


def _lint_imports(cwd: Path) -> subprocess.CompletedProcess:
    code = ("import sys; from importlinter.cli import lint_imports; "
            "sys.exit(lint_imports(config_filename='pyproject.toml', no_cache=True, no_logo=True))")
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True,
                          env={"PYTHONPATH": str(cwd), "PATH": "/usr/bin:/bin"}, timeout=120)


def _copy_project(tmp_path: Path) -> Path:
    shutil.copytree(PACKAGE, tmp_path / "handsynth",
                    ignore=shutil.ignore_patterns("__pycache__", "data"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    return tmp_path


def test_the_package_keeps_its_contracts():
    res = _lint_imports(ROOT)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "broken" in res.stdout and "0 broken" in res.stdout


@pytest.mark.parametrize("module, line, contract", [
    ("handsynth/models/_upward.py", "from ..estimate import PoseLookup\n",
     "The flow of one frame"),
    ("handsynth/db/_upward.py", "from ..live import run_live\n", "The flow of one frame"),
    ("handsynth/sensors/trackers/_upward.py", "from ...render import CameraMount\n",
     "Sensor systems import only"),
    ("handsynth/sensors/imu/_upward.py", "from ..trackers import Recording\n",
     "Each sensor system stands on its own"),
])
def test_an_upward_import_breaks_a_contract(tmp_path, module, line, contract):
    project = _copy_project(tmp_path)
    (project / module).write_text(f'"""An import against the flow."""\n\n{line}')
    res = _lint_imports(project)
    assert res.returncode == 1, res.stdout + res.stderr
    broken = [ln for ln in res.stdout.splitlines() if ln.endswith("BROKEN")]
    assert len(broken) == 1 and broken[0].startswith(contract), res.stdout


def _package_of(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1])


def _private_crossings(root: Path) -> list[str]:
    """``module: import`` for each private module or name used outside its package."""
    bad = []
    for path in sorted(root.rglob("*.py")):
        pkg = _package_of(path)
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if not isinstance(node, ast.ImportFrom) or node.module == "__future__":
                continue
            if node.level:
                base = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("handsynth"):
                continue
            parts = target.split(".")
            owner = next((".".join(parts[:i]) for i, p in enumerate(parts)
                          if p.startswith("_") and i > 0), None)
            if owner is not None:
                if not (pkg + ".").startswith(owner + "."):
                    bad.append(f"{path.relative_to(ROOT)}: from {target} import ...")
                continue  # a private module of the importer's own package
            if (pkg + ".").startswith(target + "."):
                continue  # a package's own names
            for alias in node.names:
                if alias.name.startswith("_") and not alias.name.startswith("__"):
                    bad.append(f"{path.relative_to(ROOT)}: from {target} import {alias.name}")
    return bad


def test_private_modules_and_names_stay_in_their_package():
    assert _private_crossings(PACKAGE) == []


def test_the_private_check_sees_a_crossing(tmp_path):
    project = _copy_project(tmp_path)
    (project / "handsynth" / "estimate" / "_peek.py").write_text(
        "from ..db._bits import popcount64\nfrom ..render import _preprocess\n")
    global ROOT
    saved, ROOT = ROOT, project
    try:
        found = _private_crossings(project / "handsynth")
    finally:
        ROOT = saved
    assert found == ["handsynth/estimate/_peek.py: from handsynth.db._bits import ...",
                     "handsynth/estimate/_peek.py: from handsynth.render import _preprocess"]
