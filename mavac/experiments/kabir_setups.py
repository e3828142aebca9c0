"""Notebooks 06-08: Kabir et al. (2017) Tables II-VI and Figs. 6-9 on our re-created objects.

Every function returns a pandas DataFrame (or arrays for a figure) so the notebooks stay thin.
Each object's setup space is placed by the paper's narrowing procedure (a wide coarse sweep,
setups reaching no patch dropped, the bounding box of the rest: :mod:`mavac.setups.space`) and
carried by its :class:`Baseline`. The uniform baseline sweep (Table II) is cached on disk; the
sampling experiments (Tables III,
IV, Figs. 7-8) answer grid setups from the baseline's cover matrix (:func:`lookup_reach`, the
exact reach results) and compute off-grid setups with the reach test, counting n_rfc either
way; the planner experiments (Tables V, VI) run the DFBnB of :mod:`mavac.planning.setcover`
beside its MILP certificate.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib import patheffects
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from scipy.optimize import Bounds, LinearConstraint, milp

from ..geometry.parts import load_part
from ..parallel import map_trials
from ..params import ReachParams, SamplingParams, SetupPlannerParams, SetupSpaceParams
from ..planning.certified import certified_cover
from ..planning.iess import n_repeat_for, p_find_min_cover
from ..planning.instances import write_instance
from ..planning.reduction import reduce_instance
from ..planning.setcover import (dfbnb_setup_cover, execution_time_area_passes, milp_remaining_cover,
                                 milp_setup_cover, setup_costs_from_times)
from ..robots.models import puma560
from ..planning.dominance import nondominated, pack_rows
from ..setups.reach import (CountingReach, FeasibleReach, PartReach, SharedReach, base_T_part, cached_reach_sweep,
                            lookup_reach, reach_targets_from_part)
from ..setups.space import WIDE_RESOLUTION, box_summary, narrowed_square, pedestal_clear, wide_setup_space
from ..setups.sampling import (VARIANTS, EndpointMap, coarse_resolution, endpoint_maps, gradient_descent,
                               hierarchical_sampling, random_sampling_on_map, uniform_setups, variant_plan)
from ..viz.plots import discrete_colorbar, new_figure, plot_mesh

#: Kabir Fig. 6 / Tables II-VI objects, in the paper's order.
OBJECTS = ("sine", "schwefel", "concave_bowl", "hyperboloid")
#: Kabir Table V and VI objects (the paper drops the Schwefel, whose optimum is one setup).
PLANNER_OBJECTS = ("hyperboloid", "sine", "concave_bowl")
ROBOT = "puma560"

#: Notebooks 06-08 in fast mode and at paper scale: the fine grid (Kabir Sec. IX-A1: 50 mm x
#: 50 mm x 10 deg; fast: 250 mm x 250 mm x 60 deg), the wide sweep that places the setup space
#: (fast: 0.4 m x 0.4 m x 90 deg) and the node limit of every planner row (Tables V-VI; ours).
GRID_RESOLUTION = {"fast": (0.25, 0.25, math.radians(60.0)), "paper": (0.05, 0.05, math.radians(10.0))}
WIDE_RESOLUTIONS = {"fast": (0.4, 0.4, math.radians(90.0)), "paper": WIDE_RESOLUTION}
PLANNER_MAX_NODES = {"fast": 20_000, "paper": 2_000_000}


# ---------------------------------------------------------------- baseline (Table II)


@dataclass
class Baseline:
    """Uniform-grid reach sweep of one object over its setup space.

    Attributes
    ----------
    name : str
    space : SetupSpaceParams
        The object's setup space (placed by :func:`placed_space` or given).
    setups : (m, 3) float
    cover : (m, n) bool
    area : (n,) float, m^2
    passes : (n,) int
    seed : int
        Stain seed of the part.
    removed : int
        Grid placements refused by the pedestal test (they reach nothing; still counted in
        n_rfc, one reach-test call per grid setup as in the paper).
    """

    name: str
    space: SetupSpaceParams
    setups: np.ndarray
    cover: np.ndarray
    area: np.ndarray
    passes: np.ndarray
    seed: int = 0
    removed: int = 0

    @property
    def coverable(self) -> np.ndarray:
        """(n,) bool: patches some grid setup reaches."""
        return self.cover.any(axis=0)

    @functools.cached_property
    def nondominated(self) -> np.ndarray:
        """(k,) int: rows of the non-dominated grid setups (computed once)."""
        return nondominated(self.cover)

    @functools.cached_property
    def min_setups(self) -> int:
        """Table II's optimum: fewest grid setups covering every coverable patch (computed once;
        Tables II-IV all need it)."""
        return min_cover_size(self.cover[self.nondominated])

    def reach(self, reach_params: ReachParams):
        """Exact reach function: grid setups from the sweep, others by the reach test (setups
        the pedestal test refuses reach nothing, as in the sweep)."""
        part = load_part(self.name, seed=self.seed)
        robot = puma560(reach_params.tool_length)
        live = PartReach(robot, reach_targets_from_part(part), self.space, params=reach_params,
                         part_mesh=part.mesh if reach_params.check_collision else None)
        clear = pedestal_clear(robot, part.mesh.vertices, self.space)
        return lookup_reach(self.setups, self.cover, fallback=live if clear is None else FeasibleReach(live, clear))


def _sweep(part, space: SetupSpaceParams, reach_params: ReachParams, n_jobs):
    """Reach sweep of the uniform grid of ``space``; placements the pedestal test refuses are
    removed before it (they reach nothing). Returns ``setups, cover, removed (k,) bool``."""
    targets = reach_targets_from_part(part)
    setups = uniform_setups(space)
    clear = pedestal_clear(puma560(reach_params.tool_length), part.mesh.vertices, space)
    keep = np.ones(len(setups), dtype=bool) if clear is None else clear(setups)
    cover = np.zeros((len(setups), targets.n_patches), dtype=bool)
    if keep.any():
        cover[keep] = cached_reach_sweep(ROBOT, targets.positions, targets.axes, targets.patch_targets, setups[keep],
                                         space, reach_params, n_jobs=n_jobs,
                                         part_mesh=part.mesh if reach_params.check_collision else None)
    return setups, cover, ~keep


def paper_square(names, fine: SetupSpaceParams, reach_params: ReachParams, *, wide_resolution=WIDE_RESOLUTION,
                 n_jobs: int | None = None, seed: int = 0):
    """The one setup square of every object, by the paper's narrowing (Sec. IV-A) run over
    ``names`` together (cached sweeps).

    One wide region (the table side of the robot, wide enough for the largest stain,
    :func:`mavac.setups.space.wide_setup_space`) is swept at a coarse resolution for each object,
    placements refused by the pedestal test removed first; the setups reaching no patch are
    eliminated, and the 1 m square keeping the largest share of the rest, summed over the
    objects, is kept (:func:`mavac.setups.space.narrowed_square`).

    Returns
    -------
    space : SetupSpaceParams
        The square, at ``fine``'s resolution, alpha range and table height.
    info : DataFrame
        One row per object: ``wide_setups``, ``wide_removed_pedestal``, ``wide_reaching``,
        ``reaching_in_square`` and its ``share``, the square's corners ``x_lo, x_hi, y_lo,
        y_hi`` (base frame, m), and ``count_rule_x_lo, count_rule_y_lo``: the corner the other
        reading of the rule picks (the most reaching setups of all objects together, unweighted).
    """
    parts = {name: load_part(name, seed=seed) for name in names}
    robot = puma560(reach_params.tool_length)
    every = np.concatenate([p.patch_vertices.reshape(-1, 3) for p in parts.values()])
    wide = wide_setup_space(robot, every, base=fine, resolution=wide_resolution)
    reaching, rows = {}, []
    for name, part in parts.items():
        setups, cover, removed = _sweep(part, wide, reach_params, n_jobs)
        hit = cover.any(axis=1)
        reaching[name] = setups[hit, :2] + [wide.origin_x, wide.origin_y]
        rows.append(dict(object=name, wide_setups=len(setups), wide_removed_pedestal=int(removed.sum()),
                         wide_reaching=int(hit.sum())))
    space, scores = narrowed_square(wide, reaching, size=fine.x_max - fine.x_min, fine=fine)
    by_count = scores[np.lexsort((scores[:, 0], -scores[:, 3]))[0]]  # the other reading: most setups in all
    box = box_summary(space)
    for row in rows:
        xy = reaching[row["object"]]
        inside = ((xy[:, 0] >= box["x_lo"] - 1e-9) & (xy[:, 0] <= box["x_hi"] + 1e-9)
                  & (xy[:, 1] >= box["y_lo"] - 1e-9) & (xy[:, 1] <= box["y_hi"] + 1e-9))
        row.update(reaching_in_square=int(inside.sum()), share=float(inside.mean()), **box,
                   count_rule_x_lo=float(by_count[0]), count_rule_y_lo=float(by_count[1]))
    return space, pd.DataFrame(rows)


def placed_space(name: str, fine: SetupSpaceParams, reach_params: ReachParams, *,
                 wide_resolution=WIDE_RESOLUTION, n_jobs: int | None = None, seed: int = 0):
    """The setup space of ``name``: :func:`paper_square` of the four Table II objects (one for
    all, Kabir IX-A), and that object's row of its ``info``."""
    if name not in OBJECTS:
        raise ValueError(f"name must be one of {OBJECTS}, got {name!r}")
    space, info = paper_square(OBJECTS, fine, reach_params, wide_resolution=wide_resolution, n_jobs=n_jobs,
                               seed=seed)
    return space, info[info.object == name].iloc[0].to_dict()


