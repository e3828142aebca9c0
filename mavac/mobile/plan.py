"""Deprecated path: use :mod:`mavac.inspection.plan`."""

from mavac._deprecated import alias

alias(__name__, "mavac.inspection.plan")
