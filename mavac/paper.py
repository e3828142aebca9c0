"""The papers' own numbers, read from ``data/paper_values.csv``, and paper-vs-ours tables.

Every value there is quoted from one of the two papers with the table or figure it comes
from (``ref``). ``condition`` holds ``key=value`` pairs separated by ``;`` (for example
``object=sine;variant=CA_XY``); variant names spell alpha as ``a`` (``CA_XY_a``), and
``none`` stands for "without gradient descent". Percentages are stored as printed
(unit ``%``) and converted to fractions by :func:`paper_table` and :func:`paper_scalar`.
Rows with an empty condition are single values (:func:`paper_scalar`).
"""

from __future__ import annotations

import functools

import pandas as pd

from .config import DATA_DIR

PAPER_VALUES_CSV = DATA_DIR / "paper_values.csv"


@functools.lru_cache(maxsize=1)
def _load():
    if not PAPER_VALUES_CSV.is_file():
        raise ValueError(f"{PAPER_VALUES_CSV} not found: the papers' values ship with the source "
                         "checkout; install from a clone with `pip install -e .` to use mavac.paper")
    return pd.read_csv(PAPER_VALUES_CSV, keep_default_na=False, dtype={"condition": str})


def paper_values(paper: str | None = None, ref: str | None = None, quantity: str | None = None):
    """Rows of ``data/paper_values.csv`` filtered by paper (``"mavac"``/``"kabir"``), ref and quantity."""
    df = _load()
    for col, val in (("paper", paper), ("ref", ref), ("quantity", quantity)):
        if val is not None:
            if val not in set(df[col]):
                raise ValueError(f"{col}={val!r} not in data/paper_values.csv; known: {sorted(set(df[col]))}")
            df = df[df[col] == val]
    return df.reset_index(drop=True)


def _parse(value: str):
    for cast in (int, float):
        try:
            return cast(value)
        except ValueError:
            pass
    return {"True": True, "False": False}.get(value, value)


def paper_table(paper: str, ref: str, fractions: bool = True):
    """One paper table as a wide DataFrame: condition keys and quantities become columns.

    Parameters
    ----------
    paper, ref : str
        For example ``("mavac", "Table 1")``.
    fractions : bool
        Convert values with unit ``%`` to fractions (C and O are fractions of |S| in mavac).
    """
    df = paper_values(paper=paper, ref=ref)
    df = df[df["condition"].str.contains("=")].copy()
    if df.empty:
        raise ValueError(f"{paper} {ref} has no per-condition rows; use paper_scalar() for single values")
    if fractions:
        pct = df["unit"] == "%"
        df.loc[pct, "value"] = df.loc[pct, "value"].astype(float) / 100.0
    records = {}
    for row in df.itertuples():
        key = row.condition
        rec = records.setdefault(key, {})
        for part in filter(None, key.split(";")):
            k, _, v = part.partition("=")
            rec[k] = _parse(v)
        rec[row.quantity] = row.value
    return pd.DataFrame(list(records.values()))


def paper_scalar(paper: str, ref: str, quantity: str, condition: str = "", fraction: bool = True) -> float:
    """One value, e.g. ``paper_scalar("mavac", "Fig. 6", "C_per_guard")`` (``%`` -> fraction)."""
    df = paper_values(paper=paper, ref=ref, quantity=quantity)
    df = df[df["condition"] == condition]
    if len(df) != 1:
        raise ValueError(f"no single value for {paper} {ref} {quantity} condition={condition!r}; "
                         f"conditions available: {sorted(set(paper_values(paper, ref, quantity)['condition']))}")
    value = float(df["value"].iloc[0])
    return value / 100.0 if fraction and df["unit"].iloc[0] == "%" else value


def compare(ours, paper, on, quantities):
    """Side-by-side table: ``on`` columns, then ``<q>_paper`` and ``<q>_ours`` for each quantity.

    Rows of ``ours`` with no paper counterpart are kept (paper columns empty) and vice versa.
    """
    left = paper[list(on) + [q for q in quantities if q in paper]].rename(
        columns={q: f"{q}_paper" for q in quantities})
    right = ours[list(on) + [q for q in quantities if q in ours]].rename(
        columns={q: f"{q}_ours" for q in quantities})
    out = left.merge(right, on=list(on), how="outer")
    cols = list(on) + [c for q in quantities for c in (f"{q}_paper", f"{q}_ours") if c in out]
    return out[cols]
