"""Geometry: machine meshes (MAVAC), stained parts (Kabir), mesh loading, surface sampling and
rigid transforms.

Import from the submodules (``mavac.geometry.machines``, ``.parts``, ``.mesh``, ``.surface``,
``.transforms``); this package file imports nothing so ``import mavac.geometry`` stays cheap.
"""
