"""Set-cover compression: patches grouped by the setups that reach them, ``np.unique`` against
the lexsort of :func:`mavac.planning.dominance.row_groups`.

The DFBnB search (:func:`mavac.planning.setcover.dfbnb_setup_cover`) first merges the patches
that the same setups reach; notebook 12 runs it 16,640 times, and ``np.unique(axis=0)`` on the
boolean patch columns was a quarter of that notebook. On each committed Table II instance
(``data/instances/kabir_table2_<object>.npz``: non-dominated setups x stain patches), both
groupings are timed side by side and must give the same groups. The last line is

    RATIO compress_groups <x>

with x = the ``np.unique`` CPU seconds / the ``row_groups`` CPU seconds, over all instances.

Run: ``.venv/bin/python benchmarks/bench_compress.py [--repeat 20]``.
"""

from __future__ import annotations

import argparse
import resource

import numpy as np

from mavac.config import DATA_DIR
from mavac.planning.dominance import row_groups


def cpu_seconds() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def patch_columns(path) -> np.ndarray:
    """(coverable patches, setups) bool: each coverable patch's column of the instance's cover."""
    with np.load(path) as data:
        n = int(data["n_patches"])
        cover = np.unpackbits(data["cover_bits"], axis=1, count=n, bitorder="little").astype(bool)
    return cover[:, cover.any(axis=0)].T


def groups_by_unique(cols: np.ndarray) -> np.ndarray:
    """The grouping the compression used before: np.unique over the rows, ranked by first row."""
    _, first, inverse = np.unique(cols, axis=0, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return rank[inverse.ravel()]


def timed(fn, cols, repeat: int) -> tuple[float, np.ndarray]:
    start = cpu_seconds()
    for _ in range(repeat):
        out = fn(cols)
    return cpu_seconds() - start, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20, help="calls per instance and method")
    args = parser.parse_args()
    total_unique = total_lexsort = 0.0
    for path in sorted((DATA_DIR / "instances").glob("kabir_table2_*.npz")):
        cols = patch_columns(path)
        t_unique, reference = timed(groups_by_unique, cols, args.repeat)
        t_lexsort, ours = timed(lambda c: row_groups(np.packbits(c, axis=1)), cols, args.repeat)
        if not np.array_equal(reference, ours):
            raise SystemExit(f"{path.name}: the two groupings differ")
        print(f"{path.stem}: {cols.shape[0]} patches x {cols.shape[1]} setups, {reference.max() + 1} groups; "
              f"np.unique {1e3 * t_unique / args.repeat:.2f} ms, row_groups {1e3 * t_lexsort / args.repeat:.2f} ms")
        total_unique += t_unique
        total_lexsort += t_lexsort
    print(f"RATIO compress_groups {total_unique / total_lexsort:.1f}")


if __name__ == "__main__":
    main()
