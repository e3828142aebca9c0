"""Deprecated path: use :mod:`mavac.planning.setcover`."""

from mavac._deprecated import alias

alias(__name__, "mavac.planning.setcover")