def baseline(name: str, space: SetupSpaceParams, reach_params: ReachParams, n_jobs: int | None = None,
             seed: int = 0) -> Baseline:
    """Reach sweep of ``name`` (stain draw ``seed``) over the uniform grid of ``space`` (cached
    on disk); ``removed`` counts the grid placements the pedestal test refused."""
    part = load_part(name, seed=seed)
    setups, cover, removed = _sweep(part, space, reach_params, n_jobs)
    return Baseline(name, space, setups, cover, part.patch_areas, part.passes, seed, int(removed.sum()))


def placed_baselines(names, fine: SetupSpaceParams, reach_params: ReachParams, *,
                     wide_resolution=WIDE_RESOLUTION, n_jobs: int | None = None, seed: int = 0):
    """:func:`baseline` of every object over the one :func:`paper_square` of ``OBJECTS``
    (placed with stain draw 0, whatever ``seed``: the square is placed once).

    Returns
    -------
    baselines : dict name -> Baseline
    spaces : DataFrame
        :func:`paper_square`'s ``info`` for ``names``.
    """
    space, info = paper_square(OBJECTS, fine, reach_params, wide_resolution=wide_resolution, n_jobs=n_jobs)
    baselines = {name: baseline(name, space, reach_params, n_jobs=n_jobs, seed=seed) for name in names}
    return baselines, info[info.object.isin(list(names))].reset_index(drop=True)


