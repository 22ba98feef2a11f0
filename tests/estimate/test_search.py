"""The two-stage pruned search: thresholds of SPEC.md, fast == reference, self-match."""

from __future__ import annotations

import numpy as np
import pytest

from handsynth.db import Features, extract_features, pack_mask
from handsynth.errors import InvalidInputError
from handsynth.estimate import SearchOptions, SearchTables, search, search_reference


def _tables(rows):
    return SearchTables.from_arrays(hlac=rows["hlac"], sil_bits=rows["sil_bits"],
                                    ridge_bits=rows["ridge_bits"], ridge_area=rows["ridge_area"])


def _feat(sil, ridge, hlac):
    sil_bits, ridge_bits = pack_mask(sil), pack_mask(ridge)
    return Features(silhouette=sil, contour=sil, hlac=np.full(1600, hlac, np.uint8), ridge=ridge,
                    sil_bits=sil_bits, ridge_bits=ridge_bits, ridge_area=int(ridge.sum()))


def _line(cols, row=10):
    m = np.zeros((64, 64), bool)
    m[row, cols] = True
    return m


def _hand_made_tables(entries):
    """entries: list of (sil, ridge, hlac value) -> SearchTables."""
    sil = np.stack([e[0] for e in entries])
    ridge = np.stack([e[1] for e in entries])
    hl = np.stack([np.full(1600, e[2], np.uint8) for e in entries])
    return SearchTables.from_arrays(hlac=hl, sil_bits=pack_mask(sil), ridge_bits=pack_mask(ridge),
                                    ridge_area=ridge.sum(axis=(1, 2)))


def test_stage_1_threshold_is_c_times_input_ridge_area():
    # input ridge: 10 pixels in row 10 -> th1 = 0.2 * 10 = 2 pixels
    q = _feat(np.ones((64, 64), bool), _line(slice(0, 10)), 0)
    empty = np.zeros((64, 64), bool)
    sil_p1_2 = np.ones((64, 64), bool)
    sil_p1_2[10, 0:2] = False  # 2 input ridge pixels outside -> P1 = 2 (kept)
    sil_p1_3 = np.ones((64, 64), bool)
    sil_p1_3[10, 0:3] = False  # P1 = 3 > th1 (dropped although its HLAC matches exactly)
    t = _hand_made_tables([(sil_p1_3, empty, 0), (sil_p1_2, empty, 1)])
    r = search(q, t)
    assert (r.index, r.p1, r.low_confidence, r.survivors) == (1, 2, False, 1)
    assert r.error == 1600 + 800 * 2
    assert search_reference(q, t) == r


def test_stage_2_threshold_is_quadratic_in_entry_ridge_area():
    # entry ridge A_ds = 50 -> th2 = 0.002 * 2500 + 0.03 * 50 = 6.5 pixels
    q_sil = np.ones((64, 64), bool)
    q_sil[20, 0:7] = False  # 7 input-background pixels in row 20
    q = _feat(q_sil, np.zeros((64, 64), bool), 0)
    ridge = np.zeros((64, 64), bool)
    ridge[30, 0:44] = True
    r7, r6 = ridge.copy(), ridge.copy()
    r7[20, 0:6] = True
    r7[31, 0] = True
    r7[20, 6] = True  # 7 pixels outside the input silhouette, area 51
    r7[31, 0] = False
    r6[20, 0:6] = True  # 6 pixels outside, area 50
    assert r6.sum() == 50 and r7.sum() == 51
    full = np.ones((64, 64), bool)
    # A=51 -> th2 = 5.202 + 1.53 = 6.732 < 7 (dropped); A=50 -> 6.5 >= 6 (kept)
    t = _hand_made_tables([(full, r7, 0), (full, r6, 3)])
    r = search(q, t)
    assert (r.index, r.p2, r.survivors) == (1, 6, 1)
    assert search_reference(q, t) == r


