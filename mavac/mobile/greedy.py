"""Deprecated path: use :mod:`mavac.planning.greedy`."""

from mavac._deprecated import alias

alias(__name__, "mavac.planning.greedy")
