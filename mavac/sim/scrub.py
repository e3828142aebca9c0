"""Deprecated path: use :mod:`mavac.sim.wear`."""

from mavac._deprecated import alias

alias(__name__, "mavac.sim.wear")
