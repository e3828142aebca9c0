"""Non-dominated candidate setups (Kabir et al. 2017, Section IV).

"We consider a setup s to be dominated if there exists another setup s' that contains all
the patches covered by s." Dominated setups are removed before the setup planner runs
(Section IV-A, steps iv-v). Note that dropping a dominated setup is only cost-neutral when the
superset is not more expensive; the paper drops them regardless and so does this module.
"""

from __future__ import annotations

import numpy as np

from ..validate import check_cover

# Memory cap (uint64 words) of one block of pairwise subset tests.
_BLOCK_WORDS = 1 << 22
# Word-by-word refutation rounds before the remaining pairs are tested on all words.
_PAIR_ROUNDS = 6


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


def dominated_by_any(cand: np.ndarray, sup: np.ndarray) -> np.ndarray:
    """``out[i]`` True when some row of ``sup`` is a superset of ``cand[i]``."""
    out = np.zeros(len(cand), dtype=bool)
    if len(sup) == 0 or len(cand) == 0:
        return out
    n_words = cand.shape[1]
    not_sup = ~sup
    # Test each candidate's fullest words first: most (candidate, superset) pairs are refuted
    # by one word, and the survivors are tracked as a shrinking list of pairs.
    word_order = np.argsort(-np.bitwise_count(cand), axis=1, kind="stable")
    step = max(1, _BLOCK_WORDS // len(sup))
    for a in range(0, len(cand), step):
        blk = cand[a : a + step]
        wo = word_order[a : a + step]
        k0 = wo[:, 0]
        alive = (blk[np.arange(len(blk)), k0][:, None] & not_sup[:, k0].T) == 0
        i, j = np.nonzero(alive)
        for r in range(1, min(n_words, _PAIR_ROUNDS)):
            if len(i) == 0:
                break
            k = wo[i, r]
            ok = (blk[i, k] & not_sup[j, k]) == 0
            i, j = i[ok], j[ok]
        chunk = max(1, _BLOCK_WORDS // n_words)
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
    order = np.lexsort(words.T[::-1])  # stable: equal rows keep their index order
    ranked = words[order]
    return order[np.r_[True, np.any(ranked[1:] != ranked[:-1], axis=1)]]


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
