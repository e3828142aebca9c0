"""Geometry: machine meshes (MAVAC), stained parts (Kabir), mesh loading and surface sampling.

Import from the submodules (``mavac.geometry.machines``, ``.parts``, ``.mesh``, ``.surface``);
this package file imports nothing so ``import mavac.geometry`` stays cheap.
"""
