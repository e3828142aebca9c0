"""Interrupt-safe file output: write to a temporary file, then rename it onto the target.

Temporaries live in a dedicated folder beside the target, :data:`TEMP_DIR` (same file system,
so the rename is atomic), named after the writing process. A writer killed outright (SIGKILL,
or SIGTERM with no handler) cannot delete its temporary; the next write into that folder
deletes every temporary whose process is gone, and the folder itself once it is empty.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from .validate import ParameterTypeError, check_path

#: folder, beside each target, that holds the temporaries of writes in progress
TEMP_DIR = ".mavac_tmp"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _process_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process
        return True
    return True


def clean_stale_temporaries(folder) -> list[Path]:
    """Delete the temporaries in ``folder`` / :data:`TEMP_DIR` whose writing process has
    ended (killed mid-write); returns the deleted paths. Live writers' files are kept."""
    tmp_dir = Path(folder) / TEMP_DIR
    removed = []
    for f in tmp_dir.glob("*") if tmp_dir.is_dir() else ():
        pid = f.name.split(".", 1)[0]
        if pid.isdigit() and int(pid) != os.getpid() and not _process_alive(int(pid)):
            with contextlib.suppress(FileNotFoundError):
                f.unlink()
                removed.append(f)
    return removed


def _temporary(path: Path) -> Path:
    """A new empty file in ``path.parent / TEMP_DIR`` named ``<pid>.<random>.<path.name>``
    (ending like the target, so writers that read the suffix keep working)."""
    tmp_dir = path.parent / TEMP_DIR
    for _ in range(10):  # another writer may remove the empty folder between the two calls
        tmp_dir.mkdir(parents=True, exist_ok=True)
        try:
            fd, tmp = tempfile.mkstemp(dir=tmp_dir, prefix=f"{os.getpid()}.", suffix=f".{path.name}")
        except FileNotFoundError:
            continue
        os.close(fd)
        return Path(tmp)
    raise OSError(f"could not create a temporary file in {tmp_dir}")


def _remove_if_empty(folder: Path) -> None:
    with contextlib.suppress(OSError):  # not empty (another write in progress) or gone
        folder.rmdir()


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path; on success rename it onto ``path``, on error delete it.

    An interrupted run (KeyboardInterrupt included) never leaves a half-written ``path``; a
    killed one leaves its temporary in :data:`TEMP_DIR`, deleted by the next write there.
    """
    path = check_path("path", path)
    path.parent.mkdir(parents=True, exist_ok=True)
    clean_stale_temporaries(path.parent)
    tmp = _temporary(path)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; give the file normal permissions
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    finally:
        _remove_if_empty(tmp.parent)


@contextlib.contextmanager
def atomic_paths(*paths):
    """:func:`atomic_path` for several files written together: yield their temporaries and rename
    them all at the end, so an interrupt never leaves a new file beside an old one."""
    with contextlib.ExitStack() as stack:
        yield [stack.enter_context(atomic_path(p)) for p in paths]


def write_csv(df, path, **kwargs) -> Path:
    """Write a pandas DataFrame to CSV atomically (no index, fixed float format)."""
    if not callable(getattr(df, "to_csv", None)):
        raise ParameterTypeError(f"df must be a pandas DataFrame, got {type(df).__name__}")
    kwargs.setdefault("index", False)
    kwargs.setdefault("float_format", "%.6g")
    with atomic_path(path) as tmp:
        df.to_csv(tmp, **kwargs)
    return Path(path)


def write_text(text: str, path) -> Path:
    """Write text atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def json_safe(value):
    """``value`` (dicts, lists, tuples, numbers, arrays) with NaN and infinite floats as None and
    numpy scalars and arrays as Python numbers and lists (JSON holds neither)."""
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [json_safe(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if np.isfinite(value) else None
    if isinstance(value, (np.integer, np.bool_)):
        return value.item()
    return value


def write_json(obj, path) -> Path:
    """Write JSON atomically (sorted keys, so the same data gives the same bytes); ValueError
    for an infinite or NaN number, which JSON cannot hold (write None and say why instead)."""
    return write_text(json.dumps(obj, indent=2, sort_keys=True, allow_nan=False), path)


def savefig(fig, path, dpi: int = 120) -> Path:
    """Save a matplotlib figure atomically."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format=Path(path).suffix.lstrip(".") or "png")
    return Path(path)
