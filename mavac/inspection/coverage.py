"""Coverage C and overlap O of a pose set (MAVAC eq. 1-2), as fractions of |S|.

``C_g`` is the union of the elements covered by every pose; ``O_g`` is the union of the pairwise
intersections, i.e. the elements covered at least twice. The paper reports ``|C_g| / |S|`` and
``|O_g| / |S|`` (Results, "Offline computation").

The paper's O (1.9-5.7 % in Table 1) is hard to square with eq. 2 read literally, which counts
every element seen twice; :func:`mean_pairwise_overlap` is the other reading, the mean of
``|A_i & A_j| / |S|`` over the pairs of poses, and the notebooks report both.
"""

from __future__ import annotations

import numpy as np

from ..validate import check_bool_array, check_int


def _as_visibility(visible) -> np.ndarray:
    v = check_bool_array("visible", visible)
    if v.ndim == 1:
        v = v[None, :]
    if v.ndim != 2:
        raise ValueError(f"visible must be a (poses, elements) bool array, got shape {v.shape}")
    return v


def cover_counts(visible) -> np.ndarray:
    """How many poses cover each element.

    Parameters
    ----------
    visible : (h, n) bool
        ``visible[i, j]``: pose i covers element j (``cover(S, Gm_i)`` of eq. 1).

    Returns
    -------
    (n,) int
    """
    return _as_visibility(visible).sum(axis=0).astype(np.int64)


def coverage_overlap(visible, n_elements: int | None = None) -> tuple[float, float]:
    """C and O of eq. 1-2 as fractions of |S|.

    Parameters
    ----------
    visible : (h, n) bool
        Cover sets of the h poses over the n elements of S (h may be 0).
    n_elements : int, optional
        |S|; defaults to ``visible.shape[1]``.

    Returns
    -------
    (C, O) : floats in [0, 1]
        Fraction of S covered at least once, and at least twice.
    """
    v = _as_visibility(visible)
    n = v.shape[1] if n_elements is None else check_int("n_elements", n_elements, 1)
    if n <= 0:
        raise ValueError(f"n_elements must be positive, got {n}")
    counts = v.sum(axis=0)
    return float(np.count_nonzero(counts >= 1)) / n, float(np.count_nonzero(counts >= 2)) / n


def mean_pairwise_overlap(visible, n_elements: int | None = None) -> float:
    """Mean over the pairs of poses i < j of ``|A_i & A_j| / |S|`` (the second reading of O).

    Parameters
    ----------
    visible : (h, n) bool
        Cover sets ``A_i`` of the h poses over the n elements of S.
    n_elements : int, optional
        |S|; defaults to ``visible.shape[1]``.

    Returns
    -------
    float in [0, 1]
        0 with fewer than two poses.
    """
    v = _as_visibility(visible)
    n = v.shape[1] if n_elements is None else int(n_elements)
    if n <= 0:
        raise ValueError(f"n_elements must be positive, got {n}")
    h = v.shape[0]
    if h < 2:
        return 0.0
    counts = v.sum(axis=0).astype(np.int64)
    # sum over pairs of |A_i & A_j| = sum over elements of (pairs of poses covering it)
    shared = int(np.sum(counts * (counts - 1) // 2))
    return shared / (h * (h - 1) // 2) / n
