"""Deprecated path: use :mod:`mavac.inspection.guards`."""

from mavac._deprecated import alias

alias(__name__, "mavac.inspection.guards")
