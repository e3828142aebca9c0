"""Kabir et al. execution, the twin of :mod:`mavac.cleaning`: what happens after the setup planner.

* ``toolpath`` -- plane-slicing multi-pass tool paths; ``lissajous`` -- the Lissajous force
  oscillation; ``gpr`` -- GPR operating-parameter learning (Sec. VI-VIII);
* ``wear`` -- the SIMULATED Preston-law stain removal (our model, not the paper's physics);
* ``execution`` -- tool paths of a plan, one scrubbing pass seen by the camera, the GPR black box;
* the two-arm cell of Sec. IX-C: ``cell`` (kinematics: placement, grasp, holding-arm IK),
  ``holding`` (setups the holding arm can present, the cell's setup plan), ``scene`` (the cell
  in pybullet: hold, move the part), ``scrub`` (one setup scrubbed under force control),
  ``residue`` (the camera's look after a pass: C_p, residue), ``coupon`` (the GPR learner's
  test coupon) and ``run`` (plan -> hold -> scrub -> look -> re-plan, :func:`run.run_part`).
"""
