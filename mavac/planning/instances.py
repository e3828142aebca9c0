"""Set-cover instance files: Beasley's OR-Library ``scp`` files and our compressed setup instances.

OR-Library format ("scp" files): ``rows cols``; the cost of every column; then, for each row,
the number of columns covering it followed by their 1-based indices. In the setup-planning
reading a column is a candidate setup and a row a patch, so :func:`read_scp` returns the
transpose: ``cover[j, i]`` is True when set j covers element i.

Our format (:func:`write_instance`, :func:`read_instance`): a zip of ``.npy`` arrays, the cover
bit-packed, with fixed zip timestamps so that the same instance gives the same bytes.
"""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np

from ..io import atomic_path

# Zip member timestamp of instance files (the earliest a zip can hold): same arrays, same bytes.
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)


def read_scp(path) -> tuple[np.ndarray, np.ndarray]:
    """Read an OR-Library ``scp`` file.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    cover : (m, n) bool
        ``m`` sets (the file's columns) by ``n`` elements (its rows).
    costs : (m,) float
    """
    tokens = Path(path).read_text().split()
    try:
        values = np.array(tokens, dtype=np.int64)
    except ValueError as exc:
        raise ValueError(f"path {str(path)!r} is not an OR-Library scp file (non-integer token)") from exc
    if len(values) < 2:
        raise ValueError(f"path {str(path)!r} is not an OR-Library scp file (no 'rows cols' header)")
    n, m = int(values[0]), int(values[1])
    costs = values[2:2 + m].astype(float)
    cover = np.zeros((m, n), dtype=bool)
    pos = 2 + m
    for i in range(n):
        if pos >= len(values):
            raise ValueError(f"path {str(path)!r} ends before row {i + 1} of {n}")
        k = int(values[pos])
        cols = values[pos + 1:pos + 1 + k] - 1
        if len(cols) != k or np.any(cols < 0) or np.any(cols >= m):
            raise ValueError(f"path {str(path)!r}: row {i + 1} lists columns outside 1..{m}")
        cover[cols, i] = True
        pos += 1 + k
    if len(costs) != m:
        raise ValueError(f"path {str(path)!r} gives {len(costs)} costs for {m} columns")
    return cover, costs


def write_instance(path, cover: np.ndarray, costs: np.ndarray, **arrays) -> Path:
    """Write a set-cover instance, atomically and byte-reproducibly.

    Parameters
    ----------
    path : str or Path
        Destination (``.npz``).
    cover : (m, n) bool
    costs : (m,) float, s
    **arrays : array_like
        Anything else to keep beside them (setups, patch areas, names).

    Returns
    -------
    Path
    """
    cover = np.asarray(cover, dtype=bool)
    members = dict(cover_bits=np.packbits(cover, axis=1, bitorder="little"), n_patches=np.int64(cover.shape[1]),
                   costs=np.asarray(costs, dtype=float), **{k: np.asarray(v) for k, v in arrays.items()})
    with atomic_path(path) as tmp:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            for name in sorted(members):
                buf = io.BytesIO()
                np.lib.format.write_array(buf, members[name], allow_pickle=False)
                info = zipfile.ZipInfo(f"{name}.npy", date_time=_ZIP_DATE)
                info.compress_type = zipfile.ZIP_DEFLATED
                zf.writestr(info, buf.getvalue())
    return Path(path)


def read_instance(path) -> dict:
    """Read a file of :func:`write_instance`.

    Returns
    -------
    dict
        ``cover (m, n) bool``, ``costs (m,) float`` and the other arrays stored with them.
    """
    try:
        with np.load(path, allow_pickle=False) as data:
            out = {k: data[k] for k in data.files}
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise ValueError(f"path {str(path)!r} is not a set-cover instance file: {exc}") from exc
    if "cover_bits" not in out or "costs" not in out:
        raise ValueError(f"path {str(path)!r} is not a set-cover instance file (no cover_bits / costs)")
    n = int(out.pop("n_patches"))
    out["cover"] = np.unpackbits(out.pop("cover_bits"), axis=1, count=n, bitorder="little").astype(bool)
    return out
