"""Non-dominated setups (Kabir Sec. IV): packed-bitset algorithm against a brute-force subset test."""


import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from mavac.planning.dominance import dominated_by_any, first_of_each_row, nondominated, pack_rows, row_groups


def nondominated_brute(cover):
    """Keep j unless some other row is a proper superset, or an equal row has a lower index."""
    cover = np.asarray(cover, bool)
    keep = []
    for j, row in enumerate(cover):
        if not row.any():
            continue
        dominated = False
        for k, other in enumerate(cover):
            if k == j or np.any(row & ~other):
                continue
            if np.any(other & ~row) or k < j:
                dominated = True
                break
        if not dominated:
            keep.append(j)
    return np.array(keep, dtype=np.int64)


@settings(max_examples=200, deadline=None)
@given(arrays(bool, st.tuples(st.integers(0, 14), st.integers(0, 140))))
def test_matches_brute_force(cover):
    np.testing.assert_array_equal(nondominated(cover), nondominated_brute(cover))


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_nested_random_families(seed):
    """Many nested and duplicated rows (the hard case for a subset test)."""
    rng = np.random.default_rng(seed)
    base = rng.random((6, 90)) < 0.5
    rows = [base[rng.integers(6)] & (rng.random(90) < rng.uniform(0.3, 1.0)) for _ in range(30)]
    cover = np.vstack([base, rows, base[:2]])
    cover = cover[rng.permutation(len(cover))]
    np.testing.assert_array_equal(nondominated(cover), nondominated_brute(cover))


def test_duplicates_keep_lowest_index_and_empty_rows_go():
    cover = np.array([[0, 0, 0], [1, 1, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1]], bool)
    np.testing.assert_array_equal(nondominated(cover), [1, 4])


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 40), st.integers(1, 4))
def test_first_of_each_row_is_the_index_np_unique_returns(seed, m, words):
    """Rows drawn from a few patterns, so most repeat; the full range of uint64 values."""
    rng = np.random.default_rng(seed)
    patterns = rng.integers(0, 2**64, (5, words), dtype=np.uint64, endpoint=False)
    rows = patterns[rng.integers(0, 5, m)]
    _, expected = np.unique(rows, axis=0, return_index=True)
    first = first_of_each_row(rows)
    assert first.dtype == np.int64
    np.testing.assert_array_equal(np.sort(first), np.sort(expected))


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 40), st.integers(1, 4))
def test_row_groups_number_np_uniques_groups_by_first_row(seed, m, words):
    rng = np.random.default_rng(seed)
    patterns = rng.integers(0, 256, (4, words), dtype=np.uint8)
    rows = patterns[rng.integers(0, 4, m)]
    groups = row_groups(rows)
    assert groups.dtype == np.int64 and groups.shape == (m,)
    if m == 0:
        return
    _, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    np.testing.assert_array_equal(groups, rank[inverse.ravel()])


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 30), st.integers(0, 30), st.integers(1, 200))
def test_dominated_by_any_is_the_subset_test_pair_by_pair(seed, k, m, n):
    """Nested rows (so many candidates have a superset), empty candidates among them."""
    rng = np.random.default_rng(seed)
    sup = rng.random((m, n)) < rng.uniform(0.2, 0.95)
    cand = rng.random((k, n)) < rng.uniform(0.0, 0.5)
    if m:
        cand[::2] &= sup[rng.integers(0, m, len(cand[::2]))]
    expected = [any(not np.any(c & ~s) for s in sup) for c in cand]
    got = dominated_by_any(pack_rows(cand), pack_rows(sup))
    np.testing.assert_array_equal(got, np.array(expected, dtype=bool).reshape(k))


def test_no_setups_and_no_patches():
    assert nondominated(np.zeros((0, 5), bool)).size == 0
    assert nondominated(np.zeros((4, 0), bool)).size == 0


def test_pack_rows_round_trip():
    rng = np.random.default_rng(3)
    cover = rng.random((7, 131)) < 0.4
    words = pack_rows(cover)
    assert words.dtype == np.uint64 and words.shape == (7, 3)
    bits = np.unpackbits(words.view(np.uint8), axis=1, bitorder="little")[:, :131]
    np.testing.assert_array_equal(bits.astype(bool), cover)


def test_bad_cover_is_refused():
    with pytest.raises(ValueError, match="cover"):
        nondominated(np.zeros(5, bool))
    with pytest.raises(ValueError, match="cover"):
        nondominated(np.full((2, 2), 3))


def test_paper_scale_instance_is_exact_on_a_sample():
    """m = 16317 setups over n = 5000 patches (Kabir Sec. IX-A1 grid): local reach discs."""
    rng = np.random.default_rng(0)
    m, n = 16317, 5000
    pts = rng.random((n, 2)).astype(np.float32)
    centres = rng.random((m, 2)).astype(np.float32)
    radius = rng.uniform(0.1, 0.3, m).astype(np.float32)
    cover = np.empty((m, n), bool)
    for a in range(0, m, 2048):
        d2 = ((pts[None] - centres[a:a + 2048, None]) ** 2).sum(-1)
        cover[a:a + 2048] = d2 < radius[a:a + 2048, None] ** 2
    keep = nondominated(cover)
    # Every kept row is not a subset of another kept row; spot-check removed rows.
    kept = cover[keep].astype(np.float32)
    inter = kept @ kept.T
    sizes = kept.sum(1)
    np.fill_diagonal(inter, -1)
    assert not np.any(inter == sizes[:, None])
    removed = np.setdiff1d(np.arange(m), keep)
    sample = cover[rng.choice(removed, 200, replace=False)].astype(np.float32)
    assert np.all((sample @ kept.T == sample.sum(1)[:, None]).any(axis=1))
