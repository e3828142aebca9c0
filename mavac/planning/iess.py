"""Initial estimate of the setup size (Kabir et al. 2017, Section V-B1, Algorithm 5).

Algorithm 5 draws setups uniformly at random, without replacement, until every patch is
covered, repeats that ``N_repeat`` times and returns the smallest number of draws. The
theorem (eq. 5) gives the probability that the unique minimum cover of size ``q`` among
``m`` setups is found at least once: ``1 - (1 - p)^N_repeat`` with ``p = q!(m-q)!/m!``
(eq. 6), i.e. ``p = 1 / C(m, q)``. Section IX-B picks ``N_repeat`` as the smallest value that
reaches a target probability (0.90) for the worst ``q`` (Fig. 9 a-d: a bell in ``q``,
highest near ``m / 2``).
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..validate import check_cover, check_int, check_range


def _check_prob(prob) -> float:
    return float(check_range("prob", prob, 0.0, 1.0, lo_open=True, hi_open=True))


def _check_qm(q, m) -> tuple[int, int]:
    m = check_int("m", m, 1)
    q = check_int("q", q, 1, m)
    return q, m


def p_single_trial(q: int, m: int) -> float:
    """Probability that one trial of Algorithm 5 draws the unique minimum cover (eq. 6).

    ``p = q! (m - q)! / m! = 1 / C(m, q)``, from the exact integer binomial (no factorial
    overflow; a binomial beyond float range gives 0.0).
    """
    q, m = _check_qm(q, m)
    ways = math.comb(m, q)
    return 1.0 / ways if ways < 2**1023 else 0.0


def p_find_min_cover(q: int, m: int, n_repeat: int) -> float:
    """Probability that Algorithm 5 finds the unique minimum cover (theorem, eq. 5).

    Parameters
    ----------
    q : int
        Size of the unique minimum set cover, ``1 <= q <= m``.
    m : int
        Number of candidate setups.
    n_repeat : int
        Number of random trials ``N_repeat >= 1``.

    Returns
    -------
    float
        ``1 - (1 - 1/C(m, q))^n_repeat``, evaluated as ``-expm1(n_repeat log1p(-p))`` so that
        it stays accurate for tiny ``p`` (large ``m``). Equals 1 when ``q == m`` (the paper's
        remark: the whole set is then always found).
    """
    q, m = _check_qm(q, m)
    n_repeat = check_int("n_repeat", n_repeat, 1)
    if q == m:
        return 1.0
    p = p_single_trial(q, m)
    return float(-math.expm1(n_repeat * math.log1p(-p)))


def n_repeat_for(m: int, q: int, prob: float = 0.9) -> int:
    """Smallest ``N_repeat`` with ``p_find_min_cover(q, m, N_repeat) >= prob`` (Section IX-B).

    ``N = ceil(log(1 - prob) / log(1 - p))``, corrected by one step either way so that the
    returned value is exactly the smallest one meeting the target under
    :func:`p_find_min_cover`.
    """
    q, m = _check_qm(q, m)
    prob = _check_prob(prob)
    if q == m:
        return 1
    p = p_single_trial(q, m)
    if p == 0.0:
        raise ValueError(f"q={q}, m={m}: C(m, q) exceeds float range, N_repeat is unbounded")
    n = max(1, math.ceil(math.log1p(-prob) / math.log1p(-p)))
    while p_find_min_cover(q, m, n) < prob:
        n += 1
    while n > 1 and p_find_min_cover(q, m, n - 1) >= prob:
        n -= 1
    return n


def n_repeat_for_all_q(m: int, prob: float = 0.9) -> tuple[np.ndarray, np.ndarray]:
    """``N_repeat`` against ``q = 1 .. m - 1`` for one ``m`` (Fig. 9 a-d).

    Returns
    -------
    q : (m - 1,) int
    n_repeat : (m - 1,) int
        The bell curve of the paper, highest at ``q = floor(m/2)`` and ``ceil(m/2)``.
    """
    m = check_int("m", m, 2)
    prob = _check_prob(prob)
    qs = np.arange(1, m, dtype=np.int64)
    return qs, np.array([n_repeat_for(m, int(q), prob) for q in qs], dtype=np.int64)


def n_repeat_recommended(m: int, prob: float = 0.9) -> int:
    """The paper's choice: the largest ``N_repeat`` over ``q``, reached at ``q = ceil(m/2)``.

    For ``m == 1`` a single trial suffices.
    """
    m = check_int("m", m, 1)
    prob = _check_prob(prob)
    if m == 1:
        return 1
    return n_repeat_for(m, math.ceil(m / 2), prob)


def initial_estimate_of_setup_size(
    cover, n_repeat: int, *, seed: int | np.random.Generator = 0, deadline: float | None = None
) -> int:
    """Algorithm 5: the smallest cover size found by ``n_repeat`` random draws.

    Parameters
    ----------
    cover : (m, n) bool
        ``cover[j, i]`` is True when setup j reaches patch i. Patches that no setup covers are
        ignored (the cover target is the union of all setups).
    n_repeat : int
        ``N_repeat >= 1``.
    seed : int or numpy.random.Generator
    deadline : float, optional
        ``time.perf_counter()`` value after which the remaining trials are skipped (the
        planner's ``T_max`` covers Algorithm 5 too); at least one trial always runs.

    Returns
    -------
    int
        ``min(N)``; 0 when there is nothing to cover.

    Notes
    -----
    The pseudo-code initialises ``psi`` once (step 1) but the theorem's proof draws each trial
    from the whole ``S``, so ``psi`` is reset at every trial here. A trial stops early as soon
    as it can no longer beat the current minimum, which does not change ``min(N)``.
    """
    c = check_cover(cover)
    n_repeat = check_int("n_repeat", n_repeat, 1)
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    m = c.shape[0]
    masks = row_bitsets(c)
    target = 0
    for b in masks:
        target |= b
    if target == 0:
        return 0
    best = m
    for trial in range(n_repeat):
        if deadline is not None and trial > 0 and time.perf_counter() > deadline:
            break
        perm = rng.permutation(m)
        left = target
        for k in range(min(best, m)):
            left &= ~masks[perm[k]]
            if not left:
                best = k + 1
                break
        if best == 1:
            break
    return best


def row_bitsets(cover: np.ndarray) -> list[int]:
    """Each row of a boolean matrix as a Python int (bit i = column i)."""
    packed = np.packbits(cover, axis=1, bitorder="little")
    return [int.from_bytes(row.tobytes(), "little") for row in packed]
