"""Deprecated path: use :mod:`mavac.scrubbing.lissajous`."""

from mavac._deprecated import alias

alias(__name__, "mavac.scrubbing.lissajous")
