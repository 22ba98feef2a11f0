"""The one atomic writer of every output (handsynth/_io.py): whole or nothing, never over an input."""

import json
import math
import os
from pathlib import Path

import pytest

from handsynth._io import (
    PendingOutput,
    atomic_open,
    atomic_path,
    check_output,
    same_file,
    write_bytes,
    write_text,
)
from handsynth.errors import DatabaseError, OutputError


def test_a_write_appears_whole_and_leaves_no_temporary_file(tmp_path):
    target = tmp_path / "a.json"
    write_text(target, "old\n")
    write_text(target, "new\n")
    assert target.read_text() == "new\n" and sorted(os.listdir(tmp_path)) == ["a.json"]
    assert target.stat().st_mode & 0o044  # an ordinary, readable file (not mkstemp's 0600)


def test_an_error_while_writing_keeps_the_old_file(tmp_path):
    target = tmp_path / "a.txt"
    write_text(target, "old\n")
    with pytest.raises(KeyboardInterrupt), atomic_open(target) as f:
        f.write("half")
        raise KeyboardInterrupt
    assert target.read_text() == "old\n" and sorted(os.listdir(tmp_path)) == ["a.txt"]


def test_a_failed_cleanup_never_hides_the_real_error(tmp_path, monkeypatch):
    # issue 16 item 4: in a read-only folder the cleanup's unlink raised instead
    target = tmp_path / "x.bin"
    real_unlink = Path.unlink

    def unlink(self, *args, **kwargs):
        if ".tmp-" in self.name:
            raise PermissionError(13, "Permission denied", str(self))
        return real_unlink(self, *args, **kwargs)

    monkeypatch.setattr(Path, "unlink", unlink)
    with pytest.raises(OutputError, match=r"no space left") as err, atomic_path(target) as tmp:
        tmp.write_bytes(b"12")
        raise OSError(28, "No space left on device")
    assert any("could not be removed: permission denied" in n for n in err.value.__notes__)


def test_a_read_only_folder_is_named(read_only_folder):
    with pytest.raises(DatabaseError, match=r"the file system is read-only") as err:
        write_bytes(read_only_folder / "x.h5", b"data", what="database", error=DatabaseError)
    assert "x.h5" in str(err.value)


def test_a_full_disk_is_named_and_leaves_nothing(full_disk):
    with pytest.raises(OutputError, match=r"no space left on the device"):
        write_bytes(full_disk / "big.bin", b"\1" * (512 * 1024))
    assert list(full_disk.iterdir()) == []


@pytest.mark.parametrize("make", ["same path", "symlink", "hard link", "relative path"])
def test_an_output_never_replaces_an_input(tmp_path, monkeypatch, make):
    # issue 16 item 11
    source = tmp_path / "in.csv"
    source.write_text("input\n")
    out = {"same path": source, "symlink": tmp_path / "s.csv", "hard link": tmp_path / "h.csv",
           "relative path": Path("in.csv")}[make]
    if make == "symlink":
        out.symlink_to(source)
    elif make == "hard link":
        os.link(source, out)
    monkeypatch.chdir(tmp_path)
    assert same_file(out, source)
    with pytest.raises(OutputError, match=r"never replaces an input"):
        write_text(out, "output\n", inputs=[source])
    assert source.read_text() == "input\n"


@pytest.mark.parametrize("name, words", [
    ("missing/x.json", "folder '{tmp}/missing' does not exist"),
    ("file.txt/x.json", "'{tmp}/file.txt' is not a folder"),
    ("sub", "it is a folder"),
])
def test_an_output_that_cannot_be_a_file_is_named(tmp_path, name, words):
    # issue 16 item 9: FileNotFoundError tracebacks
    (tmp_path / "sub").mkdir()
    (tmp_path / "file.txt").write_text("")
    with pytest.raises(OutputError, match=words.format(tmp=tmp_path).replace("(", r"\(")):
        check_output(tmp_path / name)


def test_a_pending_output_keeps_its_suffix_and_commits_or_discards(tmp_path):
    pending = PendingOutput(tmp_path / "v.mp4", keep_suffix=True)
    assert pending.tmp.name.endswith(".mp4") and ".tmp-" in pending.tmp.name
    pending.tmp.write_bytes(b"x")
    pending.discard()
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(OutputError, match=r"was not written"):
        pending.commit()


def test_a_device_or_pipe_is_refused_and_a_link_written_through(tmp_path):
    # as root, `-o /dev/null` turned /dev/null into a regular file (the finished file was
    # renamed onto it), and an output through a symbolic link replaced the link
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    for target in (fifo, Path("/dev/null")):
        with pytest.raises(OutputError, match="not a regular file"):
            write_text(target, "x")
    assert Path("/dev/null").is_char_device()
    real = tmp_path / "real.csv"
    real.write_text("old")
    link = tmp_path / "link.csv"
    link.symlink_to(real)
    write_text(link, "new")
    assert link.is_symlink() and real.read_text() == "new"


