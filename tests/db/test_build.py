"""The database build job: build, open, resume, rebuild, determinism, executors."""

from __future__ import annotations

import os
import re

import numpy as np
import pytest

from handsynth.db import (
    BuildOptions,
    build_database,
    build_databases,
    database_path,
    open_database,
    render_entries,
    verify,
)
from handsynth.errors import DatabaseCorruptError, DatabaseError, InvalidInputError
from handsynth.models import HandShape, pose_set
from handsynth.render import CameraMount

SMALL = {"count": 200, "render_size": (120, 80), "seed": 3}
SHAPE = HandShape()


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("db")
    path = build_database(out, SHAPE, **SMALL)
    return path, path.read_bytes()


def test_build_writes_a_database_that_opens_with_its_meta(built):
    path, _ = built
    assert path == database_path(path.parent, SHAPE)
    meta = BuildOptions(**SMALL).meta(SHAPE, CameraMount())
    db = open_database(path, expect=meta)
    assert len(db) == 200
    poses = pose_set("paper", 200, seed=3)
    np.testing.assert_allclose(db.angles, poses.astype(np.float32))
    rows = render_entries(poses[:20], SHAPE, render_size=(120, 80))
    np.testing.assert_array_equal(db.hlac[:20], rows["hlac"])
    np.testing.assert_array_equal(db.sil_bits[:20], rows["sil_bits"])
    np.testing.assert_allclose(db.keypoints_m(slice(0, 20)), rows["keypoints"], atol=6e-6)
    assert db.sil_bits.any(axis=1).all(), "every entry must show a hand"


def test_rerun_verifies_and_does_not_rewrite(built):
    path, data = built
    before = os.stat(path)
    summary = build_databases(path.parent, [SHAPE], workers=1, **SMALL)
    after = os.stat(path)
    assert summary.skipped == (SHAPE.name,) and summary.built == ()
    assert (after.st_ino, after.st_mtime_ns) == (before.st_ino, before.st_mtime_ns)
    assert path.read_bytes() == data


