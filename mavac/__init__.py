"""mavac: reproduction of two robotic-cleaning papers.

* MAVAC (Dupoirion, Michaud, Roberge 2026): offline inspection planning for a mobile
  manipulator (spots, guards, non-observed surfaces) and online adaptive dust cleaning.
* Kabir, Kaipa, Marvel, Gupta (T-ASE 2017): multi-setup, multi-pass robotic cleaning
  (setup planning by depth-first branch and bound, tool paths, Lissajous scrubbing, GPR).

Importing ``mavac`` is cheap: heavy dependencies (open3d, pybullet, ompl, meshcat) are
imported inside the modules that need them.
"""

__version__ = "0.1.0"
