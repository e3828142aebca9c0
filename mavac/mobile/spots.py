"""Deprecated path: use :mod:`mavac.inspection.spots`."""

from mavac._deprecated import alias

alias(__name__, "mavac.inspection.spots")
