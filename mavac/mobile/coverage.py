"""Deprecated path: use :mod:`mavac.inspection.coverage`."""

from mavac._deprecated import alias

alias(__name__, "mavac.inspection.coverage")