def test_make_folder_names_the_folder_and_why(tmp_path):
    from handsynth._io import make_folder
    from handsynth.errors import DatabaseError, OutputError

    assert make_folder(tmp_path / "a" / "b").is_dir()
    assert make_folder(tmp_path / "a" / "b").is_dir()  # exists already: fine
    (tmp_path / "f").write_text("")
    with pytest.raises(OutputError, match=r"cannot create the --plots folder '.*f/p': not a directory"):
        make_folder(tmp_path / "f" / "p", what="--plots folder")
    with pytest.raises(DatabaseError, match="cannot create the output folder"):
        make_folder(tmp_path / "f", error=DatabaseError)


def _strict_loads(text):
    def refuse(token):
        raise ValueError(f"bare {token} in the JSON")

    return json.loads(text, parse_constant=refuse)


def test_write_json_writes_non_finite_numbers_as_null(tmp_path):
    import numpy as np

    from handsynth._io import write_json

    obj = {"nan": float("nan"), "inf": float("inf"), "ninf": -math.inf, "ok": 1.5, "n": 3,
           "np_nan": np.float64("nan"), "np32_inf": np.float32("inf"), "np_int": np.int64(7),
           "np_ok": np.float32(0.25), "flag": np.bool_(True), "none": None, "s": "NaN",
           "nested": [{"t": (1.0, math.nan, np.nan)}, [np.array([1.0, np.nan, np.inf])]],
           "array2d": np.array([[np.nan, 2.0], [3.0, -np.inf]])}
    out = write_json(tmp_path / "r.json", obj)
    text = out.read_text()
    assert out == tmp_path / "r.json" and text.endswith("\n")
    assert "NaN" not in text.replace('"NaN"', "") and "Infinity" not in text
    assert _strict_loads(text) == {
        "nan": None, "inf": None, "ninf": None, "ok": 1.5, "n": 3, "np_nan": None,
        "np32_inf": None, "np_int": 7, "np_ok": 0.25, "flag": True, "none": None, "s": "NaN",
        "nested": [{"t": [1.0, None, None]}, [[1.0, None, None]]],
        "array2d": [[None, 2.0], [3.0, None]]}
    assert sorted(os.listdir(tmp_path)) == ["r.json"]
    with pytest.raises(ValueError, match="bare NaN"):  # the strict reader the test relies on
        _strict_loads('{"a": NaN}')


def test_write_json_checks_its_output_like_the_other_writers(tmp_path):
    from handsynth._io import write_json

    source = tmp_path / "in.json"
    source.write_text("{}")
    with pytest.raises(OutputError, match="is the input"):
        write_json(source, {"a": 1}, inputs=[source])
    assert source.read_text() == "{}"
    with pytest.raises(OutputError, match=r"cannot write the JSON file '.*missing/r.json'"):
        write_json(tmp_path / "missing" / "r.json", {"a": 1})
    with pytest.raises(TypeError):  # not JSON: refused before anything is written
        write_json(tmp_path / "r.json", {"a": {1, 2}})
    assert sorted(os.listdir(tmp_path)) == ["in.json"]
    write_json(tmp_path / "r.json", [1], indent=None)
    assert (tmp_path / "r.json").read_text() == "[1]\n"


def test_a_folder_that_cannot_be_written_is_refused_before_any_work(read_only_folder):
    from handsynth._io import make_folder

    with pytest.raises(OutputError, match=r"cannot write the JSON file '.*r.json' into folder "
                                          r"'.*read_only': the file system is read-only"):
        check_output(read_only_folder / "r.json", what="JSON file")
    with pytest.raises(OutputError, match=r"cannot write into the --plots folder '.*read_only': "
                                          r"the file system is read-only"):
        make_folder(read_only_folder, what="--plots folder", writable=True)
    assert make_folder(read_only_folder) == read_only_folder  # a folder only read: fine


def test_a_folder_without_write_permission_is_named(tmp_path, monkeypatch):
    # root may write anywhere, so the permission check is what a user without it meets
    from handsynth import _io

    monkeypatch.setattr(_io.os, "access", lambda path, mode: False)
    with pytest.raises(OutputError, match="x.csv' into folder .*: this user may not write into it"):
        check_output(tmp_path / "x.csv")
    with pytest.raises(OutputError, match="this user may not write into it"):
        _io.make_folder(tmp_path, writable=True)