def test_corrupted_file_is_rebuilt_to_the_same_bytes(built, tmp_path):
    _, data = built
    path = database_path(tmp_path, SHAPE)
    damaged = bytearray(data)
    damaged[len(damaged) // 2] ^= 0xFF
    path.write_bytes(bytes(damaged))
    with pytest.raises(DatabaseCorruptError):
        verify(path)
    summary = build_databases(tmp_path, [SHAPE], workers=1, **SMALL)
    assert summary.built == (SHAPE.name,)
    assert SHAPE.name in summary.rebuilt
    assert path.read_bytes() == data


def test_other_parameters_are_rebuilt_not_kept(built, tmp_path):
    _, data = built
    path = database_path(tmp_path, SHAPE)
    path.write_bytes(data)
    summary = build_databases(tmp_path, [SHAPE], workers=1, **{**SMALL, "seed": 4})
    assert "seed" in summary.rebuilt[SHAPE.name]
    assert verify(path)["pose_set"]["seed"] == 4


def test_stale_temporary_files_are_removed(tmp_path):
    path = database_path(tmp_path, SHAPE)
    stale = path.with_name(path.name + ".tmp-999999999")
    stale.write_bytes(b"half a file")
    build_databases(tmp_path, [SHAPE], workers=1, **{**SMALL, "count": 40})
    assert not stale.exists()
    verify(path)


def test_bytes_do_not_depend_on_chunks_or_workers(built, tmp_path):
    _, data = built
    a = build_databases(tmp_path / "a", [SHAPE], workers=1, chunk_size=37, **SMALL).paths[0]
    b = build_databases(tmp_path / "b", [SHAPE], workers=2, **SMALL).paths[0]
    assert a.read_bytes() == data
    assert b.read_bytes() == data


def test_progress_reports_every_chunk_and_finishes(tmp_path):
    seen = []
    shapes = [SHAPE, HandShape(length=1.05)]
    summary = build_databases(tmp_path, shapes, workers=1, chunk_size=25, progress=seen.append,
                              **{**SMALL, "count": 50})
    done = [p.entries_done for p in seen]
    assert done == sorted(done) and done[-1] == 100
    assert all(p.entries_total == 100 and p.shapes_total == 2 for p in seen)
    assert seen[-1].finished and seen[-1].shapes_done == 2 and seen[-1].eta_s == 0
    assert not any(p.finished for p in seen[:-1])
    assert summary.entries == 100 and len(summary.paths) == 2


@pytest.mark.parametrize("kwargs, word", [
    ({"count": 0}, "count"),
    ({"seed": -1}, "seed"),
    ({"pose_set": "yoga"}, "pose_set"),
    ({"side": "middle"}, "side"),
    ({"render_size": (120,)}, "render_size"),
    ({"render_size": (8, 8)}, "render_size"),
    ({"workers": 0}, "workers"),
    ({"executor": "dask"}, "executor"),
    ({"chunk_size": 0}, "chunk_size"),
])
def test_bad_options_name_the_argument_and_value(tmp_path, kwargs, word):
    with pytest.raises(InvalidInputError, match=word) as info:
        build_databases(tmp_path, [SHAPE], **{"count": 10, **kwargs})
    value = next(iter(kwargs.values()))
    assert repr(value) in str(info.value) or str(value) in str(info.value)
    assert not any(tmp_path.iterdir())


def test_bad_shapes_are_refused(tmp_path):
    with pytest.raises(InvalidInputError, match="hand-shape name"):
        build_databases(tmp_path, ["L1.0"], count=10)
    with pytest.raises(InvalidInputError, match="distinct"):
        build_databases(tmp_path, [SHAPE, SHAPE.name], count=10)
    with pytest.raises(InvalidInputError, match="at least one"):
        build_databases(tmp_path, [], count=10)


@pytest.mark.slow
def test_ray_executor_gives_the_same_bytes(built, tmp_path):
    pytest.importorskip("ray", reason="Ray is optional: pip install 'handsynth[ray]'")
    _, data = built
    path = build_database(tmp_path, SHAPE, workers=2, executor="ray", **SMALL)
    assert path.read_bytes() == data


def test_a_build_from_a_script_without_the_main_guard_says_so(tmp_path):
    # the spawned workers import the script and start the build again; the parent got a
    # bare BrokenProcessPool traceback
    import subprocess
    import sys
    from pathlib import Path

    script = tmp_path / "unguarded.py"
    script.write_text("from handsynth.db import build_databases\n"
                      "from handsynth.models import HandShape\n"
                      f"build_databases({str(tmp_path / 'dbs')!r}, [HandShape()], workers=2, "
                      "count=200, render_size=(120, 80), seed=3)\n")
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))
    res = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         timeout=300, env=env, cwd=tmp_path)
    assert res.returncode != 0
    last = res.stderr.strip().splitlines()[-1]
    assert last.startswith("handsynth.errors.DatabaseError: a worker process of the build died")
    assert "'unguarded.py'" in last and 'if __name__ == "__main__":' in last


TINY = {"count": 30, "render_size": (64, 48), "seed": 3}


def test_left_and_right_hands_have_their_own_files(tmp_path):
    from handsynth.db import find_database

    right = build_databases(tmp_path, [SHAPE], workers=1, **TINY).paths[0]
    left = build_databases(tmp_path, [SHAPE], workers=1, side="left", **TINY)
    assert right.name == f"{SHAPE.name}.h5"  # the right hand's name is unchanged
    assert left.paths[0].name == f"{SHAPE.name}_left.h5" and left.built == (SHAPE.name,)
    assert not left.rebuilt  # the right hand's file was not touched
    assert verify(right)["side"] == "right" and verify(left.paths[0])["side"] == "left"
    # each verifies and is kept on the next run
    assert build_databases(tmp_path, [SHAPE], workers=1, **TINY).skipped == (SHAPE.name,)
    assert build_databases(tmp_path, [SHAPE], workers=1, side="left",
                           **TINY).skipped == (SHAPE.name,)
    assert find_database(tmp_path, SHAPE, "left") == left.paths[0]
    assert database_path(tmp_path, SHAPE.name, side="left") == left.paths[0]


