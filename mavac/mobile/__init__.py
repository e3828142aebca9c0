"""Deprecated package: MAVAC's offline planning moved to :mod:`mavac.inspection`."""