def test_fallback_when_pruning_leaves_nothing_is_low_confidence():
    q = _feat(np.ones((64, 64), bool), _line(slice(0, 10)), 0)
    sil_a, sil_b = np.ones((64, 64), bool), np.ones((64, 64), bool)
    sil_a[10, 0:5] = False  # P1 = 5
    sil_b[10, 0:4] = False  # P1 = 4, both > th1 = 2
    t = _hand_made_tables([(sil_a, np.zeros((64, 64), bool), 0),
                           (sil_b, np.zeros((64, 64), bool), 2)])
    r = search(q, t)
    assert r.low_confidence and r.survivors == 0
    # E_a = 0 + 800*5 = 4000 ; E_b = 1600*4 + 800*4 = 9600 -> a
    assert (r.index, r.error) == (0, 4000.0)
    assert search_reference(q, t) == r


def test_fast_search_equals_reference_on_rendered_frames(small_rows, query_rows):
    t = _tables(small_rows)
    options = [SearchOptions(), SearchOptions(prune=False), SearchOptions(c=0.05, c1=0.0, c2=0.02),
               SearchOptions(c3=10.0, c4=3000.0)]
    low = 0
    for sil in query_rows["silhouette"]:
        f = extract_features(sil)
        for opt in options:
            fast, ref = search(f, t, options=opt), search_reference(f, t, options=opt)
            # the fast search counts only the survivors it had to score
            assert fast == ref  # survivors are not compared
            assert np.array_equal(fast.tied, ref.tied) and fast.tied[0] == fast.index
            assert 0 <= fast.survivors <= ref.survivors
            assert (fast.survivors > 0) == (ref.survivors > 0)
            low += fast.low_confidence
            assert search(f, t, options=opt, seed=7) == ref  # temporal seed: same answer
    assert 0 < low < len(query_rows["silhouette"]) * len(options)  # both branches ran


def test_entry_own_features_return_that_entry(small_rows):
    t = _tables(small_rows)
    for i in (0, 17, 101, 239):
        f = extract_features(small_rows["silhouette"][i])
        r = search(f, t)
        same = np.flatnonzero((small_rows["hlac"] == f.hlac).all(1)
                              & (small_rows["sil_bits"] == f.sil_bits).all(1)
                              & (small_rows["ridge_bits"] == f.ridge_bits).all(1))
        assert r.error == 0.0 and r.index == same[0] and not r.low_confidence


def test_options_and_arguments_are_checked(small_rows):
    with pytest.raises(TypeError):
        SearchOptions(c5=1.0)
    with pytest.raises(InvalidInputError, match="c1"):
        SearchOptions(c1=-1.0)
    with pytest.raises(InvalidInputError, match="prune"):
        SearchOptions(prune=1)
    t = _tables(small_rows)
    f = extract_features(small_rows["silhouette"][0])
    with pytest.raises(InvalidInputError, match="seed"):
        search(f, t, seed=len(t))
    for bad in ("x", 1.5, True, -1):  # "x" was int()'s ValueError
        with pytest.raises(InvalidInputError, match=r"^seed must be an integer >= 0, got "):
            search(f, t, seed=bad)


def _stack(rows, index):
    return SearchTables.from_arrays(hlac=rows["hlac"][index], sil_bits=rows["sil_bits"][index],
                                    ridge_bits=rows["ridge_bits"][index],
                                    ridge_area=rows["ridge_area"][index])


