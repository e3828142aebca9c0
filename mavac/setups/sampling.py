"""Candidate setups for Kabir et al. (2017), Section IV: uniform grids, hierarchical uniform
sampling with gradient descent (IV-A2), random sampling with gradient descent (IV-A3), the six
gradient-descent variants of Table I and the conservative / absolute scores of IV-B.

Everything here works against an abstract reach function

    reach_fn(setups (k, 3) float) -> (k, n) bool

(``setups`` rows are ``(x [m], y [m], alpha [rad])``, column i of the answer says whether patch i
is reachable), so the same code runs on the Puma 560 reach test of :mod:`mavac.setups.reach`,
on a lookup into a precomputed cover matrix (:func:`lookup_reach`) or on a toy function in a
test. Wrap it in :class:`CountingReach` to count n_rfc the paper's way.

Gradient descent
----------------
The paper "uses gradient descent in the configuration space to optimize the area covered by a
setup" without giving the update rule; coverage is a step function of the setup, so here it is a
*discrete steepest ascent* on the number of covered patches: from the current setup, evaluate
the neighbours one step (``SamplingParams.gd_step_*``) away along each axis of the variant in both
directions, move to the best-scoring neighbour when its score beats the current one, stop
otherwise. Neighbours outside the x/y range are not evaluated; alpha wraps around the circle.
Every move strictly increases the score, so the ascent ends after at most n moves.

Scores (IV-B), with P1 the patches of the current setup and P2 those of a neighbour:
conservative = ``|P2|`` if ``P1 <= P2`` else ``|P1 & P2|`` (a move can only go to a strict
superset, so the patches of the seed stay covered); absolute = ``|P2|``. Type I variants run one
conservative round, Type II ("CA") a conservative round followed by an absolute one.
Variant axes (Table I): ``*_XY`` x and y at fixed alpha; ``*_XY_a`` x and y at fixed alpha, then
alpha alone (both stages in each round); ``*_XYa`` x, y and alpha together. ``"none"`` is the
paper's "without gradient descent".

End-point map
-------------
When reach is a lookup into a grid's cover matrix and the seeds are grid setups (Table IV's
random runs), where a descent ends depends on its seed alone. :func:`endpoint_maps` computes it
for every seed at once (numpy over the seeds, bit-packed covers), with what n_rfc needs, and
:func:`random_sampling_on_map` reads a run from it: the same result as :func:`random_sampling`,
without a descent per run. :func:`gradient_descent` stays the reference (and draws Fig. 8).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..params import SAMPLING_VARIANTS, SamplingParams, SetupSpaceParams
from ..tolerances import COUNT_SLACK, SETUP_KEY_QUANTUM
from ..validate import check_int, check_points, check_positive, check_size
from ..planning.dominance import nondominated, pack_rows
from .reach import CountingReach, lookup_reach, setup_keys  # noqa: F401  (re-exported)

ReachFn = Callable[[np.ndarray], np.ndarray]

#: Table I names (one home: :data:`mavac.params.SAMPLING_VARIANTS`); "a" spells alpha, "none" is
#: sampling without gradient descent.
VARIANTS = SAMPLING_VARIANTS
GD_VARIANTS = VARIANTS[1:]

_STAGES = {"XY": ((0, 1),), "XY_a": ((0, 1), (2,)), "XYa": ((0, 1, 2),)}
_ROUNDS = {"C": ("conservative",), "CA": ("conservative", "absolute")}


def variant_plan(variant: str) -> tuple[tuple[str, ...], tuple[tuple[int, ...], ...]]:
    """Scoring rounds and axis stages of a Table I variant.

    Returns
    -------
    rounds : tuple of ``"conservative"`` / ``"absolute"``
    stages : tuple of axis tuples (0 = x, 1 = y, 2 = alpha), run in order within each round
    """
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")
    if variant == "none":
        return (), ()
    scoring, _, axes = variant.partition("_")
    return _ROUNDS[scoring], _STAGES[axes]


# ---------------------------------------------------------------- setup space and grids


#: Setups a uniform grid may have: 60 times the paper's 16,317 (50 mm x 50 mm x 10 deg); a
#: tiny resolution would otherwise exhaust memory (and the reach sweep would run for days).
MAX_GRID_SETUPS = 1_000_000


def _resolution(space: SetupSpaceParams, resolution) -> np.ndarray:
    if resolution is None:
        return np.array([space.res_x, space.res_y, space.res_alpha], dtype=float)
    res = np.asarray(resolution, dtype=float)
    if res.shape != (3,):
        raise ValueError(f"resolution must be (res_x [m], res_y [m], res_alpha [rad]), got shape {res.shape}")
    for name, r in zip(("res_x", "res_y", "res_alpha"), res):
        check_positive(f"resolution {name}", r)
    return res


def _axis_values(lo: float, hi: float, res: float) -> np.ndarray:
    # Both ends included when the range is a multiple of the step.
    count = int(math.floor((hi - lo) / res + COUNT_SLACK)) + 1
    return lo + res * np.arange(count)


def full_circle(space: SetupSpaceParams) -> bool:
    """Whether the alpha range is the whole circle (then alpha_max is alpha_min again)."""
    return space.alpha_max - space.alpha_min >= 2.0 * math.pi - COUNT_SLACK


def _alpha_values(space: SetupSpaceParams, res: float) -> np.ndarray:
    values = _axis_values(space.alpha_min, space.alpha_max, res)
    if full_circle(space):  # alpha_min + 2 pi is alpha_min: one pose, one setup
        values = values[values < space.alpha_min + 2.0 * math.pi - COUNT_SLACK * res]
    return values


def grid_axes(space: SetupSpaceParams, resolution=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sample values along x [m], y [m] and alpha [rad] of a uniform grid.

    x and y run from their lower bound in steps of the resolution and include the upper bound
    when the range is a multiple of the step. Over the whole circle alpha leaves out
    ``alpha_min + 2 pi``, the same pose as ``alpha_min``: 50 mm x 50 mm x 10 deg over
    [0, 1 m] x [0, 1 m] x [0, 2 pi] gives 21 x 21 x 36 = 15,876 distinct setups. (The paper's
    16,317 = 21 x 21 x 37 counts alpha = 0 and alpha = 2 pi both.)

    Parameters
    ----------
    space : SetupSpaceParams
    resolution : (3,) float, optional
        ``(res_x [m], res_y [m], res_alpha [rad])``; default the space's own resolution.
    """
    res = _resolution(space, resolution)
    return (_axis_values(space.x_min, space.x_max, res[0]),
            _axis_values(space.y_min, space.y_max, res[1]),
            _alpha_values(space, res[2]))


