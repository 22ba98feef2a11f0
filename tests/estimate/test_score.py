"""The one scoring kernel of E: each status code against the plain definition."""

from __future__ import annotations

import numpy as np
import pytest

from handsynth.db import extract_features
from handsynth.estimate._score import (
    ABOVE_BEST,
    PRUNED,
    SURVIVOR,
    SURVIVOR_ABOVE_BEST,
    Constants,
    Query,
    Rows,
    score,
)


@pytest.mark.parametrize("prune", [True, False])
def test_status_codes_follow_the_definition_of_e(small_rows, query_rows, prune):
    rows = Rows(hlac=small_rows["hlac"], sil_bits=small_rows["sil_bits"],
                ridge_bits=small_rows["ridge_bits"],
                ridge_area=small_rows["ridge_area"].astype(np.float64))
    seen = set()
    for sil in query_rows["silhouette"][:6]:
        f = extract_features(sil)
        q = Query(hlac=f.hlac, sil_bits=f.sil_bits, ridge_bits=f.ridge_bits)
        k = Constants(th1=0.2 * f.ridge_area, c1=0.002, c2=0.03, c3=800.0, c4=800.0, prune=prune)
        p1 = np.bitwise_count(f.ridge_bits[None, :] & ~rows.sil_bits).sum(axis=1)
        p2 = np.bitwise_count(rows.ridge_bits & ~f.sil_bits[None, :]).sum(axis=1)
        a = rows.ridge_area
        stage1 = p1 <= k.th1
        stage2 = p2 <= k.c1 * a * a + k.c2 * a
        if not prune:
            stage1[:] = stage2[:] = True
        d = ((rows.hlac.astype(np.int64) - f.hlac.astype(np.int64)) ** 2).sum(axis=1)
        e = d + (k.c3 * p1 + k.c4 * p2)
        for best_e in (np.inf, float(np.median(e)), float(e.min())):
            for i in range(len(a)):
                st, ei, di, p1i, p2i = score(i, 0.0, best_e, q, rows, k)
                seen.add(st)
                assert p1i == p1[i]
                if not stage1[i]:
                    assert st == PRUNED
                elif k.c3 * p1[i] > best_e:
                    assert st == ABOVE_BEST and p2i == 0
                elif not stage2[i]:
                    assert st == PRUNED and p2i == p2[i]
                elif e[i] > best_e:
                    assert st == SURVIVOR_ABOVE_BEST and ei == np.inf and p2i == p2[i]
                else:
                    assert st == SURVIVOR and (ei, di, p2i) == (e[i], d[i], p2[i])
    expected = {PRUNED, ABOVE_BEST, SURVIVOR_ABOVE_BEST, SURVIVOR} if prune \
        else {ABOVE_BEST, SURVIVOR_ABOVE_BEST, SURVIVOR}
    assert seen == expected  # every branch ran


def test_a_lower_bound_of_the_hlac_distance_gives_up_early(small_rows, query_rows):
    rows = Rows(hlac=small_rows["hlac"], sil_bits=small_rows["sil_bits"],
                ridge_bits=small_rows["ridge_bits"],
                ridge_area=small_rows["ridge_area"].astype(np.float64))
    f = extract_features(query_rows["silhouette"][0])
    q = Query(hlac=f.hlac, sil_bits=f.sil_bits, ridge_bits=f.ridge_bits)
    k = Constants(th1=np.inf, c1=0.0, c2=0.0, c3=1.0, c4=1.0, prune=False)
    st, e, d = score(0, 0.0, np.inf, q, rows, k)[:3]
    assert st == SURVIVOR
    # the same row with a bound that puts it above the best: P2 not counted
    assert score(0, e, e - 1.0, q, rows, k)[0] == ABOVE_BEST
    assert score(0, 0.0, e, q, rows, k)[:3] == (SURVIVOR, e, d)  # E == best: a survivor
