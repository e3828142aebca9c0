"""Simulation shared by both papers.

* :mod:`mavac.sim.world` -- ``SimWorld``: a pybullet ``DIRECT`` world with an explicit client
  (a context manager that always disconnects), static concave machine meshes, carried parts,
  visual-only markers (dust heaps), robots (``SimRobot``), contact forces.
* :mod:`mavac.sim.urdf` -- a URDF pybullet loads, written from a pinocchio robot model.
* :mod:`mavac.sim.control` -- torque control with pinocchio dynamics: gravity compensation,
  joint PD, computed torque, Cartesian impedance, joint-trajectory tracking.
* :mod:`mavac.sim.camera` -- RGB-D + segmentation images with the TinyRenderer, metric depth,
  intrinsics from the field of view.
* :mod:`mavac.sim.cell` -- kinematics of Kabir et al.'s two-arm iiwa cell: placement, fixed
  grasp, the holding arm's IK for a part pose, room for the part between the arms.
* :mod:`mavac.sim.bimanual` -- that cell in pybullet: the held part, collision-free setup
  motions, scrubbing under force control with the Lissajous overlay, Preston wear from the
  measured contact (SIMULATED), stain overlays and camera snapshots.
* :mod:`mavac.sim.wear` -- the SIMULATED Preston-law stain removal that stands in for Kabir et
  al.'s physical scrubbing (our model, not the papers' physics); :mod:`mavac.sim.scrub`.

pybullet is imported inside the functions that need it: ``import mavac.sim`` stays light.
"""