def test_a_file_of_another_hand_is_refused_not_overwritten(tmp_path):
    from handsynth.errors import DatabaseMismatchError, InvalidShapeError

    # a left hand's file under the right hand's name (as builds before the _left name made)
    left = build_databases(tmp_path / "l", [SHAPE], workers=1, side="left", **TINY).paths[0]
    old = database_path(tmp_path, SHAPE)
    old.write_bytes(left.read_bytes())
    for force in (False, True):
        with pytest.raises(DatabaseMismatchError, match=r"holds the left hand .* but the right "
                                                        r"hand .* was asked for"):
            build_databases(tmp_path, [SHAPE], workers=1, force=force, **TINY)
    assert old.read_bytes() == left.read_bytes()
    # a shape that differs below the name's 0.001 is refused before anything is built
    with pytest.raises(InvalidShapeError, match=r"shapes\[0\] has ratios finer than its database "
                                                r"file name L1.000_W1.000_P1.000_T1.000 .*"
                                                r"length=1.0004"):
        build_databases(tmp_path / "n", [HandShape(length=1.0004)], workers=1, **TINY)
    assert not (tmp_path / "n").exists()
    # a file named for the left hand that holds the right hand
    right = build_databases(tmp_path / "r", [SHAPE], workers=1, **TINY).paths[0]
    fake = database_path(tmp_path / "r", SHAPE, "left")
    fake.write_bytes(right.read_bytes())
    with pytest.raises(DatabaseMismatchError, match=r"named for the left hand but holds the "
                                                    r"right hand"):
        open_database(fake)


def test_shape_names_and_bad_arguments_of_path_functions(tmp_path):
    from handsynth.db import find_database

    assert database_path(tmp_path, SHAPE.name) == database_path(tmp_path, SHAPE)
    with pytest.raises(InvalidInputError, match=r"shape must be a HandShape or a shape name .*"
                                                r"got int"):
        database_path(tmp_path, 3)
    with pytest.raises(InvalidInputError, match=r"side must be 'right' or 'left', got 'Left'"):
        find_database(tmp_path, SHAPE, "Left")
    with pytest.raises(InvalidInputError, match=r"not-a-shape"):
        find_database(tmp_path, "not-a-shape")
    with pytest.raises(DatabaseError, match=r"no database for the right hand of shape "
                                            r"L1.000_W1.000_P1.000_T1.000 in"):
        find_database(tmp_path, SHAPE.name)


@pytest.mark.parametrize("call, words", [
    (lambda d: build_database(None), r"out_dir must be a folder name \(str or path\), got None"),
    (lambda d: build_databases(None, [SHAPE], count=10), r"out_dir must be a folder name .*got None"),
    (lambda d: build_database(3, count=10), r"out_dir must be a folder name .*got int 3"),
    (lambda d: database_path(None, SHAPE), r"out_dir must be a folder name .*got None"),
    (lambda d: build_database(d, count=10, bogus=1),
     r"^build_database got an unexpected keyword argument 'bogus' \(the option keywords are side, "),
    (lambda d: build_databases(d, [SHAPE], count=10, bogus=1),
     r"^build_databases got an unexpected keyword argument 'bogus'"),
    (lambda d: build_database(d, count=10, progress="x"),
     r"progress must be None or a callable taking a BuildProgress, got str 'x'"),
    (lambda d: build_databases(d, [SHAPE], count=10, progress=3), r"progress must be .*got int 3"),
])
def test_build_arguments_are_refused_by_name_before_any_file(tmp_path, call, words):
    # issue: None gave a raw pathlib TypeError, bogus=1 named BuildOptions.__init__, and
    # progress="x" failed deep inside with "'str' object is not callable"
    with pytest.raises(InvalidInputError, match=words):
        call(tmp_path)
    assert not any(tmp_path.iterdir())


def test_find_database_refuses_a_folder_that_is_not_a_name(tmp_path):
    from handsynth.db import find_database

    with pytest.raises(InvalidInputError, match=r"folder must be a folder name .*got None"):
        find_database(None, SHAPE)
    with pytest.raises(InvalidInputError, match=r"folder must name a folder, got ''"):
        find_database("", SHAPE)


