"""Deprecated path: use :mod:`mavac.scrubbing.gpr`."""

from mavac._deprecated import alias

alias(__name__, "mavac.scrubbing.gpr")
