"""Simulation shared by both papers.

* :mod:`mavac.sim.world` -- ``SimWorld``: a pybullet ``DIRECT`` world with an explicit client
  (a context manager that always disconnects), static concave machine meshes, carried and
  welded bodies, visual-only markers (dust heaps), robots (``SimRobot``: torques, brakes),
  contact properties and forces.
* :mod:`mavac.sim.urdf` -- a URDF pybullet loads, written from a pinocchio robot model.
* :mod:`mavac.sim.control` -- torque control with pinocchio dynamics: gravity compensation,
  joint PD, computed torque, Cartesian impedance, joint-trajectory tracking.
* :mod:`mavac.sim.render` -- RGB-D + segmentation images with the TinyRenderer, metric depth,
  intrinsics from the field of view.

The paper-specific scenes live with their loops: MAVAC's machine and dust heaps in
:mod:`mavac.cleaning.scene`, Kabir et al.'s two-arm cell in :mod:`mavac.scrubbing.scene`.
pybullet is imported inside the functions that need it: ``import mavac.sim`` stays light.
"""
