"""Every ``handsynth`` command the README and docs/ show is one the command line accepts.

A renamed option or sub-command otherwise leaves the documentation telling users to type
something that fails.  Commands in fenced blocks are parsed whole, as click parses them
(options, their values, the number of arguments); commands quoted inline in the text are
often fragments (``handsynth imu eval --json out.json [--plots DIR]``,
``handsynth imu calibrate | track``), so of those the sub-commands and option names are
checked.  Nothing is run: the values are not converted (files need not exist).
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import click
import pytest

from handsynth.cli._main import cli

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

_FENCE = re.compile(r"^```[\w-]*\n(.*?)^```", re.S | re.M)
_INLINE = re.compile(r"`(handsynth [^`]+)`")


def documented_commands(text: str) -> list[tuple[int, bool, str]]:
    """``(line, whole, command)`` of each ``handsynth`` command in a Markdown page.

    `whole` is True for a command on its own line in a fenced block (a shell comment after
    two spaces and ``\\`` continuations allowed), False for one quoted inline.
    """
    found = []
    for block in _FENCE.finditer(text):
        first = text.count("\n", 0, block.start(1)) + 1
        lines = block.group(1).splitlines()
        i = 0
        while i < len(lines):
            start, line = i, lines[i]
            while line.endswith("\\") and i + 1 < len(lines):
                i += 1
                line = line[:-1] + " " + lines[i]
            command = line.split("  #")[0].strip()
            if command.startswith("handsynth "):
                found.append((first + start, True, command))
            i += 1
    outside = _FENCE.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    for m in _INLINE.finditer(outside):
        found.append((outside.count("\n", 0, m.start()) + 1, False, " ".join(m.group(1).split())))
    return found


def _option_names(command: click.Command) -> set[str]:
    return {name for p in command.params if isinstance(p, click.Option)
            for name in (*p.opts, *p.secondary_opts)}


def command_problem(command: str, *, whole: bool) -> str | None:
    """What the command line would refuse in `command`, or None.

    Parameters
    ----------
    command : str
        ``handsynth ...`` as documented.
    whole : bool, keyword-only
        Parse it whole (options, values, arguments) rather than checking only the names
        of its sub-commands and options.
    """
    tokens = shlex.split(command)[1:]
    if not whole:
        tokens = [t for t in re.split(r"\s+", command.replace("[", " ").replace("]", " "))[1:]
                  if t]
    group: click.Command = cli
    ctx = click.Context(cli, info_name="handsynth")
    while isinstance(group, click.Group) and tokens and not tokens[0].startswith("-"):
        names = [tokens.pop(0)]
        while not whole and len(tokens) >= 2 and tokens[0] == "|":  # a | b | c
            names.append(tokens[1])
            del tokens[:2]
        missing = [n for n in names if group.get_command(ctx, n) is None]
        if missing:
            return f"no command {' '.join(missing)!r} under {ctx.command_path!r}"
        if len(names) > 1:
            return None
        sub = group.get_command(ctx, names[0])
        ctx = click.Context(sub, info_name=names[0], parent=ctx)
        group = sub
    if not whole:
        known = _option_names(group) | {"--help"}
        unknown = [t.split("=")[0] for t in tokens
                   if t.startswith("-") and len(t) > 1 and t.split("=")[0] not in known]
        return f"{ctx.command_path} has no option {unknown[0]}" if unknown else None
    try:
        _, extra, _ = group.make_parser(ctx).parse_args(list(tokens))
    except click.UsageError as exc:
        return f"{ctx.command_path}: {exc.format_message()}"
    return f"{ctx.command_path}: unexpected arguments {extra}" if extra else None


def _cases():
    for page in PAGES:
        for line, whole, command in documented_commands(page.read_text(encoding="utf-8")):
            yield pytest.param(command, whole, id=f"{page.name}:{line}")


CASES = list(_cases())


def test_the_pages_show_commands():
    whole = [c for c in CASES if c.values[1]]
    assert len(CASES) >= 60 and len(whole) >= 20, (len(CASES), len(whole))


@pytest.mark.parametrize("command, whole", CASES)
def test_documented_command_is_accepted(command, whole):
    assert command_problem(command, whole=whole) is None


@pytest.mark.parametrize("command, whole, words", [
    ("handsynth glove calibrate cal.csv -o cal.json --kind dg5 --no-such", True,
     ["handsynth glove calibrate", "--no-such"]),
    ("handsynth glove calibrate cal.csv extra.csv -o cal.json", True, ["extra.csv"]),
    ("handsynth glove calibrate cal.csv -o", True, ["-o", "argument"]),
    ("handsynth glove calibrte cal.csv", True, ["calibrte"]),
    ("handsynth imu eval --json out.json [--plotz DIR]", False, ["--plotz"]),
    ("handsynth imu calibrate | track | evaluate", False, ["evaluate"]),
])
def test_a_wrong_command_is_found(command, whole, words):
    problem = command_problem(command, whole=whole)
    assert problem is not None
    for w in words:
        assert w in problem, problem