@pytest.mark.parametrize("compact", [True, False])
def test_repeated_rows_are_searched_once_and_ties_go_to_the_lowest_index(small_rows, query_rows,
                                                                        compact, monkeypatch):
    from handsynth.estimate import _search

    if not compact:  # the index reads the database's own rows instead of a compact copy
        monkeypatch.setattr(_search, "_COMPACT_MAX_BYTES", 0)
    n = len(small_rows["hlac"])
    index = np.concatenate([[100], np.arange(n), [5, 17, 100, 5]])  # entry 100 at 0, 101, 243
    t = _stack(small_rows, index)
    ix = t.prepare()
    assert t.prepare() is ix  # built once
    # every entry maps to a row with equal features, and that row is its group's lowest index
    same = ((t.hlac[ix.rows[ix.group]] == t.hlac).all(1)
            & (t.sil_bits[ix.rows[ix.group]] == t.sil_bits).all(1)
            & (t.ridge_bits[ix.rows[ix.group]] == t.ridge_bits).all(1))
    assert same.all() and (ix.rows[ix.group] <= np.arange(len(t))).all()
    assert ix.group[0] == ix.group[101] == ix.group[243] and ix.sizes[ix.group[0]] >= 3
    assert ix.sizes.sum() == len(t) and np.unique(ix.rows).size == ix.rows.size
    assert (ix.source is ix.rows) != compact
    # the rows the kernel reads are the distinct rows, in layout order
    np.testing.assert_array_equal(ix.hlac[ix.source], t.hlac[ix.rows])
    np.testing.assert_array_equal(ix.ridge_bits[ix.source], t.ridge_bits[ix.rows])
    f = extract_features(small_rows["silhouette"][100])
    for seed in (None, 101, 243, 7):
        r = search(f, t, seed=seed)
        assert r.index == 0 and r.error == 0.0 and r == search_reference(f, t)
        assert np.array_equal(r.tied, search_reference(f, t).tied)
        assert {0, 101, 243} <= set(r.tied.tolist())
    for sil in query_rows["silhouette"][::3]:
        q = extract_features(sil)
        for opt in (SearchOptions(), SearchOptions(prune=False)):
            ref = search_reference(q, t, options=opt)
            assert search(q, t, options=opt) == ref
            assert search(q, t, options=opt, seed=244) == ref


def test_near_ties_give_the_reference_answer(small_rows, query_rows):
    # many rows one HLAC count apart: the bounds must keep every candidate that can tie
    rng = np.random.default_rng(3)
    base = rng.choice(len(small_rows["hlac"]), 60)
    hl = small_rows["hlac"][base].astype(np.int16)
    hl[np.arange(60), rng.integers(0, 1600, 60)] += rng.choice([-1, 1], 60)
    hl = np.clip(hl, 0, 255).astype(np.uint8)
    t = SearchTables.from_arrays(
        hlac=np.vstack([small_rows["hlac"], hl]),
        sil_bits=np.vstack([small_rows["sil_bits"], small_rows["sil_bits"][base]]),
        ridge_bits=np.vstack([small_rows["ridge_bits"], small_rows["ridge_bits"][base]]),
        ridge_area=np.concatenate([small_rows["ridge_area"], small_rows["ridge_area"][base]]))
    for sil in list(query_rows["silhouette"]) + list(small_rows["silhouette"][base[:8]]):
        q = extract_features(sil)
        ref = search_reference(q, t)
        for seed in (None, int(rng.integers(len(t)))):
            r = search(q, t, seed=seed)
            assert r == ref and np.array_equal(r.tied, ref.tied)


