"""Old module paths from before the layout of version 0.2, kept importable for one release.

Each old module is a two-line file that calls :func:`alias`; the import then returns the new
module itself (not a copy), so ``isinstance`` checks and monkeypatching keep working.
"""

from __future__ import annotations

import importlib
import sys
import warnings


def alias(old: str, new: str) -> None:
    """Make ``import old`` return module ``new``, with a ``DeprecationWarning``."""
    warnings.warn(f"{old} moved to {new}; the old path will be removed in mavac 0.3",
                  DeprecationWarning, stacklevel=3)
    sys.modules[old] = importlib.import_module(new)
