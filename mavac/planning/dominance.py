"""Non-dominated candidate setups (Kabir et al. 2017, Section IV).

"We consider a setup s to be dominated if there exists another setup s' that contains all
the patches covered by s." Dominated setups are removed before the setup planner runs
(Section IV-A, steps iv-v). Note that dropping a dominated setup is only cost-neutral when the
superset is not more expensive; the paper drops them regardless and so does this module.
"""

from __future__ import annotations

import numpy as np

from ..validate import check_cover

# Memory cap (array elements) of one block of pairwise subset tests.
_BLOCK_WORDS = 1 << 22


def pack_rows(cover) -> np.ndarray:
    """Pack each setup's patch set into 64-bit words.

    Parameters
    ----------
    cover : (m, n) bool
        ``cover[j, i]`` is True when setup j reaches patch i.

    Returns
    -------
    (m, ceil(n / 64)) uint64
        Row j holds the bits of ``cover[j]`` (zero padded).
    """
    c = check_cover(cover)
    m, n = c.shape
    n_words = max(1, -(-n // 64))
    packed = np.zeros((m, n_words * 8), dtype=np.uint8)
    if n:
        packed[:, : -(-n // 8)] = np.packbits(c, axis=1, bitorder="little")
    return packed.view(np.uint64)


def _bits(words: np.ndarray) -> np.ndarray:
    """Packed rows (k, w) uint64 back to (k, 64 w) bool, patch i at column i."""
    return np.unpackbits(np.ascontiguousarray(words).view(np.uint8), axis=1, bitorder="little").view(bool)


def dominated_by_any(cand: np.ndarray, sup: np.ndarray) -> np.ndarray:
    """``out[i]`` True when some row of ``sup`` is a superset of ``cand[i]``.

    A superset holds every patch of the candidate, so only the rows of ``sup`` holding the
    candidate's rarest patch (the one fewest rows of ``sup`` hold) are tested, on every word.
    """
    out = ~cand.any(axis=1)  # the empty set is in every row
    if len(sup) == 0 or len(cand) == 0:
        return np.zeros(len(cand), dtype=bool)
    sup_bits = _bits(sup)
    held = sup_bits.sum(axis=0)
    not_sup = ~sup
    step = max(1, _BLOCK_WORDS // max(len(sup), sup_bits.shape[1]))
    chunk = max(1, _BLOCK_WORDS // cand.shape[1])
    for a in range(0, len(cand), step):
        blk = cand[a : a + step]
        rarest = np.argmin(np.where(_bits(blk), held, len(sup) + 1), axis=1)
        i, j = np.nonzero(sup_bits[:, rarest].T)
        for c in range(0, len(i), chunk):
            ic, jc = i[c : c + chunk], j[c : c + chunk]
            ok = ((blk[ic] & not_sup[jc]) == 0).all(axis=1)
            out[a + ic[ok]] = True
    return out


def first_of_each_row(words: np.ndarray) -> np.ndarray:
    """Lowest index of each distinct row of ``words`` (m, w), in lexicographic order of the rows.

    The same indices as ``np.unique(words, axis=0, return_index=True)`` (in another order), by a
    stable lexsort over the columns: ``np.unique`` sorts the rows as opaque bytes, 15-30 times
    slower on the covers of notebook 07.

    Returns
    -------
    (k,) int64
    """
    if len(words) == 0:
        return np.zeros(0, dtype=np.int64)
    order, starts = _sorted_rows(words)
    return order[starts]


def _sorted_rows(words: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row order of a stable lexsort of ``words`` (m, w), m >= 1, and where each run of equal
    rows starts in it, (m,) bool."""
    order = np.lexsort(words.T[::-1])  # stable: equal rows keep their index order
    ranked = words[order]
    return order, np.r_[True, np.any(ranked[1:] != ranked[:-1], axis=1)]


def row_groups(words: np.ndarray) -> np.ndarray:
    """Group of each row of ``words`` (m, w): equal rows share a group, and the groups are
    numbered in the order of their first rows. The ``rank[inverse]`` of
    ``np.unique(words, axis=0, return_index=True, return_inverse=True)`` with the unique rows
    ranked by first index, by the lexsort of :func:`first_of_each_row`.

    Returns
    -------
    (m,) int64
    """
    if len(words) == 0:
        return np.zeros(0, dtype=np.int64)
    order, starts = _sorted_rows(words)
    firsts = order[starts]
    rank = np.empty(len(firsts), dtype=np.int64)
    rank[np.argsort(firsts, kind="stable")] = np.arange(len(firsts))
    groups = np.empty(len(words), dtype=np.int64)
    groups[order] = rank[np.cumsum(starts) - 1]
    return groups


def nondominated(cover) -> np.ndarray:
    """Indices of the non-dominated, non-empty setups.

    A setup is dominated when another setup covers a superset of its patches. Among setups
    with identical patch sets the lowest index is kept. Setups covering no patch are removed.

    Parameters
    ----------
    cover : (m, n) bool
        ``cover[j, i]`` is True when setup j reaches patch i.

    Returns
    -------
    (k,) int
        Sorted indices into the rows of ``cover``.

    Notes
    -----
    Rows are packed into uint64 words and processed by decreasing patch count, so each row is
    only tested against the non-dominated rows kept so far (a superset of a dominated row is
    dominated by that row's dominator too); the tests are vectorised in blocks.
    """
    words = pack_rows(cover)
    m = words.shape[0]
    if m == 0:
        return np.zeros(0, dtype=np.int64)
    counts = np.bitwise_count(words).sum(axis=1, dtype=np.int64)
    first = first_of_each_row(words)
    first = first[counts[first] > 0]
    # Decreasing count; a proper superset always has a strictly larger count.
    order = first[np.lexsort((first, -counts[first]))]
    kept: list[np.ndarray] = []
    kept_words = np.zeros((0, words.shape[1]), dtype=np.uint64)
    block = 256
    for a in range(0, len(order), block):
        idx = order[a : a + block]
        idx = idx[~dominated_by_any(words[idx], kept_words)]
        # Within the block: distinct rows, so any other row that is a superset dominates.
        w = words[idx]
        inside = (w[:, None, :] & ~w[None, :, :]) == 0
        inside = inside.all(axis=2)
        np.fill_diagonal(inside, False)
        idx = idx[~inside.any(axis=1)]
        if len(idx):
            kept.append(idx)
            kept_words = np.concatenate([kept_words, words[idx]])
    if not kept:
        return np.zeros(0, dtype=np.int64)
    return np.sort(np.concatenate(kept)).astype(np.int64)