def uniform_setups(space: SetupSpaceParams, resolution=None) -> np.ndarray:
    """All setups of a uniform grid (Section IV-A1), x slowest, alpha fastest; no two rows are
    the same pose.

    Returns
    -------
    (nx * ny * na, 3) float
        Rows ``(x [m], y [m], alpha [rad])``.
    """
    xs, ys, alphas = grid_axes(space, resolution)
    check_size("resolution", _resolution(space, resolution).tolist(), len(xs) * len(ys) * len(alphas),
               MAX_GRID_SETUPS, "setups")
    grid = np.stack(np.meshgrid(xs, ys, alphas, indexing="ij"), axis=-1)
    return grid.reshape(-1, 3)


def coarse_resolution(space: SetupSpaceParams, sampling: SamplingParams) -> np.ndarray:
    """Level-1 resolution of hierarchical sampling: ``coarse_points_*`` values per axis.

    x and y: both ends of the range and evenly between (3 points: 0, half, all of it); alpha over
    the whole circle: ``coarse_points_alpha`` distinct angles (4: 0, 90, 180, 270 deg), else both
    ends. A single point uses the whole range as its step (only the lower bound is sampled).

    Returns
    -------
    (3,) float: ``(res_x [m], res_y [m], res_alpha [rad])``.
    """
    def step(lo, hi, points):
        return (hi - lo) / (points - 1) if points > 1 and hi > lo else max(hi - lo, 1.0)

    alpha = (2.0 * math.pi / sampling.coarse_points_alpha if full_circle(space)
             else step(space.alpha_min, space.alpha_max, sampling.coarse_points_alpha))
    return np.array([step(space.x_min, space.x_max, sampling.coarse_points_x),
                     step(space.y_min, space.y_max, sampling.coarse_points_y), alpha])


def hierarchy_resolution(coarse, level: int) -> np.ndarray:
    """Resolution of level ``level`` (1-based) of hierarchical sampling (Section IX-A2).

    "Sampling resolution was scaled by half along one axis at a time at the different
    hierarchies": level 1 is ``coarse``; each further level halves the next axis in the cycle
    x, y, alpha.
    """
    level = check_int("level", level, lo=1)
    res = np.asarray(coarse, dtype=float).copy()
    for k in range(level - 1):
        res[k % 3] /= 2.0
    return res


