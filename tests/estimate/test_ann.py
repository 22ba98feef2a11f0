"""The approximate (IVF) search: exact when every cell is probed, never better than exact."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from handsynth.db import extract_features, render_entries
from handsynth.errors import InvalidInputError
from handsynth.estimate._ann import (
    ApproximateIndex,
    ApproximateOptions,
    _code_bound,
    ann_path,
)
from handsynth.estimate._search import (
    SearchOptions,
    SearchTables,
    search,
    search_reference,
)
from handsynth.models import HandShape, natural_pose_set
from handsynth.render import CameraMount

RENDER_SIZE = (180, 120)  # render size of the shared small database (tests/conftest.py)


def _tables(rows):
    return SearchTables.from_arrays(hlac=rows["hlac"], sil_bits=rows["sil_bits"],
                                    ridge_bits=rows["ridge_bits"], ridge_area=rows["ridge_area"])


@pytest.fixture(scope="module", autouse=True)
def _faiss_one_thread():
    """faiss on one thread: its OpenMP threads crawl on a busy machine."""
    import faiss

    before = faiss.omp_get_max_threads()
    faiss.omp_set_num_threads(1)
    yield
    faiss.omp_set_num_threads(before)


@pytest.fixture(scope="module")
def natural_rows():
    """1,200 natural poses of the standard hand (more entries than the shared fixture)."""
    return render_entries(natural_pose_set(1200, seed=3), HandShape(), CameraMount(),
                          render_size=RENDER_SIZE)


@pytest.fixture(scope="module")
def queries(query_rows):
    return [extract_features(s) for s in query_rows["silhouette"]]


@pytest.fixture(scope="module")
def small_index(small_rows):
    opts = ApproximateOptions(nlist=16, max_scored=None)
    return ApproximateIndex.build(_tables(small_rows), options=opts, seed=0)


@pytest.fixture(scope="module")
def natural_index(natural_rows):
    opts = ApproximateOptions(nlist=32, nprobe=2, dims=32, train_size=500, max_scored=None)
    return ApproximateIndex.build(_tables(natural_rows), options=opts, seed=1)


def test_probing_every_cell_gives_the_exact_answer(small_index, queries):
    t = small_index.tables
    options = [SearchOptions(), SearchOptions(prune=False), SearchOptions(c=0.05, c1=0.0, c2=0.02),
               SearchOptions(c3=10.0, c4=3000.0)]
    low = 0
    for f in queries:
        for opt in options:
            exact = search_reference(f, t, options=opt)
            approx = small_index.search(f, opt, nprobe=small_index.nlist)
            assert approx == exact  # survivors are not compared
            assert 1 <= approx.survivors <= exact.survivors or approx.low_confidence
            assert small_index.search(f, opt, nprobe=10**6, seed=7) == exact
            low += exact.low_confidence
    assert 0 < low < len(queries) * len(options)  # the fallback branch ran too


def test_probing_every_cell_is_exact_on_a_larger_natural_database(natural_index, queries):
    for f in queries:
        assert natural_index.search(f, nprobe=natural_index.nlist) == search(
            f, natural_index.tables)


def test_fewer_probes_never_beat_the_exact_error(natural_index, queries):
    t = natural_index.tables
    differ = 0
    for f in queries:
        exact = search(f, t)
        for nprobe in (1, 2, 4):
            approx = natural_index.search(f, nprobe=nprobe)
            assert approx.error >= exact.error
            assert approx.low_confidence == exact.low_confidence  # widened before falling back
            differ += approx.index != exact.index
        for nprobe in (1, 3):  # a seed adds a candidate: never worse than without it
            seeded = natural_index.search(f, nprobe=nprobe, seed=exact.index)
            assert exact.error <= seeded.error <= natural_index.search(f, nprobe=nprobe).error
            assert seeded.index == exact.index
    assert differ > 0  # one probe out of 32 cells does miss some answers


def test_capped_scoring_still_answers_a_survivor(natural_index, queries):
    capped = natural_index.with_options(max_scored=3)
    t = natural_index.tables
    changed = 0
    for f in queries:
        exact = search(f, t)
        r = capped.search(f, nprobe=natural_index.nlist)
        assert r.error >= exact.error and r.low_confidence == exact.low_confidence
        assert 1 <= r.survivors <= 3 or r.low_confidence
        changed += r.index != exact.index
    assert changed > 0  # three scorings per frame are not enough for every frame


def test_an_entry_finds_itself(natural_index, natural_rows):
    for i in (0, 77, 1199):
        f = extract_features(natural_rows["silhouette"][i])
        r = natural_index.search(f, nprobe=1)
        assert r.error == 0.0 and not r.low_confidence
        assert (natural_rows["hlac"][r.index] == f.hlac).all()


def test_code_bound_never_exceeds_the_hlac_distance(natural_index, queries):
    idx = natural_index
    hlac = idx.tables.hlac.astype(np.int64)
    tight = []
    for f in queries:
        q_y = idx._a64 @ f.hlac.astype(np.float64)
        d = ((hlac - f.hlac.astype(np.int64)) ** 2).sum(axis=1)
        b = np.array([_code_bound(q_y, idx.codes[idx.position[i]], idx.step, idx._band)
                      for i in range(len(d))])
        b *= idx._inv_gain
        assert (b <= d).all()
        tight.append(np.median(b / np.maximum(d, 1)))
    assert np.median(tight) > 0.3  # and it is not trivially loose


def test_lists_partition_the_database(natural_index):
    idx = natural_index
    assert np.array_equal(np.sort(idx.order), np.arange(len(idx)))
    assert np.array_equal(idx.order[idx.position], np.arange(len(idx)))
    y = idx.tables.hlac.astype(np.float64) @ idx._a64.T
    nearest = np.argmin(((y[:, None, :] - idx.centroids[None]) ** 2).sum(axis=2), axis=1)
    for c in range(idx.nlist):
        members = idx.order[idx.offsets[c]:idx.offsets[c + 1]]
        assert (np.diff(members) > 0).all()
        assert (nearest[members] == c).mean() > 0.99  # rounding may flip near-ties


def test_index_is_saved_loaded_and_rebuilt_when_stale(tmp_path, small_rows, queries, monkeypatch):
    path = tmp_path / "db.h5.ann.npz"
    t_small = _tables(small_rows)
    opts = ApproximateOptions(nlist=8, nprobe=2)
    first = ApproximateIndex.open(None, t_small, options=opts, seed=2, path=path)
    assert path.is_file() and not list(tmp_path.glob("*.tmp-*"))

    def no_build(*args, **kwargs):
        raise AssertionError("rebuilt although the saved index matches")

    with monkeypatch.context() as m:
        m.setattr(ApproximateIndex, "build", classmethod(no_build))
        again = ApproximateIndex.open(None, t_small, options=ApproximateOptions(nlist=8, nprobe=3),
                                      seed=2, path=path)
    assert again.key == first.key and again.options.nprobe == 3
    assert np.array_equal(again.codes, first.codes) and np.array_equal(again.order, first.order)
    assert [again.search(f, nprobe=2) for f in queries] == [first.search(f) for f in queries]

    # another database, other build options or another seed: rebuilt and replaced
    rows = {k: v[::-1] for k, v in small_rows.items()}
    other = ApproximateIndex.open(None, _tables(rows), options=opts, seed=2, path=path)
    assert other.key != first.key
    with monkeypatch.context() as m:
        m.setattr(ApproximateIndex, "build", classmethod(no_build))
        assert ApproximateIndex.open(None, _tables(rows), options=opts, seed=2,
                                     path=path).key == other.key
    assert ApproximateIndex.open(None, t_small, options=opts, seed=3, path=path).key != first.key
    # a damaged file is rebuilt too
    path.write_bytes(b"not an index")
    assert ApproximateIndex.open(None, t_small, options=opts, seed=2, path=path).key == first.key


@pytest.mark.parametrize("damage", ["flip", "cut", "meta"])
def test_damaged_index_file_is_rebuilt_not_raised(tmp_path, small_rows, queries, damage):
    path = tmp_path / "db.h5.ann.npz"
    t_small = _tables(small_rows)
    opts = ApproximateOptions(nlist=8, nprobe=2)
    first = ApproximateIndex.open(None, t_small, options=opts, seed=2, path=path)
    data = bytearray(path.read_bytes())
    if damage == "flip":  # inside a stored array: a bad CRC-32 when read
        data[len(data) // 3] ^= 0xFF
    elif damage == "cut":
        data = data[:len(data) // 2]
    else:  # a readable zip whose meta is not a JSON object
        import io
        import json

        buf = io.BytesIO()
        np.savez(buf, meta=np.frombuffer(json.dumps([1, 2]).encode(), np.uint8))
        data = bytearray(buf.getvalue())
    path.write_bytes(bytes(data))
    again = ApproximateIndex.open(None, t_small, options=opts, seed=2, path=path)
    assert again.key == first.key
    assert [again.search(f) for f in queries] == [first.search(f) for f in queries]
    # and the rebuilt file replaced the damaged one
    assert ApproximateIndex._load(path, t_small, key=first.key, options=again.options,
                                  seed=2) is not None



def test_index_next_to_a_database_file_follows_its_checksum(tmp_path, db_folder, small_rows,
                                                           monkeypatch):
    from handsynth.db import open_database, write_database

    src = next(db_folder.glob("*.h5"))
    db_file = tmp_path / "hand.h5"
    shutil.copyfile(src, db_file)
    opts = ApproximateOptions(nlist=8)
    db = open_database(db_file)
    first = ApproximateIndex.open(db, options=opts)
    assert ann_path(db_file).is_file() and ann_path(db_file).name == "hand.h5.ann.npz"

    def no_build(*args, **kwargs):
        raise AssertionError("rebuilt although the saved index matches")

    with monkeypatch.context() as m:
        m.setattr(ApproximateIndex, "build", classmethod(no_build))
        assert ApproximateIndex.open(open_database(db_file), options=opts).key == first.key

    # the database file is rebuilt with other rows: its index is stale
    rows = {k: np.ascontiguousarray(v[::-1]) for k, v in small_rows.items()}
    write_database(db_file, angles=rows["angles"], hlac=rows["hlac"], sil_bits=rows["sil_bits"],
                   ridge_bits=rows["ridge_bits"], ridge_area=rows["ridge_area"],
                   keypoints=rows["keypoints"], meta=db.meta)
    rebuilt = ApproximateIndex.open(open_database(db_file), options=opts)
    assert rebuilt.key != first.key
    # tables still holding the old rows do not match the new file's index either
    assert ApproximateIndex.open(db, options=opts).key not in (rebuilt.key, first.key)


def test_options_and_arguments_are_checked(small_index, small_rows, queries):
    for bad, name in (({"nprobe": 0}, "nprobe"), ({"nlist": True}, "nlist"),
                      ({"dims": 0}, "dims"), ({"dims": 1601}, "dims"),
                      ({"train_size": 2.5}, "train_size"), ({"niter": -1}, "niter"),
                      ({"nprobe": 8, "max_nprobe": 4}, "max_nprobe")):
        with pytest.raises(InvalidInputError, match=name):
            ApproximateOptions(**bad)
    with pytest.raises(InvalidInputError, match="'nprob'"):
        ApproximateOptions.from_dict({"nprob": 4})
    assert ApproximateOptions.from_dict({"nprobe": 4}).nprobe == 4
    with pytest.raises(TypeError):
        ApproximateOptions(nprob=4)
    t = _tables(small_rows)
    with pytest.raises(InvalidInputError, match="nlist"):
        ApproximateIndex.build(t, options=ApproximateOptions(nlist=241))
    with pytest.raises(InvalidInputError, match="tables"):
        ApproximateIndex.build(small_rows)
    with pytest.raises(InvalidInputError, match="options"):
        ApproximateIndex.build(t, options={"nprobe": 2})
    with pytest.raises(InvalidInputError, match="seed"):
        ApproximateIndex.build(t, seed=-1)
    f = queries[0]
    with pytest.raises(InvalidInputError, match="nprobe"):
        small_index.search(f, nprobe=0)
    with pytest.raises(InvalidInputError, match="seed"):
        small_index.search(f, seed=240)
    with pytest.raises(InvalidInputError, match="options"):
        small_index.search(f, ApproximateOptions())
    with pytest.raises(InvalidInputError, match="'dims'"):
        small_index.with_options(dims=8)
    assert small_index.with_options(nprobe=3).options.nprobe == 3
    small_index.check_matches(_tables(small_rows))  # same rows, other object: fine
    rows = {k: v[::-1] for k, v in small_rows.items()}
    with pytest.raises(InvalidInputError, match="other database rows"):
        small_index.check_matches(_tables(rows))
