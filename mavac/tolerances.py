"""Numerical tolerances of the package, in one place, each with the reason for its value.

These are not parameters of the papers' methods (those live in :mod:`mavac.params`): they
decide when two floating-point quantities count as equal, so that rounding never splits a
result that exact arithmetic would not split.
"""

from __future__ import annotations

#: Largest entry of ``|R^T R - I|`` (and of the last-row error) accepted in a rigid transform.
#: Poses composed in float64 are orthonormal to ~1e-15 and poses read back from our JSON
#: (rounded to 9 decimals) to ~1e-9; a scale or shear typed by mistake is off by far more.
RIGID_ATOL = 1e-6

#: Tolerance on the camera's far plane ``x_c <= L_d + FAR_PLANE_TOL``, metres. A guard sits
#: ``L_d`` from its target along the normal, so the target's face lies on that plane; but its
#: camera pose comes from the FK of an IK solution, which may miss the nominal pose by the IK
#: tolerances (IK_POSITION_TOL = 1e-5 m, plus IK_ROTATION_TOL = 1e-4 rad tilting the far
#: rectangle, half-diagonal < 0.5 m at L_d = 0.5 m: < 5e-5 m), so up to ~6e-5 m either way. A
#: relative 1e-9 (~5e-10 m) cut about a third of the guards' own target faces. 1 mm is 15x that
#: residual, and far below both the Azure Kinect's depth error (~1 cm) and the 5 cm spacing of S.
FAR_PLANE_TOL = 1e-3

#: A ray "reaches" a surface point when nothing is hit before ``|p - v| - eps``, with ``eps``
#: this fraction of the mesh's bounding-box diagonal: large against float32 ray precision
#: (~1e-7 relative), small against any wall thickness of a machine or part.
RAY_EPS_RELATIVE = 1e-4

#: Points and faces this close above the floor (m), facing down (normal z below
#: ``FLOOR_NORMAL_Z``), are the machine's base standing on the floor, not exposed surface.
#: Meshes are lowered onto z = 0 exactly, so only rounding separates them from it.
FLOOR_TOLERANCE = 1e-6
#: cos of the 8 degrees within which a face normal counts as pointing straight down.
FLOOR_NORMAL_Z = -0.99

#: A surface point is buried in another body of its mesh when it lies more than this (m) inside
#: that body. Points on the body's boundary (a coplanar face shared by two overlapping boxes,
#: which is outer surface) are then always kept: their depth is rounding (~1e-16 m relative) or
#: below trimesh's 1e-8 m band, where ``signed_distance`` returns an unsigned distance. 10 um is
#: far below the 5 cm spacing of S, so a buried point is kept only within 10 um of a crossing line.
BURIED_TOLERANCE = 1e-5

#: Setups closer than this (m or rad) are the same setup (n_rfc counts each once): far below
#: the finest sampling step (25 mm, 5 deg), far above the rounding of ``lo + k * step``.
SETUP_KEY_QUANTUM = 1e-7
#: Decimals at which (vertex, normal) pairs of the reach test are the same IK target: mesh
#: vertices shared by faces agree to ~1e-16, distinct ones differ by > 1e-4 m.
TARGET_DECIMALS = 9

#: Decimals (of a metre) kept of a user's machine mesh in its own frame, after the whole-metre
#: move of ``machine_from_mesh``: 1 nm. A file's coordinates far from its origin carry float64
#: noise of |x| * 1.1e-16 (2e-12 m at 10 km, 1e-10 m at 1000 km), which flips surface points
#: lying on a face that coincides with a grid boundary (e.g. a guard cluster's voxel) from one
#: cell to the next. Rounding to 1 nm, far above that noise and far below any feature a camera
#: sees, gives the same numbers as the file written at its origin; a coordinate with at most 9
#: decimals in metres is kept bit for bit.
MACHINE_FRAME_DECIMALS = 9

#: Relative slack when a score is compared with the greedy threshold (P x first maximum): a
#: candidate tying the threshold is kept whatever the last bit of the product.
GREEDY_TIE_RTOL = 1e-12

#: A 2-opt move must shorten a tour by more than this (m or rad), so moves that only trade
#: rounding errors are not taken and the improvement loop always ends.
TOUR_GAIN_TOL = 1e-12

#: Slack (in units of the quantity) when a count is taken from a ratio that should be an
#: integer, e.g. ``(hi - lo) / step`` of a sampling grid or ``length / spacing`` of a tool
#: path: 21 grid values over [0, 1 m] at 50 mm must not become 20 by rounding.
COUNT_SLACK = 1e-9

#: Two unit vectors are (anti)parallel when ``|a . b| > 1 - PARALLEL_TOL`` (about 4.5e-5 rad):
#: used to fall back to another reference axis before a cross product degenerates.
PARALLEL_TOL = 1e-9

#: Default convergence tolerances of the inverse kinematics: 10 um and 0.1 mrad, two orders
#: below what a tool or camera pose needs, reached in a few Newton steps from a nearby seed.
IK_POSITION_TOL = 1e-5
IK_ROTATION_TOL = 1e-4