@pytest.mark.parametrize("pose_set, words", [(["paper"], r"got list \['paper'\]"),
                                             ({"paper": 1}, r"got dict \{'paper': 1\}"),
                                             ("yoga", r"got str 'yoga'")])
def test_a_pose_set_that_is_not_a_name_is_refused(pose_set, words):
    # issue: BuildOptions(pose_set=["paper"]) said "unhashable type: 'list'"
    with pytest.raises(InvalidInputError, match=rf"pose_set must be one of paper, natural, {words}"):
        BuildOptions(pose_set=pose_set)


def test_a_mount_that_never_sees_the_hand_writes_no_database(tmp_path):
    # issue: a mount allowed by CameraMount but with the hand out of view wrote a database
    # whose every silhouette was empty
    from handsynth.errors import InvalidCameraError

    mount = CameraMount(thumb_offset_mm=1000.0)
    with pytest.raises(InvalidCameraError, match=r"mount CameraMount\(.*thumb_offset_mm=1000.0.* "
                                                 r"never sees the hand: all 8 probed silhouettes "
                                                 r"of shape L1.000_W1.000_P1.000_T1.000 \(right "
                                                 r"hand; the open hand, a fist and 6 poses of the "
                                                 r"set\) are empty"):
        build_database(tmp_path, SHAPE, mount, count=6, render_size=(72, 48))
    assert not list(tmp_path.glob("*.h5*"))


def test_the_rendered_silhouettes_are_still_checked_after_the_probe(tmp_path, monkeypatch):
    # the probe renders a few poses; a shape it sees is still refused when every one of its
    # rendered silhouettes is empty
    from handsynth.db import _build
    from handsynth.errors import InvalidCameraError

    monkeypatch.setattr(_build, "_probe_in_view", lambda *args: None)
    mount = CameraMount(thumb_offset_mm=1000.0)
    with pytest.raises(InvalidCameraError, match=r"mount CameraMount\(.*thumb_offset_mm=1000.0.* "
                                                 r"never sees the hand: all 6 silhouettes of "
                                                 r"shape L1.000_W1.000_P1.000_T1.000 \(right "
                                                 r"hand\) are empty"):
        build_database(tmp_path, SHAPE, mount, count=6, render_size=(72, 48))
    assert not list(tmp_path.glob("*.h5*"))


def test_a_shape_the_mount_never_sees_refuses_the_build_before_any_file_is_written(tmp_path):
    # issue: the all-empty check ran per shape after rendering, so the earlier shapes'
    # databases were written before a later shape was refused
    from handsynth.errors import InvalidCameraError

    mount = CameraMount(along_mm=250.0, fov_deg=30.0, thumb_offset_mm=0.0)  # past short fingers
    seen, unseen = HandShape(length=2.0), HandShape(length=0.5)
    with pytest.raises(InvalidCameraError, match=r"^mount CameraMount\(.*along_mm=250.0.*\) never "
                                                 r"sees the hand: all 8 probed silhouettes of "
                                                 r"shape L0.500_W1.000_P1.000_T1.000 \(right "
                                                 r"hand; .* so neither L0.500_W1.000_P1.000_T1.000"
                                                 r"\.h5 nor any other database of this build is "
                                                 r"written"):
        build_databases(tmp_path, [seen, unseen], mount, count=6, render_size=(72, 48), workers=1)
    assert not list(tmp_path.glob("*.h5*"))
    summary = build_databases(tmp_path, [seen], mount, count=6, render_size=(72, 48), workers=1)
    assert summary.built == (seen.name,)  # the mount does see the long hand


@pytest.mark.parametrize("size", ["720x480", (720, 480, 3), (720.5, 480), (8, 480), None])
def test_render_entries_refuses_a_render_size_that_is_not_two_pixel_counts(size):
    # "720x480" was refused as "got '7'"; (720, 480, 3) was taken
    with pytest.raises(InvalidInputError, match=r"render_size must be \(width, height\) with "
                                                r"integers in \[16, 4096\], got " + re.escape(repr(size))):
        render_entries(np.zeros((1, 20)), render_size=size)
