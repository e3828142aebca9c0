"""Deprecated path: use :mod:`mavac.inspection.nos`."""

from mavac._deprecated import alias

alias(__name__, "mavac.inspection.nos")
