"""mavac: reproduction of two robotic-cleaning papers.

* MAVAC (Dupoirion, Michaud, Roberge 2026): offline inspection planning for a mobile
  manipulator (spots, guards, non-observed surfaces) in :mod:`mavac.inspection`; the online
  adaptive dust cleaning (Algorithm 1) in :mod:`mavac.cleaning`.
* Kabir, Kaipa, Marvel, Gupta (T-ASE 2017): multi-setup, multi-pass robotic cleaning: setup
  planning by depth-first branch and bound in :mod:`mavac.setups` and :mod:`mavac.planning`;
  tool paths, Lissajous scrubbing, stain perception, GPR parameter learning and the
  simulated two-arm cell's plan -> hold -> scrub -> look -> re-plan loop in :mod:`mavac.scrubbing`.

Both sit on shared layers: :mod:`mavac.geometry`, :mod:`mavac.robots`, :mod:`mavac.vision`,
:mod:`mavac.planning` and :mod:`mavac.sim` (the pybullet world, control, camera, URDF).

Importing ``mavac`` is cheap: heavy dependencies (open3d, pybullet, ompl, meshcat) are
imported inside the functions that need them.
"""

__version__ = "0.1.0"
