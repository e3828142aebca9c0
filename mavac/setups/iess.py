"""Deprecated path: use :mod:`mavac.planning.iess`."""

from mavac._deprecated import alias

alias(__name__, "mavac.planning.iess")
