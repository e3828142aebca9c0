"""Deprecated path: use :mod:`mavac.inspection.reachability`."""

from mavac._deprecated import alias

alias(__name__, "mavac.inspection.reachability")
