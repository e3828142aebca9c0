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
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..params import SAMPLING_VARIANTS, SamplingParams, SetupSpaceParams
from ..tolerances import COUNT_SLACK
from ..validate import check_int, check_positive, check_size
from .dominance import nondominated
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
