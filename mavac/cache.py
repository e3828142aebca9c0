"""On-disk cache for expensive stages (reachability maps, reach sweeps), verified on load.

Callers wrap their function with :func:`verified_cache` (``verified_cache(fn, ignore=[...])``),
leaving out of the key what does not change the result (worker counts) or hashes slowly (robot
objects, which they replace by a kinematic fingerprint). The key is the function's code and
its hashed arguments (joblib ``Memory``), so a change of input or parameter recomputes.

joblib only notices a cache entry it cannot unpickle; bytes flipped inside an array load as a
different array. So every entry also stores the SHA-256 of its output file, written when the
output is computed and compared before every load: an entry whose bytes differ (or that has
no checksum, e.g. written before checksums existed) is recomputed, with a warning, and
stored again.
"""

from __future__ import annotations

import functools
import hashlib
import warnings
from pathlib import Path

from joblib import Memory

from .config import cache_dir

#: name of the checksum file beside joblib's ``output.pkl`` in a cache entry's folder
CHECKSUM_FILE = "output.sha256"


@functools.lru_cache(maxsize=1)
def memory():
    """The package's ``joblib.Memory`` under :func:`mavac.config.cache_dir`."""
    return Memory(cache_dir(), verbose=0)


def _sha256(path: Path) -> str:
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


class VerifiedFunc:
    """A joblib-memorized function whose cached outputs are checked against a checksum.

    Call it like the function. ``memorized`` is the joblib ``MemorizedFunc`` (its
    ``check_call_in_cache`` still answers whether a call is stored).
    """

    def __init__(self, memorized):
        self.memorized = memorized

    def _entry(self, reference) -> Path:
        return Path(reference.store_backend.location, reference.func_id, reference.args_id)

    def __call__(self, *args, **kwargs):
        stored = self.memorized.check_call_in_cache(*args, **kwargs)
        reference = self.memorized.call_and_shelve(*args, **kwargs)  # computes when missing
        entry = self._entry(reference)
        output, checksum = entry / "output.pkl", entry / CHECKSUM_FILE
        if not stored:  # computed just now: record its checksum
            checksum.write_text(_sha256(output))  # a torn write only costs a recomputation
            return reference.get()
        if checksum.is_file() and checksum.read_text().strip() == _sha256(output):
            return reference.get()
        why = "differs from its checksum" if checksum.is_file() else "has no checksum"
        warnings.warn(f"cache entry {entry} {why} (corrupted or written by an older version); "
                      "recomputing it", RuntimeWarning, stacklevel=2)
        value, _ = self.memorized.call(*args, **kwargs)
        checksum.write_text(_sha256(output))
        return value

    def check_call_in_cache(self, *args, **kwargs) -> bool:
        """Whether joblib holds an entry for this call (not whether it is intact)."""
        return self.memorized.check_call_in_cache(*args, **kwargs)


def verified_cache(fn, *, ignore=(), location: Memory | None = None) -> VerifiedFunc:
    """``fn`` cached on disk with a checksum per output (see the module docstring).

    Parameters
    ----------
    fn : callable
        A module-level function (joblib keys the cache on its code).
    ignore : sequence of str
        Arguments left out of the key.
    location : joblib.Memory, optional
        Default :func:`memory` (under :func:`mavac.config.cache_dir`).
    """
    mem = memory() if location is None else location
    return VerifiedFunc(mem.cache(fn, ignore=list(ignore)))