def min_cover_size(cover) -> int:
    """Fewest setups covering every coverable patch (exact; 0 if nothing is coverable).

    The instance is reduced first (:func:`mavac.planning.reduction.reduce_instance` at unit
    cost: forced setups counted, implied patches and dominated setups dropped). What is left
    needs at least two setups (one covering it all would dominate the others and be forced), so
    a greedy cover of two is optimal and one of three is decided by testing every pair. Beyond,
    the LP relaxation gives a lower bound; when it meets the greedy size that is optimal,
    otherwise :func:`mavac.planning.certified.certified_cover` at unit cost decides (the Table II
    Schwefel in about 1 CPU s, where HiGHS on the whole program took 16), and the unit-cost
    MILP (HiGHS) when its node budgets run out.
    """
    cover = np.asarray(cover, dtype=bool)
    if cover.shape[0] == 0 or not cover.any():
        return 0
    red = reduce_instance(cover, np.ones(cover.shape[0]))
    cols = red.cover
    if cols.shape[1] == 0:
        return len(red.forced)
    left, greedy = np.ones(cols.shape[1], dtype=bool), 0
    while left.any():
        left &= ~cols[np.argmax((cols & left).sum(axis=1))]
        greedy += 1
    if greedy <= 2:
        return len(red.forced) + greedy
    if greedy == 3:
        return len(red.forced) + (2 if _pair_covers(cols) else 3)
    lp = milp(c=np.ones(cols.shape[0]), constraints=LinearConstraint(cols.T.astype(float), lb=1.0),
              bounds=Bounds(0.0, 1.0))
    if lp.status == 0 and math.ceil(lp.fun - 1e-6) >= greedy:
        return len(red.forced) + greedy
    proof = certified_cover(cols, np.ones(cols.shape[0]))
    if proof.status == "optimal":  # unit costs: within rel_tol is exact
        return len(red.forced) + len(proof.setups)
    res = milp_setup_cover(cols, np.ones(cols.shape[0]))
    if not res.optimal:
        raise RuntimeError(f"MILP did not prove optimality: {res.status}")
    return len(red.forced) + len(res.setups)


