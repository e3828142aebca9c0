"""Deprecated path: use :mod:`mavac.scrubbing.toolpath`."""

from mavac._deprecated import alias

alias(__name__, "mavac.scrubbing.toolpath")