def random_setups(space: SetupSpaceParams, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` setups drawn uniformly from the sampling box, ``(count, 3)``."""
    count = check_int("count", count, lo=0)
    lo = np.array([space.x_min, space.y_min, space.alpha_min])
    hi = np.array([space.x_max, space.y_max, space.alpha_max])
    return lo + (hi - lo) * rng.random((count, 3))


# ---------------------------------------------------------------- gradient descent


def score(p1: np.ndarray, p2: np.ndarray, scoring: str) -> np.ndarray:
    """Score of candidate patch sets ``p2`` against the current set ``p1`` (Section IV-B).

    Parameters
    ----------
    p1 : (n,) bool
        Patches of the current setup.
    p2 : (k, n) bool
        Patches of k candidate setups.
    scoring : ``"conservative"`` or ``"absolute"``

    Returns
    -------
    (k,) int
    """
    p2 = np.atleast_2d(np.asarray(p2, dtype=bool))
    if scoring == "absolute":
        return p2.sum(axis=1)
    if scoring == "conservative":
        inter = (p2 & p1).sum(axis=1)
        superset = inter == p1.sum()
        return np.where(superset, p2.sum(axis=1), inter)
    raise ValueError(f"scoring must be 'conservative' or 'absolute', got {scoring!r}")


def _wrap_alpha(alpha: np.ndarray, space: SetupSpaceParams) -> np.ndarray:
    turn = np.mod(alpha - space.alpha_min, 2.0 * math.pi)
    # a float a hair under a full turn is the start again (300 + 60 deg is 0 deg, one setup)
    return space.alpha_min + np.where(turn > 2.0 * math.pi - 1e-9, 0.0, turn)


def neighbours(setup, axes, step, space: SetupSpaceParams) -> np.ndarray:
    """Setups one step away from ``setup`` along each axis in ``axes``, both directions.

    x and y neighbours outside the sampling range are dropped; alpha wraps around when the
    alpha range is the full circle and is dropped at the ends otherwise.

    Returns
    -------
    (k, 3) float, k <= 2 * len(axes), order: axis by axis, minus before plus.
    """
    setup = np.asarray(setup, dtype=float)
    lo = np.array([space.x_min, space.y_min, space.alpha_min])
    hi = np.array([space.x_max, space.y_max, space.alpha_max])
    full_circle = space.alpha_max - space.alpha_min >= 2.0 * math.pi - COUNT_SLACK
    out = []
    for k in axes:
        for sign in (-1.0, 1.0):
            cand = setup.copy()
            cand[k] += sign * step[k]
            if k == 2 and full_circle:
                cand[2] = _wrap_alpha(cand[2], space)
            elif not (lo[k] - COUNT_SLACK <= cand[k] <= hi[k] + COUNT_SLACK):
                continue
            out.append(cand)
    return np.array(out, dtype=float).reshape(-1, 3)


@dataclass
class GDResult:
    """Outcome of one gradient-descent refinement.

    Attributes
    ----------
    setup : (3,) float
        Final setup ``(x, y, alpha)``.
    covered : (n,) bool
        Patches reachable from the final setup.
    path : (p, 3) float
        Setups visited, the seed first, the final setup last.
    path_scores : (p,) int
        Patches covered at each setup of the path.
    round_ends : (r, 3) float
        Setup at the end of each scoring round (conservative first, then absolute for "CA").
    round_end_steps : (r,) int
        Index into ``path`` of each round's end.
    """

    setup: np.ndarray
    covered: np.ndarray
    path: np.ndarray
    path_scores: np.ndarray
    round_ends: np.ndarray
    round_end_steps: np.ndarray


def gd_step(sampling: SamplingParams) -> np.ndarray:
    """Gradient-descent step ``(dx [m], dy [m], dalpha [rad])``."""
    return np.array([sampling.gd_step_x, sampling.gd_step_y, sampling.gd_step_alpha], dtype=float)


def gradient_descent(reach: ReachFn, seed_setup, variant: str, space: SetupSpaceParams,
                     sampling: SamplingParams, seed_cover: np.ndarray | None = None) -> GDResult:
    """Refine one setup by a Table I gradient-descent variant (discrete steepest ascent).

    Parameters
    ----------
    reach : callable
        ``reach(setups (k, 3)) -> (k, n) bool`` (usually a :class:`CountingReach`).
    seed_setup : (3,) float
        Starting setup ``(x [m], y [m], alpha [rad])``.
    variant : str
        One of :data:`VARIANTS` (``"none"`` returns the seed).
    seed_cover : (n,) bool, optional
        Patches of the seed, when already known (saves one reach call).
    """
    rounds, stages = variant_plan(variant)
    cur = np.asarray(seed_setup, dtype=float).reshape(3).copy()
    cov = np.asarray(reach(cur[None]), dtype=bool)[0] if seed_cover is None else np.asarray(seed_cover, bool)
    step = gd_step(sampling)
    path, scores, ends, end_steps = [cur.copy()], [int(cov.sum())], [], []
    for scoring in rounds:
        for axes in stages:
            while True:
                cand = neighbours(cur, axes, step, space)
                if len(cand) == 0:
                    break
                covs = np.asarray(reach(cand), dtype=bool)
                s = score(cov, covs, scoring)
                best = int(np.argmax(s))  # first maximum: deterministic tie-break
                if s[best] <= cov.sum():
                    break
                cur, cov = cand[best], covs[best]
                path.append(cur.copy())
                scores.append(int(cov.sum()))
        ends.append(cur.copy())
        end_steps.append(len(path) - 1)
    return GDResult(setup=cur, covered=cov, path=np.array(path), path_scores=np.array(scores),
                    round_ends=np.array(ends, dtype=float).reshape(-1, 3),
                    round_end_steps=np.array(end_steps, dtype=np.int64))


# ---------------------------------------------------------------- sampling approaches


@dataclass
class SamplingResult:
    """Candidate setups ψ produced by one sampling approach.

    Attributes
    ----------
    setups : (m, 3) float
        Every distinct setup added to ψ, in the order found.
    cover : (m, n) bool
        Patches of each setup.
    nondominated : (k,) int
        Rows of ``setups`` that no other row dominates (input to the setup planner).
    n_rfc : int
        Reach-test calls made by this run.
    covers_target : bool
        Whether the setups cover every target patch.
    level : int
        Hierarchy level at which the target was covered (or the last level tried); 1 for
        uniform sampling; 0 for random sampling.
    samples : int
        Seeds drawn (random sampling) or grid setups evaluated (uniform / hierarchical).
    seeds : (s, 3) float
        The seed setups, in order (before gradient descent).
    """

    setups: np.ndarray
    cover: np.ndarray
    nondominated: np.ndarray
    n_rfc: int
    covers_target: bool
    level: int
    samples: int
    seeds: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    @property
    def nondominated_setups(self) -> np.ndarray:
        """``(k, 3)`` non-dominated setups."""
        return self.setups[self.nondominated]

    @property
    def nondominated_cover(self) -> np.ndarray:
        """``(k, n)`` cover matrix of the non-dominated setups."""
        return self.cover[self.nondominated]


class _Psi:
    """The set ψ of refined setups (distinct by :func:`setup_keys`)."""

    def __init__(self, n: int):
        self.keys: dict[tuple, int] = {}
        self.setups: list[np.ndarray] = []
        self.covers: list[np.ndarray] = []
        self.covered = np.zeros(n, dtype=bool)

    def add(self, setup, cover) -> None:
        k = setup_keys(np.asarray(setup, dtype=float)[None])[0]
        if k not in self.keys:
            self.keys[k] = len(self.setups)
            self.setups.append(np.asarray(setup, dtype=float))
            self.covers.append(np.asarray(cover, dtype=bool))
            self.covered |= cover

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        n = len(self.covered)
        if not self.setups:
            return np.zeros((0, 3)), np.zeros((0, n), dtype=bool)
        return np.array(self.setups), np.array(self.covers)


def _counting(reach: ReachFn) -> CountingReach:
    return reach if isinstance(reach, CountingReach) else CountingReach(reach)


def _target_mask(target, n: int) -> np.ndarray:
    if target is None:
        return np.ones(n, dtype=bool)
    t = np.asarray(target, dtype=bool)
    if t.shape != (n,):
        raise ValueError(f"target must be an (n,) bool mask over the n = {n} patches, got shape {t.shape}")
    return t


def uniform_sampling(reach: ReachFn, space: SetupSpaceParams, *, resolution=None, target=None) -> SamplingResult:
    """Fine-resolution uniform sampling plus dominance elimination (Section IV-A1).

    Parameters
    ----------
    reach : callable
        ``reach(setups (k, 3)) -> (k, n) bool``.
    resolution : (3,) float, optional
        Default: the space's resolution (50 mm x 50 mm x 10 deg).
    target : (n,) bool, optional
        Patches that must be covered (default all); only sets ``covers_target``.
    """
    reach = _counting(reach)
    before = reach.n_rfc
    grid = uniform_setups(space, resolution)
    cover = reach(grid)
    tgt = _target_mask(target, cover.shape[1])
    nd = nondominated(cover)
    return SamplingResult(setups=grid, cover=cover, nondominated=nd, n_rfc=reach.n_rfc - before,
                          covers_target=bool(cover.any(axis=0)[tgt].all()), level=1, samples=len(grid),
                          seeds=grid)


def hierarchical_sampling(reach: ReachFn, space: SetupSpaceParams, sampling: SamplingParams,
                          *, variant: str = "CA_XY", target=None) -> SamplingResult:
    """Hierarchical uniform sampling with gradient descent (Section IV-A2).

    Level 1 is a uniform grid at the coarse resolution (:func:`coarse_resolution`); every
    further level halves one axis (:func:`hierarchy_resolution`). At each level the grid setups
    not seen at an earlier level are refined by ``variant`` and added to ψ; the search stops at
    the first level whose setups cover every target patch, or after ``max_levels``.

    Parameters
    ----------
    reach : callable
        ``reach(setups (k, 3)) -> (k, n) bool``.
    variant : str
        One of :data:`VARIANTS`.
    target : (n,) bool, optional
        Patches to cover (default all). Pass the patches some setup can reach (e.g. from the
        uniform baseline): a patch no setup reaches would make every level run.
    """
    variant_plan(variant)
    reach = _counting(reach)
    before = reach.n_rfc
    coarse = coarse_resolution(space, sampling)
    seen: set = set()
    psi: _Psi | None = None
    tgt = None
    seeds, samples, level = [], 0, 0
    for level in range(1, sampling.max_levels + 1):
        grid = uniform_setups(space, hierarchy_resolution(coarse, level))
        fresh = [i for i, k in enumerate(setup_keys(grid)) if k not in seen]
        seen.update(setup_keys(grid))
        starts = grid[fresh]
        covers = reach(starts)
        if psi is None:
            psi = _Psi(covers.shape[1])
            tgt = _target_mask(target, covers.shape[1])
        for s, c in zip(starts, covers):
            if variant == "none":
                psi.add(s, c)
            else:
                g = gradient_descent(reach, s, variant, space, sampling, seed_cover=c)
                psi.add(g.setup, g.covered)
        seeds.append(starts)
        samples += len(starts)
        if psi.covered[tgt].all():
            break
    setups, cover = psi.arrays()
    return SamplingResult(setups=setups, cover=cover, nondominated=nondominated(cover),
                          n_rfc=reach.n_rfc - before, covers_target=bool(psi.covered[tgt].all()),
                          level=level, samples=samples, seeds=np.concatenate(seeds))


def random_sampling(reach: ReachFn, space: SetupSpaceParams, sampling: SamplingParams,
                    *, variant: str = "CA_XY", seed: int = 0, target=None) -> SamplingResult:
    """Random sampling with gradient descent (Section IV-A3).

    Seeds are drawn one at a time, refined by ``variant`` and added to ψ when new, until ψ covers
    every target patch. With ``SamplingParams.random_on_grid`` the seeds are drawn without
    replacement from the fine uniform grid (so the gradient-descent steps, one fine step each,
    stay on it and the run ends after at most the grid size); otherwise they are drawn from the
    continuous box, at most ``max_random_samples`` of them.

    Parameters
    ----------
    seed : int
        Seed of the ``numpy.random.Generator`` that draws the samples.
    target : (n,) bool, optional
        Patches to cover (default all).
    """
    variant_plan(variant)
    reach = _counting(reach)
    before = reach.n_rfc
    rng = np.random.default_rng(seed)
    if sampling.random_on_grid:
        grid = uniform_setups(space)
        order = rng.permutation(len(grid))
        draw = (grid[j] for j in order)
    else:
        draw = iter(random_setups(space, sampling.max_random_samples, rng))
    psi: _Psi | None = None
    tgt = None
    seeds = []
    for s in draw:
        c = reach(s[None])[0]
        if psi is None:
            psi = _Psi(len(c))
            tgt = _target_mask(target, len(c))
        seeds.append(s)
        if variant == "none":
            psi.add(s, c)
        else:
            g = gradient_descent(reach, s, variant, space, sampling, seed_cover=c)
            psi.add(g.setup, g.covered)
        if psi.covered[tgt].all():
            break
    setups, cover = psi.arrays()
    return SamplingResult(setups=setups, cover=cover, nondominated=nondominated(cover),
                          n_rfc=reach.n_rfc - before, covers_target=bool(psi.covered[tgt].all()),
                          level=0, samples=len(seeds), seeds=np.array(seeds).reshape(-1, 3))


# ---------------------------------------------------------------- end-point map (grid lookups)


@dataclass(frozen=True)
class EndpointMap:
    """Where the gradient descent from every seed of a grid ends (:func:`endpoint_maps`).

    When reach is a lookup into the grid's cover matrix, a descent from a grid seed depends on
    the seed alone, so random-sampling runs (:func:`random_sampling_on_map`) only read this.

    Attributes
    ----------
    variant : str
        One of :data:`VARIANTS`.
    setups : (m, 3) float
        The grid, rows ``(x [m], y [m], alpha [rad])``.
    words : (m, w) uint64
        Patch set of each grid row, bit-packed (:func:`mavac.planning.dominance.pack_rows`).
    n_patches : int
        n, the patch count (the bits used in each row of ``words``).
    end : (m,) int64
        Grid row where the descent from seed j ends.
    end_setup : (m, 3) float
        That end as :func:`gradient_descent` returns it: the seed plus its steps, in the same
        float arithmetic (it may differ from ``setups[end]`` in the last bits).
    round_ends : (m, r) int64
        Grid row at the end of each scoring round (r = 0, 1 or 2).
    tested_ptr : (m + 1,) int64
    tested : (t,) int64
        Distinct grid rows whose reach the descent from seed j asks for, seed included:
        ``tested[tested_ptr[j]:tested_ptr[j + 1]]`` (the n_rfc of a run is the size of their
        union over its seeds, as :class:`CountingReach` counts it).
    """

    variant: str
    setups: np.ndarray
    words: np.ndarray
    n_patches: int
    end: np.ndarray
    end_setup: np.ndarray
    round_ends: np.ndarray
    tested_ptr: np.ndarray
    tested: np.ndarray


@dataclass(frozen=True)
class _Grid:
    """What one descent step reads: the grid's bit-packed covers, their patch counts, the index
    from setup keys to rows, the step and the space."""

    words: np.ndarray
    counts: np.ndarray
    axis_keys: tuple
    ids: np.ndarray
    id_rows: np.ndarray
    step: np.ndarray
    space: SetupSpaceParams


def _keys(setups: np.ndarray) -> np.ndarray:
    """The integers of :func:`setup_keys` of ``setups`` (..., 3), as an int64 array."""
    return np.round(setups / SETUP_KEY_QUANTUM).astype(np.int64)


def _key_ids(axis_keys: tuple, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One int64 per key row from its place in each axis' sorted keys; False where a
    coordinate is not a grid value."""
    ids, hit = np.zeros(len(keys), dtype=np.int64), np.ones(len(keys), dtype=bool)
    for k, values in enumerate(axis_keys):
        at = np.minimum(np.searchsorted(values, keys[:, k]), len(values) - 1)
        hit &= values[at] == keys[:, k]
        ids = ids * len(values) + at
    return ids, hit


def _grid(setups: np.ndarray, words: np.ndarray, step: np.ndarray, space: SetupSpaceParams) -> _Grid:
    keys = _keys(setups)
    axis_keys = tuple(np.unique(keys[:, k]) for k in range(3))
    ids, _ = _key_ids(axis_keys, keys)
    order = np.argsort(ids, kind="stable")
    if np.any(np.diff(ids[order]) == 0):
        raise ValueError("setups must be distinct setups (two rows have the same setup_keys)")
    counts = np.bitwise_count(words).sum(axis=1, dtype=np.int64)
    return _Grid(words, counts, axis_keys, ids[order], order, step, space)


def _rows(g: _Grid, points: np.ndarray) -> np.ndarray:
    """Grid row of each of ``points`` (k, 3) by setup key, -1 for points off the grid."""
    ids, hit = _key_ids(g.axis_keys, _keys(points))
    at = np.minimum(np.searchsorted(g.ids, ids), len(g.ids) - 1)
    return np.where(hit & (g.ids[at] == ids), g.id_rows[at], -1)


def _candidate_setups(g: _Grid, cur: np.ndarray, axes) -> tuple[np.ndarray, np.ndarray]:
    """:func:`neighbours` of every row of ``cur`` (a, 3) at once, in the same float arithmetic.

    Returns
    -------
    cand : (a, s, 3) float
        s = 2 len(axes) slots in the order of :func:`neighbours` (axis by axis, minus first).
    inside : (a, s) bool
        False for a candidate :func:`neighbours` leaves out (out of the x, y or alpha range).
    """
    lo = np.array([g.space.x_min, g.space.y_min, g.space.alpha_min])
    hi = np.array([g.space.x_max, g.space.y_max, g.space.alpha_max])
    circle = full_circle(g.space)
    cands, inside = [], []
    for k in axes:
        for sign in (-1.0, 1.0):
            cand = cur.copy()
            cand[:, k] += sign * g.step[k]
            if k == 2 and circle:
                cand[:, 2] = _wrap_alpha(cand[:, 2], g.space)
                inside.append(np.ones(len(cur), dtype=bool))
            else:
                inside.append((lo[k] - COUNT_SLACK <= cand[:, k]) & (cand[:, k] <= hi[k] + COUNT_SLACK))
            cands.append(cand)
    return np.stack(cands, axis=1), np.stack(inside, axis=1)


def _grows(words: np.ndarray, counts: np.ndarray, a: np.ndarray, b: np.ndarray,
           block: int = 1 << 14) -> np.ndarray:
    """``out[i]``: row ``b[i]`` covers a strict superset of the patches of row ``a[i]``."""
    out = counts[b] > counts[a]
    at = np.flatnonzero(out)
    for s in range(0, len(at), block):  # blocks bound the (k, w) temporaries
        i = at[s:s + block]
        out[i] = ~np.any(words[a[i]] & ~words[b[i]], axis=1)
    return out


@dataclass(frozen=True)
class _Table:
    """Candidates of every grid row along one axis set, from the grid's own floats.

    Attributes
    ----------
    keys : (m, s, 3) int64
        Setup keys of the candidates.
    rows : (m, s) int64
        Their grid rows, -1 when out of range or off the grid.
    grows : (m, s) bool
        The candidate covers a strict superset of the row's patches (a conservative move).
    """

    keys: np.ndarray
    rows: np.ndarray
    grows: np.ndarray


def _table(g: _Grid, setups: np.ndarray, axes) -> _Table:
    """:class:`_Table` of the grid ``setups`` (m, 3) along ``axes``."""
    cand, inside = _candidate_setups(g, setups, axes)
    rows = np.where(inside, _rows(g, cand.reshape(-1, 3)).reshape(inside.shape), -1)
    a, s = np.nonzero(rows >= 0)
    grows = np.zeros(rows.shape, dtype=bool)
    grows[a, s] = _grows(g.words, g.counts, a, rows[a, s])
    return _Table(_keys(cand), rows, grows)


def _step_rows(g: _Grid, t: _Table, pos: np.ndarray, cur: np.ndarray, axes):
    """Candidates of the setups ``cur`` (a, 3) on grid rows ``pos`` (a,).

    A candidate whose key is the table's (the usual case) takes the table's row; one that
    differs, by the rounding a path picks up, is looked up like :func:`lookup_reach` would.

    Returns
    -------
    cand : (a, s, 3) float
    rows : (a, s) int64
        Grid row of each candidate, -1 where :func:`neighbours` leaves it out.
    grows : (a, s) bool
        The candidate is a conservative move (a strict superset of the patches at ``pos``).
    """
    cand, inside = _candidate_setups(g, cur, axes)
    use = inside & (t.rows[pos] >= 0) & np.all(_keys(cand) == t.keys[pos], axis=2)
    rows, grows = np.where(use, t.rows[pos], -1), np.where(use, t.grows[pos], False)
    a, s = np.nonzero(inside & ~use)
    if len(a):
        rows[a, s] = _rows(g, cand[a, s])
        if np.any(rows[a, s] < 0):
            raise KeyError("a gradient-descent step leaves the grid: the steps must be multiples of its "
                           "resolution")
        grows[a, s] = _grows(g.words, g.counts, pos[a], rows[a, s])
    return cand, rows, grows


def _stage(g: _Grid, t: _Table, pos: np.ndarray, cur: np.ndarray, axes, scoring: str):
    """One stage of :func:`gradient_descent` (one scoring, one axis set) from every seed at once.

    Parameters
    ----------
    t : _Table
        Candidates of the grid rows along ``axes``.
    pos : (m,) int64
        Grid row of each seed's current setup.
    cur : (m, 3) float
        That setup as the descent holds it.

    Returns
    -------
    pos, cur : the same after the stage
    tested : (2, t) int64
        Pairs (seed, grid row) of every candidate reach-tested on the way.
    """
    pos, cur = pos.copy(), cur.copy()
    active, tested = np.arange(len(pos)), []
    while len(active):
        cand, rows, grows = _step_rows(g, t, pos[active], cur[active], axes)
        a, s = np.nonzero(rows >= 0)
        tested.append(np.stack([active[a], rows[a, s]]))
        # the score of a candidate that can win a move (absolute: any; conservative: a strict
        # superset, every other conservative score is below |P1|), -1 for the rest
        size = np.where(rows >= 0, g.counts[np.maximum(rows, 0)], -1)
        scores = size if scoring == "absolute" else np.where(grows, size, -1)
        best = np.argmax(scores, axis=1)  # first maximum, as gradient_descent
        move = scores[np.arange(len(active)), best] > g.counts[pos[active]]
        active, best, took = active[move], best[move], np.flatnonzero(move)
        pos[active] = rows[took, best]
        cur[active] = cand[took, best]
    return pos, cur, np.concatenate(tested, axis=1) if tested else np.zeros((2, 0), dtype=np.int64)


def _csr(pairs: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Distinct (seed, row) pairs (2, t) as CSR ``(ptr (m + 1,), rows (k,))`` by seed."""
    code = np.sort(pairs[0] * m + pairs[1])
    code = code[np.r_[True, code[1:] != code[:-1]]]  # (np.unique hashes: slower here)
    ptr = np.zeros(m + 1, dtype=np.int64)
    np.cumsum(np.bincount(code // m, minlength=m), out=ptr[1:])
    return ptr, code % m


@dataclass(frozen=True)
class _Descent:
    """All seeds' descents after some rounds: current rows ``pos`` (m,), setups ``cur`` (m, 3),
    the (seed, row) pairs reach-tested so far and the rows at each round's end."""

    pos: np.ndarray
    cur: np.ndarray
    pairs: tuple
    ends: tuple


def _round(g: _Grid, tables: dict, start: _Descent, stages, scoring: str) -> _Descent:
    """One scoring round (its stages in order) of every seed's descent."""
    pos, cur, pairs = start.pos, start.cur, start.pairs
    for axes in stages:
        pos, cur, tested = _stage(g, tables[axes], pos, cur, axes, scoring)
        pairs += (tested,)
    return _Descent(pos, cur, pairs, start.ends + (pos,))


def endpoint_maps(setups, cover, space: SetupSpaceParams, sampling: SamplingParams,
                  variants=VARIANTS) -> dict[str, EndpointMap]:
    """End of the gradient descent of each variant from every seed of a grid, all seeds at once.

    Reach is the grid's own cover matrix (:func:`lookup_reach` without fallback): each map holds
    what :func:`gradient_descent` gives seed by seed (end, float end setup, round ends, reach
    tests), computed by numpy over the seeds still moving, one step of the discrete steepest
    ascent at a time, on bit-packed covers. A "CA" variant continues its "C" variant's
    conservative round, which is computed once for both.

    Parameters
    ----------
    setups : (m, 3) float
        Grid setups ``(x [m], y [m], alpha [rad])``, distinct; usually :func:`uniform_setups`.
    cover : (m, n) bool
        ``cover[j, i]``: setup j reaches patch i.
    space : SetupSpaceParams
    sampling : SamplingParams
        Only the ``gd_step_*`` are read.
    variants : sequence of str
        Each one of :data:`VARIANTS`.

    Returns
    -------
    dict variant -> EndpointMap

    Raises
    ------
    KeyError
        When a step from some seed leaves the grid (where :func:`lookup_reach` would raise).
    """
    plans = {v: variant_plan(v) for v in variants}
    setups = check_points("setups", setups, 3)
    words = pack_rows(cover)
    m = len(setups)
    if words.shape[0] != m:
        raise ValueError(f"cover must have one row per setup ({m}), got {words.shape[0]}")
    g = _grid(setups, words, gd_step(sampling), space)
    seeds = np.arange(m)
    start = _Descent(seeds, setups.copy(), (np.stack([seeds, seeds]),), ())
    tables = {axes: _table(g, setups, axes) for _, stages in plans.values() for axes in stages}
    rounds_done: dict = {}
    maps = {}
    for v, (rounds, stages) in plans.items():
        d = start
        for i, scoring in enumerate(rounds):
            if (stages, rounds[:i + 1]) not in rounds_done:
                rounds_done[stages, rounds[:i + 1]] = _round(g, tables, d, stages, scoring)
            d = rounds_done[stages, rounds[:i + 1]]
        ptr, rows = _csr(np.concatenate(d.pairs, axis=1), m)
        maps[v] = EndpointMap(variant=v, setups=setups, words=words, n_patches=np.asarray(cover).shape[1],
                              end=d.pos, end_setup=d.cur,
                              round_ends=np.array(d.ends, dtype=np.int64).reshape(len(d.ends), m).T,
                              tested_ptr=ptr, tested=rows)
    return maps


def _union_size(ptr: np.ndarray, rows: np.ndarray, seeds: np.ndarray, m: int) -> int:
    """Distinct rows of the CSR lists of ``seeds`` (k,) together."""
    lens = ptr[seeds + 1] - ptr[seeds]
    at = np.repeat(ptr[seeds] - np.cumsum(lens) + lens, lens) + np.arange(lens.sum())
    hit = np.zeros(m, dtype=bool)
    hit[rows[at]] = True
    return int(hit.sum())


def _psi_order(emap: EndpointMap, order: np.ndarray, need: np.ndarray):
    """The ends a run adds to ψ, drawing the seeds in ``order``, until their patches hold
    ``need`` (packed (w,) uint64).

    Returns
    -------
    found : (k,) int64
        Grid rows of the ends, in the order the run finds them.
    first : (k,) int64
        Place in ``order`` of the seed that first reached each.
    covers : bool
        Whether the last of them completed ``need`` (else every seed was drawn).
    """
    m = len(order)
    seen, acc = np.zeros(m, dtype=bool), np.zeros_like(need)
    found, first = [], []
    start, size = 0, 64
    while start < m:  # blocks of growing size: a run that ends early reads only a few seeds
        ends, at = np.unique(emap.end[order[start:start + size]], return_index=True)
        fresh = ~seen[ends]
        by_time = np.argsort(at[fresh])
        ends, at = ends[fresh][by_time], at[fresh][by_time] + start
        seen[ends] = True
        cum = np.bitwise_or.accumulate(emap.words[ends], axis=0) | acc
        done = np.flatnonzero(np.all((cum & need) == need, axis=1))
        if len(done):
            found.append(ends[:done[0] + 1])
            first.append(at[:done[0] + 1])
            return np.concatenate(found), np.concatenate(first), True
        found.append(ends)
        first.append(at)
        acc = cum[-1] if len(cum) else acc
        start, size = start + size, 2 * size
    return np.concatenate(found), np.concatenate(first), False


def random_sampling_on_map(emap: EndpointMap, *, seed: int = 0, target=None) -> SamplingResult:
    """:func:`random_sampling` on the grid of an :class:`EndpointMap`, read from the map.

    The result equals ``random_sampling(CountingReach(lookup_reach(emap.setups, cover)), space,
    sampling, variant=emap.variant, seed=seed, target=target)`` with ``random_on_grid`` when
    ``emap.setups`` is ``uniform_setups(space)``, the grid it draws from: the same seeds (one
    permutation of the grid), setups in the order found (each as the first descent reaching it
    returned it), covers, samples and n_rfc (the reach tests of the drawn seeds' descents,
    each setup once).

    Parameters
    ----------
    seed : int
        Seed of the ``numpy.random.Generator`` that draws the samples.
    target : (n,) bool, optional
        Patches to cover (default all).
    """
    m = len(emap.setups)
    order = np.random.default_rng(seed).permutation(m)
    need = pack_rows(_target_mask(target, emap.n_patches)[None])[0]
    found, first, covers = _psi_order(emap, order, need)
    samples = int(first[-1]) + 1 if covers else m
    drawn = order[:samples]
    cover = np.unpackbits(emap.words[found].view(np.uint8), axis=1, count=emap.n_patches,
                          bitorder="little").astype(bool)
    return SamplingResult(setups=emap.end_setup[order[first]], cover=cover, nondominated=nondominated(cover),
                          n_rfc=_union_size(emap.tested_ptr, emap.tested, drawn, m), covers_target=covers,
                          level=0, samples=samples, seeds=emap.setups[drawn])