def _pair_covers(cols: np.ndarray) -> bool:
    """Whether two rows of ``cols`` (m, k) bool together cover every column."""
    words = pack_rows(cols)
    full = pack_rows(np.ones((1, cols.shape[1]), dtype=bool))[0]
    missing = ~words & full
    block = max(1, (1 << 22) // max(1, words.size))
    for a in range(0, len(words), block):
        if np.any(np.all((missing[a:a + block, None, :] & words[None, :, :]) == missing[a:a + block, None, :], axis=2)):
            return True
    return False


def setup_costs(cover, area, passes, setup_time: float, cleaning_rate: float) -> np.ndarray:
    """Eq. 1 cost per setup: ``t_s + sum(area x passes) / cleaning_rate``, (m,) s."""
    return setup_costs_from_times(execution_time_area_passes(cover, area, passes, cleaning_rate), setup_time)


def table2(baselines: dict) -> pd.DataFrame:
    """Kabir Table II: minimum number of setups and non-dominated setups of the uniform grid.

    Columns ``object, seed, setups, nondominated, n_rfc`` (n_rfc = grid size, one call per
    setup), ``removed_pedestal`` (grid placements the pedestal test refused), ``patches``,
    ``coverable`` (patches some grid setup reaches) and ``complete_cover`` (every patch is).
    """
    rows = []
    for name, b in baselines.items():
        coverable = int(b.coverable.sum())
        rows.append(dict(object=name, seed=b.seed, setups=b.min_setups, nondominated=len(b.nondominated),
                         n_rfc=len(b.setups), removed_pedestal=b.removed, patches=b.cover.shape[1],
                         coverable=coverable, complete_cover=coverable == b.cover.shape[1]))
    return pd.DataFrame(rows)


def level1_check(b: Baseline, reach_params: ReachParams, sampling: SamplingParams) -> dict:
    """The 36 level-1 setups of hierarchical sampling (no descent) on ``b``'s square: how many
    reach a patch, whether together they cover every patch the grid covers, and their
    minimum cover (the paper's Table III finds a cover at level 1)."""
    level1 = uniform_setups(b.space, coarse_resolution(b.space, sampling))
    cover = b.reach(reach_params)(level1)
    covered = cover.any(axis=0)
    return dict(object=b.name, seed=b.seed, level1_setups=len(level1), level1_reaching=int(cover.any(axis=1).sum()),
                level1_covers_coverable=bool(np.array_equal(covered, b.coverable)),
                level1_min_setups=min_cover_size(cover[nondominated(cover)]) if covered.any() else 0)


def acceptance_checks(baselines: dict, reach_params: ReachParams, sampling: SamplingParams) -> pd.DataFrame:
    """The setup space's checks per object: ``n_rfc`` against the grid of its space,
    ``removed_pedestal``, ``reached_from_pedestal`` (patches reached from a placement the pedestal
    test refuses; 0 when none stands on it), ``level1_reaching`` of the 36 level-1 setups and
    whether that is at least half, and whether level 1 covers what the grid covers."""
    rows = []
    robot = puma560(reach_params.tool_length)
    for name, b in baselines.items():
        clear = pedestal_clear(robot, load_part(name, seed=b.seed).mesh.vertices, b.space)
        on = np.zeros(len(b.setups), dtype=bool) if clear is None else ~clear(b.setups)
        level1 = level1_check(b, reach_params, sampling)
        rows.append(dict(object=name, n_rfc=len(b.setups), grid_setups=len(uniform_setups(b.space)),
                         removed_pedestal=b.removed, on_pedestal=int(on.sum()),
                         reached_from_pedestal=int(b.cover[on].sum()), level1_reaching=level1["level1_reaching"],
                         level1_half_reach=level1["level1_reaching"] * 2 >= level1["level1_setups"],
                         level1_covers_coverable=level1["level1_covers_coverable"]))
    return pd.DataFrame(rows)


def table2_draws(names, space: SetupSpaceParams, reach_params: ReachParams, seeds, *,
                 sampling: SamplingParams | None = None, n_jobs: int | None = None) -> pd.DataFrame:
    """:func:`table2` with :func:`level1_check` for every stain draw (seed) of every object,
    one baseline in memory at a time (sweeps cached on disk)."""
    sampling = SamplingParams() if sampling is None else sampling
    rows = []
    for seed in seeds:
        for name in names:
            b = baseline(name, space, reach_params, n_jobs=n_jobs, seed=int(seed))
            row = table2({name: b}).iloc[0].to_dict()
            row.update({k: v for k, v in level1_check(b, reach_params, sampling).items() if k.startswith("level1")})
            rows.append(row)
    return pd.DataFrame(rows)


def table2_summary(draws: pd.DataFrame) -> pd.DataFrame:
    """Table II over stain draws: per object the median and range of ``setups`` and
    ``nondominated``, n_rfc, and in how many draws the grid covers every patch and level 1
    covers what the grid covers."""
    rows = []
    for name, g in draws.groupby("object", sort=False):
        rows.append(dict(object=name, draws=len(g), setups=float(g.setups.median()), setups_min=int(g.setups.min()),
                         setups_max=int(g.setups.max()), nondominated=float(g.nondominated.median()),
                         nondominated_min=int(g.nondominated.min()), nondominated_max=int(g.nondominated.max()),
                         n_rfc=int(g.n_rfc.iloc[0]), removed_pedestal=int(g.removed_pedestal.iloc[0]),
                         complete_cover=f"{int(g.complete_cover.sum())} of {len(g)}",
                         level1_reaching_min=int(g.level1_reaching.min()),
                         level1_complete=f"{int(g.level1_covers_coverable.sum())} of {len(g)}"))
    return pd.DataFrame(rows)


def coverage_summary(baselines: dict) -> pd.DataFrame:
    """Patches, reachable fraction and the best single setup per object."""
    rows = []
    for name, b in baselines.items():
        counts = b.cover.sum(axis=1)
        j = int(np.argmax(counts))
        rows.append(dict(object=name, patches=b.cover.shape[1], coverable=int(b.coverable.sum()),
                         uncoverable=int((~b.coverable).sum()), best_single_setup=int(counts[j]),
                         best_x=b.setups[j, 0], best_y=b.setups[j, 1], best_alpha_deg=math.degrees(b.setups[j, 2]),
                         setups_reaching_nothing=int((counts == 0).sum())))
    return pd.DataFrame(rows)


def write_table2_instances(baselines: dict, folder, setup_time: float, cleaning_rate: float) -> list[Path]:
    """Each object's Table II planner instance (non-dominated grid setups, eq. 1 costs) as
    ``folder/kabir_table2_<object>.npz`` (:func:`mavac.planning.instances.write_instance`: arrays
    ``cover``, ``costs``, ``setups``, ``patch_area``), for ``benchmarks/bench_planner.py``."""
    paths = []
    for name, b in baselines.items():
        nd = b.nondominated
        cover = b.cover[nd]
        costs = setup_costs(cover, b.area, b.passes, setup_time, cleaning_rate)
        paths.append(write_instance(Path(folder) / f"kabir_table2_{name}.npz", cover, costs, setups=b.setups[nd],
                                    patch_area=b.area, setup_time=np.float64(setup_time),
                                    cleaning_rate=np.float64(cleaning_rate)))
    return paths


# ---------------------------------------------------------------- sampling (Tables III-IV, Figs. 7-8)


@dataclass(frozen=True)
class _HierarchicalTask:
    """Picklable hierarchical-sampling runs for one object, one per variant (Table III), over
    one reach test whose answers they share (:class:`mavac.setups.reach.SharedReach`); each
    run counts its own n_rfc."""

    baseline: Baseline
    variants: tuple
    optimum: int
    reach_params: ReachParams
    sampling: SamplingParams

    def __call__(self, _=None) -> list[dict]:
        b = self.baseline
        shared = SharedReach(b.reach(self.reach_params))
        rows = []
        for variant in self.variants:
            res = hierarchical_sampling(CountingReach(shared), b.space, self.sampling, variant=variant,
                                        target=b.coverable)
            rows.append(dict(object=b.name, variant=variant, setups=min_cover_size(res.nondominated_cover),
                             level=res.level, n_rfc=res.n_rfc, optimal_setups=self.optimum,
                             covers_target=res.covers_target))
        return rows


def table3(baselines: dict, reach_params: ReachParams, sampling: SamplingParams,
           variants=VARIANTS, n_jobs: int | None = None) -> pd.DataFrame:
    """Kabir Table III: hierarchical uniform sampling with each gradient-descent variant.

    The target is every patch the baseline grid covers. Columns ``object, variant, setups,
    level, n_rfc`` plus ``optimal_setups`` (Table II's optimum) and ``covers_target``.
    """
    tasks = [_HierarchicalTask(b, tuple(variants), b.min_setups, reach_params, sampling) for b in baselines.values()]
    rows = map_trials(_run, tasks, n_jobs=n_jobs, desc="hierarchical sampling")
    return pd.DataFrame([r for task_rows in rows for r in task_rows])


@dataclass(frozen=True)
class _RandomTask:
    """Picklable repetitions of random sampling for one object and variant, read from the
    variant's end-point map of the object's baseline grid."""

    name: str
    seeds: tuple
    emap: EndpointMap
    target: np.ndarray
    optimum: int

    def __call__(self, _=None) -> list[dict]:
        return [self.row(seed, random_sampling_on_map(self.emap, seed=seed, target=self.target))
                for seed in self.seeds]

    def row(self, seed: int, res) -> dict:
        """The :func:`random_runs` row of the run ``res`` (a SamplingResult) drawn with ``seed``."""
        size = min_cover_size(res.nondominated_cover)
        return dict(object=self.name, variant=self.emap.variant, seed=seed, n_rfc=res.n_rfc, samples=res.samples,
                    candidates=len(res.setups), nondominated=len(res.nondominated),
                    covers_target=res.covers_target, setups=size, optimal_setups=self.optimum,
                    optimal=res.covers_target and size == self.optimum)


def _run(task):
    return task()


def random_runs(baselines: dict, sampling: SamplingParams, *, variants=VARIANTS,
                repetitions: int | None = None, n_jobs: int | None = None, chunk: int = 25) -> pd.DataFrame:
    """Kabir IX-A2: ``repetitions`` random-sampling runs per object and variant (seeds 0..r-1).

    Random seeds are drawn on the baseline grid (``sampling.random_on_grid`` must be True), so
    every reach answer comes from the baseline sweep, and a descent from a grid seed ends where
    the variant's end-point map (:func:`endpoint_maps`, built once per object) says: the runs
    read it (:func:`random_sampling_on_map`) and give the rows :func:`random_sampling` would.
    One row per run: ``object, variant, seed, n_rfc, samples, candidates, nondominated,
    covers_target, setups, optimal_setups, optimal``; a run is optimal when its candidates
    cover every patch the baseline covers and their minimum cover has the baseline's optimal
    size. Tasks hold ``chunk`` repetitions each so the workers stay balanced.
    """
    if not sampling.random_on_grid:
        raise ValueError("sampling.random_on_grid must be True: runs are answered from the baseline grid")
    reps = sampling.repetitions if repetitions is None else repetitions
    rows = []
    for name, b in baselines.items():
        if not np.array_equal(b.setups, uniform_setups(b.space)):
            raise ValueError(f"baseline {name!r}: setups must be uniform_setups(space), the grid random sampling draws")
        best = b.min_setups
        maps = endpoint_maps(b.setups, b.cover, b.space, sampling, variants)
        tasks = [_RandomTask(name, tuple(range(a, min(reps, a + chunk))), maps[v], b.coverable, best)
                 for v in variants for a in range(0, reps, chunk)]
        rows += map_trials(_run, tasks, n_jobs=n_jobs, desc=f"random sampling, {name}")
    return pd.DataFrame([r for chunk in rows for r in chunk])


def exhaustion_diagnosis(b: Baseline, sampling: SamplingParams, variant: str = "CA_XY", seed: int = 0) -> dict:
    """Why a random-sampling run exhausts the grid (Fig. 7): the patches it never covers, how
    many grid setups reach each, and whether the seeds that reach them still do after the
    conservative round and after the absolute round of the descent (read from the variant's
    end-point map, :func:`mavac.setups.sampling.endpoint_maps`).

    Returns
    -------
    dict
        ``object, variant, seed, n_rfc, covers_target, missing_patches, grid_setups_reaching_min,
        grid_setups_reaching_max, seeds_reaching_missing, kept_after_conservative,
        kept_after_absolute``.
    """
    target = b.cover.any(axis=0)
    emap = endpoint_maps(b.setups, b.cover, b.space, sampling, (variant,))[variant]
    run = random_sampling_on_map(emap, seed=seed, target=target)
    missing = np.flatnonzero(target & ~run.cover.any(axis=0))
    counts = b.cover[:, missing].sum(axis=0)
    seeds = np.flatnonzero(b.cover[:, missing].any(axis=1)) if len(missing) else np.zeros(0, dtype=np.int64)
    had = b.cover[np.ix_(seeds, missing)]
    rounds, _ = variant_plan(variant)
    # a seed keeps the missing patches it had when the round's end (a grid row) still covers them
    kept = {name: int(np.all(b.cover[np.ix_(ends, missing)] | ~had, axis=1).sum())
            for name, ends in zip(rounds, emap.round_ends[seeds].T)}
    return dict(object=b.name, variant=variant, seed=seed, n_rfc=run.n_rfc, covers_target=run.covers_target,
                missing_patches=len(missing), grid_setups_reaching_min=int(counts.min()) if len(counts) else 0,
                grid_setups_reaching_max=int(counts.max()) if len(counts) else 0,
                seeds_reaching_missing=len(seeds), kept_after_conservative=kept.get("conservative", 0),
                kept_after_absolute=kept.get("absolute"))


def table4(runs: pd.DataFrame) -> pd.DataFrame:
    """Kabir Table IV: likelihood of finding the optimal setup count. Columns ``object, variant,
    p_optimal``."""
    out = runs.groupby(["object", "variant"], sort=False)["optimal"].mean().reset_index()
    return out.rename(columns={"optimal": "p_optimal"})


def landscape(b: Baseline, alpha: float):
    """Patches covered on the x-y grid at the grid alpha nearest ``alpha`` (Kabir Fig. 8).

    Returns
    -------
    xs : (nx,) float, ys : (ny,) float, counts : (nx, ny) int, alpha : float (the grid value used)
    """
    alphas = np.unique(b.setups[:, 2])
    a = float(alphas[np.argmin(np.abs(alphas - alpha))])
    sel = np.isclose(b.setups[:, 2], a)
    xs, ys = np.unique(b.setups[sel, 0]), np.unique(b.setups[sel, 1])
    counts = b.cover[sel].sum(axis=1).reshape(len(xs), len(ys))
    return xs, ys, counts, a


def gd_paths(b: Baseline, sampling: SamplingParams, alpha: float, *, n_paths: int = 8,
             seed: int = 0, variant: str = "CA_XY") -> pd.DataFrame:
    """Gradient-descent paths from random x-y seeds at a fixed grid alpha (Kabir Fig. 8).

    Columns ``path, step, x, y, alpha, covered, conservative_end, absolute_end, variant`` (the
    two ``*_end`` flag the setups where the conservative and the absolute round ended).
    """
    reach = CountingReach(lookup_reach(b.setups, b.cover))
    _, _, _, a = landscape(b, alpha)
    grid = b.setups[np.isclose(b.setups[:, 2], a)]
    rng = np.random.default_rng(seed)
    rows = []
    rounds, _ = variant_plan(variant)
    for k, j in enumerate(rng.choice(len(grid), n_paths, replace=False)):
        g = gradient_descent(reach, grid[j], variant, b.space, sampling)
        ends = dict(zip(rounds, g.round_end_steps.tolist()))
        for step, (s, c) in enumerate(zip(g.path, g.path_scores)):
            rows.append(dict(path=k, step=step, x=s[0], y=s[1], alpha=s[2], covered=int(c),
                             conservative_end=ends.get("conservative") == step,
                             absolute_end=ends.get("absolute") == step, variant=variant))
    return pd.DataFrame(rows)


# ---------------------------------------------------------------- planner (Tables V-VI, Fig. 9)


@dataclass
class PlannerInstance:
    """The 36-candidate instance of Kabir Tables V-VI for one object (level 1 grid, no GD)."""

    name: str
    setups: np.ndarray
    cover: np.ndarray
    area: np.ndarray
    passes: np.ndarray


def planner_instance(b: Baseline, reach_params: ReachParams, sampling: SamplingParams) -> PlannerInstance:
    """Level-1 hierarchical grid without gradient descent, dominated setups removed."""
    res = hierarchical_sampling(CountingReach(b.reach(reach_params)), b.space,
                                dataclasses.replace(sampling, max_levels=1), variant="none")
    return PlannerInstance(b.name, res.nondominated_setups, res.nondominated_cover, b.area, b.passes)


def _dfbnb_row(inst: PlannerInstance, params: SetupPlannerParams, cleaning_rate: float) -> dict:
    """One DFBnB run beside the MILP optimum of the same instance and cost model."""
    patch_time = inst.area * inst.passes / cleaning_rate
    costs = setup_costs(inst.cover, inst.area, inst.passes, params.setup_time, cleaning_rate)
    d = dfbnb_setup_cover(inst.cover, costs, patch_area=inst.area, params=params, setup_time=params.setup_time,
                          patch_time=patch_time)
    if params.cost_model == "remaining":
        m = milp_remaining_cover(inst.cover, params.setup_time, patch_time)
    else:
        m = milp_setup_cover(inst.cover, costs)
    gap = (d.cost - m.cost) / m.cost if (m.optimal and math.isfinite(d.cost) and m.cost > 0) else \
        (0.0 if d.cost == m.cost else math.inf)
    return dict(object=inst.name, nondominated=len(inst.cover), nodes=d.node_expansions, size=len(d.setups),
                seconds=d.seconds, cost=d.cost, milp_cost=m.cost, milp_size=len(m.setups),
                milp_seconds=m.seconds, gap=gap, timed_out=d.timed_out, node_limited=d.node_limited,
                finished=d.finished, iess=d.iess)


def table5(instances: dict, cleaning_rate: float, max_nodes: int, setup_time: float = 60.0) -> pd.DataFrame:
    """Kabir Table V: node expansions with the pruning / guiding heuristics on and off
    (Algorithm 2, bound eq. 2), each run bounded by ``max_nodes`` (deterministic; no time bound).

    Columns ``object, pruning, guiding, nodes, pct_of_off_off, timed_out, node_limited, finished``
    plus ``size, cost, milp_cost, gap``. A row with ``finished`` False stopped at the node
    limit: its count is a lower bound, and so is a percentage that divides by it.
    """
    rows = []
    for inst in instances.values():
        for pruning in (False, True):
            for guiding in (False, True):
                p = SetupPlannerParams(algorithm=2, bound="lb", pruning=pruning, guiding=guiding, t_max=None,
                                       max_nodes=max_nodes, setup_time=setup_time)
                r = _dfbnb_row(inst, p, cleaning_rate)
                rows.append(dict(object=inst.name, pruning=pruning, guiding=guiding, nodes=r["nodes"],
                                 timed_out=r["timed_out"], node_limited=r["node_limited"], finished=r["finished"],
                                 size=r["size"], cost=r["cost"], milp_cost=r["milp_cost"], gap=r["gap"]))
    df = pd.DataFrame(rows)
    off = df[(~df.pruning) & (~df.guiding)].set_index("object").nodes
    df.insert(4, "pct_of_off_off", 100.0 * df.nodes / df.object.map(off))
    return df


def table6(instances: dict, cleaning_rate: float, max_nodes: int, setup_times=(0.0, 60.0, 3000.0),
           n_repeat: int | None = None, cost_models=("fixed", "remaining")) -> pd.DataFrame:
    """Kabir Table VI: Algorithm 2 with eq. 2 (``lb``) and eq. 7 (``b``), Algorithm 4 with eq. 7,
    for each setup time and cost model (``fixed``: each setup's cost over all its patches;
    ``remaining``: the paper's recomputation on the patches not yet cleaned), MILP optimum beside
    each; every run bounded by ``max_nodes``. Columns ``object, cost_model, setup_time, bound,
    algorithm, nodes, size, seconds, milp_cost, gap, timed_out, node_limited, finished`` plus
    ``cost, milp_size, iess``."""
    rows = []
    for inst in instances.values():
        for model in cost_models:
            for ts in setup_times:
                for algorithm, bound in ((2, "lb"), (2, "b"), (4, "b")):
                    p = SetupPlannerParams(algorithm=algorithm, bound=bound, t_max=None, max_nodes=max_nodes,
                                           setup_time=ts, cost_model=model,
                                           n_repeat=n_repeat if algorithm == 4 else None)
                    r = _dfbnb_row(inst, p, cleaning_rate)
                    rows.append(dict(object=inst.name, cost_model=model, setup_time=ts, bound=bound,
                                     algorithm=algorithm, nodes=r["nodes"], size=r["size"], seconds=r["seconds"],
                                     milp_cost=r["milp_cost"], gap=r["gap"], timed_out=r["timed_out"],
                                     node_limited=r["node_limited"], finished=r["finished"], cost=r["cost"],
                                     milp_size=r["milp_size"], iess=r["iess"]))
    return pd.DataFrame(rows)


def fig9(*, ms=(7, 12, 13, 20), prob: float = 0.9, n_repeat_grid=None) -> pd.DataFrame:
    """Kabir Fig. 9 from eq. 5: (a-d) N_repeat reaching ``prob`` against q, (e-h) probability
    against N_repeat for every q. Columns ``panel, m, q, n_repeat, probability``."""
    rows = []
    for m in ms:
        for q in range(1, m):
            n = n_repeat_for(m, q, prob)
            rows.append(dict(panel="n_repeat_vs_q", m=m, q=q, n_repeat=n, probability=p_find_min_cover(q, m, n)))
        top = n_repeat_for(m, math.ceil(m / 2), prob)
        grid = n_repeat_grid if n_repeat_grid is not None else np.unique(
            np.round(np.logspace(0, math.log10(max(2 * top, 10)), 60)).astype(int))
        for q in range(1, m):
            for n in grid:
                rows.append(dict(panel="probability_vs_n_repeat", m=m, q=q, n_repeat=int(n),
                                 probability=p_find_min_cover(q, m, int(n))))
    return pd.DataFrame(rows)


# ---------------------------------------------------------------- figures


#: face colours of Fig. 6: clean, then 1, 2, 3 passes (darker red = more passes)
PASS_COLORS = np.array([[0.78, 0.78, 0.82, 1.0], [1.0, 0.6, 0.6, 1.0], [0.95, 0.25, 0.25, 1.0], [0.7, 0.0, 0.0, 1.0]])
PASS_LABELS = ("clean", "1 pass", "2 passes", "3 passes")


def plot_objects(names=OBJECTS, seed: int = 0):
    """Kabir Fig. 6: the four objects, stain in red (darker = more passes), with a colour bar."""
    fig, axes = new_figure(ncols=len(names), projection="3d", size=(4.5, 4.0))
    for ax, name in zip(np.atleast_1d(axes), names):
        part = load_part(name, seed=seed)
        face_passes = np.zeros(len(part.mesh.faces), dtype=np.int64)
        face_passes[part.stain_faces] = part.passes
        plot_mesh(ax, part.mesh, face_colors=PASS_COLORS[face_passes], alpha=1.0, max_faces=20000)
        ext = part.mesh.extents
        ax.set_title(f"{name}\n{ext[0]:.2f} x {ext[1]:.2f} x {ext[2]:.2f} m, {len(part.stain_faces)} patches")
    discrete_colorbar(fig, list(np.atleast_1d(axes)), PASS_COLORS, PASS_LABELS, "cleaning passes N_i",
                      shrink=0.6, pad=0.02)
    return fig


def contrast_setup(b: Baseline) -> np.ndarray:
    """The grid setup that reaches closest to half of the patches some setup reaches: a reach
    test picture with both reachable and unreachable patches in quantity."""
    reached = b.cover.sum(axis=1)
    target = b.cover.any(axis=0).sum() / 2
    return b.setups[int(np.argmin(np.abs(reached - target)))]


def plot_reach(b: Baseline, setup):
    """One setup seen from above in the robot base frame: reachable patches green, others red,
    the robot's joint-1 axis at the origin and the setup square dashed."""
    part = load_part(b.name, seed=b.seed)
    setup = np.asarray(setup, dtype=float)
    j = int(np.argmin(np.linalg.norm(b.setups - setup, axis=1)))
    space = b.space
    T = base_T_part(b.setups[j][None], space)[0]
    centres = part.mesh.triangles_center[part.stain_faces] @ T[:3, :3].T + T[:3, 3]
    fig, ax = new_figure(size=(6, 5))
    ok = b.cover[j]
    ax.scatter(centres[~ok, 0], centres[~ok, 1], s=2, c="tab:red", label="unreachable patch")
    ax.scatter(centres[ok, 0], centres[ok, 1], s=2, c="tab:green", label="reachable patch")
    ax.plot([0], [0], "k^", ms=8, label="Puma 560 joint 1")
    sq = np.array([[space.x_min, space.y_min], [space.x_max, space.y_min], [space.x_max, space.y_max],
                   [space.x_min, space.y_max], [space.x_min, space.y_min]]) + [space.origin_x, space.origin_y]
    ax.plot(sq[:, 0], sq[:, 1], "k--", lw=1, label="setup space (part origin)")
    circle = np.linspace(0, 2 * np.pi, 200)
    ax.plot(0.864 * np.cos(circle), 0.864 * np.sin(circle), ":", c="grey", lw=1, label="a2 + d4 = 0.864 m")
    ax.set_aspect("equal")
    ax.set_xlabel("base x [m]")
    ax.set_ylabel("base y [m]")
    x, y, a = b.setups[j]
    ax.set_title(f"{b.name}: setup ({x:.2f} m, {y:.2f} m, {math.degrees(a):.0f} deg), "
                 f"{int(ok.sum())}/{len(ok)} patches")
    ax.legend(loc="upper left", fontsize=7)
    return fig


def plot_fig7(runs: pd.DataFrame, grid_size: dict | None = None):
    """Kabir Fig. 7: n_rfc of the random-sampling runs per variant, one panel per object.

    Runs that never covered every coverable patch (``covers_target`` False) drew every setup of
    the grid and stop at its size: they are drawn hatched, with the count of such runs above the
    box, and each object's grid size (``grid_size``, name -> setups) as a dotted line.
    """
    names = list(dict.fromkeys(runs.object))
    fig, axes = new_figure(ncols=len(names), size=(4.0, 3.6))
    for ax, name in zip(np.atleast_1d(axes), names):
        sub = runs[runs.object == name]
        variants = list(dict.fromkeys(sub.variant))
        box = ax.boxplot([sub[sub.variant == v].n_rfc.to_numpy() for v in variants], showfliers=True,
                         patch_artist=True)
        for patch, v in zip(box["boxes"], variants):
            failed = int((~sub[sub.variant == v].covers_target.astype(bool)).sum())
            patch.set_facecolor("white")
            if failed:
                patch.set_hatch("////")
                patch.set_edgecolor("tab:red")
                top = sub[sub.variant == v].n_rfc.max()
                ax.annotate(f"{failed}/{int((sub.variant == v).sum())}", (variants.index(v) + 1, top),
                            textcoords="offset points", xytext=(0, 4), ha="center", fontsize=7, color="tab:red")
        if grid_size and name in grid_size:
            ax.axhline(grid_size[name], color="grey", ls=":", lw=1)
        ax.set_xticks(range(1, len(variants) + 1), variants, rotation=60, fontsize=7)
        ax.set_title(name)
        ax.set_ylabel("n_rfc")
    handles = [Patch(facecolor="white", edgecolor="k", label="runs covering every coverable patch"),
               Patch(facecolor="white", edgecolor="tab:red", hatch="////",
                     label="runs that exhausted the grid without covering it (count above)")]
    if grid_size:
        handles.append(Line2D([], [], color="grey", ls=":", label="grid size of the object's setup space"))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), frameon=False, fontsize=8)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return fig


