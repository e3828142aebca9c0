"""Simulation shared by both papers.

* :mod:`mavac.sim.world` -- ``SimWorld``: a pybullet ``DIRECT`` world with an explicit client
  (a context manager that always disconnects), static concave machine meshes, carried parts,
  visual-only markers (dust heaps), robots (``SimRobot``), contact forces.
* :mod:`mavac.sim.urdf` -- a URDF pybullet loads, written from a pinocchio robot model.
* :mod:`mavac.sim.control` -- torque control with pinocchio dynamics: gravity compensation,
  joint PD, computed torque, Cartesian impedance, joint-trajectory tracking.
* :mod:`mavac.sim.camera` -- RGB-D + segmentation images with the TinyRenderer, metric depth,
  intrinsics from the field of view.
* :mod:`mavac.sim.wear` -- the SIMULATED Preston-law stain removal that stands in for Kabir et
  al.'s physical scrubbing (our model, not the papers' physics); :mod:`mavac.sim.scrub`.

pybullet is imported inside the functions that need it: ``import mavac.sim`` stays light.
"""