@pytest.mark.parametrize("kind", ["rendered", "uniform", "extreme"])
def test_hlac_lower_bound_never_exceeds_the_distance(small_rows, kind):
    from handsynth.estimate._score import Constants
    from handsynth.estimate._search import (
        _bounds,
        _IndexArrays,
        _query_projection,
        _QueryBounds,
        _Scratch,
    )

    rng = np.random.default_rng(11)
    if kind == "rendered":
        hl = small_rows["hlac"]
    elif kind == "uniform":
        hl = rng.integers(0, 256, (300, 1600), dtype=np.uint8)
    else:  # far from the mean in every direction: the largest rounding errors
        hl = np.where(rng.random((300, 1600)) < 0.5, 0, 255).astype(np.uint8)
    n = len(hl)
    t = SearchTables.from_arrays(hlac=hl, sil_bits=np.zeros((n, 64), np.uint64),
                                 ridge_bits=np.zeros((n, 64), np.uint64), ridge_area=np.zeros(n))
    ix = t.prepare()
    queries = np.vstack([hl[:20], rng.integers(0, 256, (20, 1600), dtype=np.uint8),
                         np.full((1, 1600), 255, np.uint8), np.zeros((1, 1600), np.uint8)])
    u = ix.rows.size
    s = _Scratch(key=np.empty(u), lb=np.empty(u), ties=np.empty(u, np.int64),
                 top=np.empty(8, np.int64), lb1=np.empty(u, np.int32), lb2=np.empty(u, np.int32),
                 hb=np.empty(u, np.float32))
    no_penalty = Constants(th1=0.0, c1=0.0, c2=0.0, c3=0.0, c4=0.0, prune=False)
    for q in queries:
        qp, qr = _query_projection(q, ix.mean, ix.basis)
        qb = _QueryBounds(planes=np.zeros((5, 4), np.uint64), sil_coarse=np.zeros(4, np.uint64),
                          proj=qp, resid=qr)
        ntop = _bounds(qb, _IndexArrays(*ix.arrays), no_penalty, np.inf, s)
        key, lb = s.key.copy(), s.lb.copy()
        d = ((hl[ix.rows].astype(np.int64) - q.astype(np.int64)) ** 2).sum(axis=1)
        assert np.all(key == 0.0) and np.all(lb <= d)
        # the rows scored first: the 8 smallest bounds, ascending, ties in row order
        assert list(s.top[:ntop]) == list(np.argsort(lb, kind="stable")[:8])
        cap = float(np.sort(lb)[3])  # a known E: rows above it are left out of both
        ntop = _bounds(qb, _IndexArrays(*ix.arrays), no_penalty, cap, s)
        kept = lb <= cap
        assert np.array_equal(s.lb[kept], lb[kept]) and np.all(s.lb[~kept] == np.inf)
        assert list(s.top[:ntop]) == list(np.argsort(lb, kind="stable")[:kept.sum()][:8])
        if kind == "rendered":  # and it is tight enough to prune: most rows above half
            assert np.mean(lb >= 0.5 * d) > 0.5


def test_from_arrays_refuses_what_it_would_wrap_or_truncate(small_rows):
    rows = {k: small_rows[k] for k in ("hlac", "sil_bits", "ridge_bits", "ridge_area")}
    hl = rows["hlac"].astype(np.int32)
    hl[5, 7] = 300
    with pytest.raises(InvalidInputError, match=r"hlac must lie in \[0, 255\], got 300 at index "
                                                r"\(5, 7\)"):
        SearchTables.from_arrays(**dict(rows, hlac=hl))
    with pytest.raises(InvalidInputError, match=r"hlac must be an integer array, got dtype "
                                                r"float64"):
        SearchTables.from_arrays(**dict(rows, hlac=rows["hlac"] + 0.5))
    for value, words in ((np.nan, r"whole numbers, got nan at index \(3,\)"),
                         (-5, r"ridge_area must lie in \[0, 4096\], got -5.0 at index \(3,\)")):
        area = rows["ridge_area"].astype(np.float64)
        area[3] = value
        with pytest.raises(InvalidInputError, match=words):
            SearchTables.from_arrays(**dict(rows, ridge_area=area))
    with pytest.raises(InvalidInputError, match=r"sil_bits must have shape \(240, 64\)"):
        SearchTables.from_arrays(**dict(rows, sil_bits=rows["sil_bits"][:10]))
    t = SearchTables.from_arrays(**rows)
    assert t.hlac.dtype == np.uint8 and np.array_equal(t.ridge_area, rows["ridge_area"])


def test_search_names_an_argument_of_the_wrong_type(small_rows):
    t = _tables(small_rows)
    f = extract_features(small_rows["silhouette"][0])
    with pytest.raises(InvalidInputError, match=r"features must be the Features of a silhouette "
                                                r".*got ndarray"):
        search(small_rows["silhouette"][0], t)
    with pytest.raises(InvalidInputError, match=r"options must be a SearchOptions, got dict "
                                                r"\{'c': 0.2\} \(make one: SearchOptions"):
        search(f, t, options={"c": 0.2})
    with pytest.raises(InvalidInputError, match=r"tables must be SearchTables"):
        search(f, small_rows)
    assert search(f, t).index == search_reference(f, t).index