def plot_fig8(b: Baseline, paths: pd.DataFrame, alpha: float):
    """Kabir Fig. 8: coverage landscape over x-y at fixed alpha with gradient-descent paths
    (black = seed, green = end of the conservative round, red = end of the absolute round), with
    the variant's name and a legend of the stars."""
    xs, ys, counts, a = landscape(b, alpha)
    n = paths.path.nunique()
    cols = min(4, n)
    fig, axes = new_figure(ncols=cols, nrows=math.ceil(n / cols), size=(3.6, 3.2))
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    outline = [patheffects.withStroke(linewidth=2.2, foreground="k")]
    for k, ax in zip(range(n), np.atleast_1d(axes)):
        cs = ax.contourf(X, Y, counts, levels=20, cmap="viridis")
        p = paths[paths.path == k].sort_values("step")
        ax.plot(p.x, p.y, "w-", lw=1, path_effects=outline)
        ax.plot(p.x.iloc[0], p.y.iloc[0], "k*", ms=10)
        cons, absolute = p[p.conservative_end], p[p.absolute_end]
        ax.plot(cons.x, cons.y, "g*", ms=12)
        ax.plot(absolute.x, absolute.y, "r*", ms=8)
        ax.set_title(" -> ".join(str(int(v)) for v in (p.covered.iloc[0], *cons.covered, *absolute.covered)),
                     fontsize=8)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    fig.subplots_adjust(hspace=0.55, wspace=0.4, bottom=0.16)
    fig.colorbar(cs, ax=list(np.atleast_1d(axes)), shrink=0.6, label="patches reached (absolute score)")
    variant = paths["variant"].iloc[0] if "variant" in paths else "gradient descent"
    fig.suptitle(f"{b.name}, alpha = {math.degrees(a):.0f} deg: {variant} paths; panel titles = patches at "
                 "seed -> conservative end -> absolute end")
    star = dict(marker="*", ls="", mec="k", mew=0.3)
    fig.legend(handles=[Line2D([], [], color="k", ms=10, label="seed (random start)", **star),
                        Line2D([], [], color="g", ms=12, label="end of the conservative round (Type I score)", **star),
                        Line2D([], [], color="r", ms=8, label="end of the absolute round (Type II)", **star),
                        Line2D([], [], color="w", lw=1, path_effects=outline, label="descent path")],
               loc="lower center", ncol=4, frameon=False, fontsize=8)
    return fig


