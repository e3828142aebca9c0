"""Robot models (pinocchio + coal), batched kinematics and collision checking.

Submodules: ``models`` (``ur10_mobile``, ``puma560``, ``load_robot``), ``kinematics`` (FK,
Jacobian, batched IK, closed-form Puma axis IK, maneuverability index), ``collision``
(``CollisionChecker``). They import pinocchio/coal, so import them explicitly.
"""