def plot_fig9(df: pd.DataFrame):
    """Kabir Fig. 9: N_repeat vs q (top) and probability vs N_repeat (bottom) per m."""
    ms = sorted(df.m.unique())
    fig, axes = new_figure(ncols=len(ms), nrows=2, size=(3.5, 3.0))
    axes = np.asarray(axes).reshape(2, len(ms))
    for i, m in enumerate(ms):
        top = df[(df.m == m) & (df.panel == "n_repeat_vs_q")]
        axes[0, i].semilogy(top.q, top.n_repeat, "o-", ms=3)
        axes[0, i].set_title(f"m = {m}")
        axes[0, i].set_xlabel("q")
        axes[0, i].set_ylabel("N_repeat for p >= 0.9")
        bot = df[(df.m == m) & (df.panel == "probability_vs_n_repeat")]
        for q, g in bot.groupby("q"):
            axes[1, i].semilogx(g.n_repeat, g.probability, lw=1, label=f"q = {q}")
        axes[1, i].set_xlabel("N_repeat")
        axes[1, i].set_ylabel("probability")
        axes[1, i].legend(fontsize=6, ncol=2, title="q = minimum cover size\n(q and m - q coincide)", title_fontsize=6, loc="lower right")
    fig.tight_layout()
    return fig
