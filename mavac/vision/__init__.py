"""Vision: the emulated camera of MAVAC and surface-point visibility.

* :mod:`mavac.vision.camera` -- FOV pyramid test (``fov_mask``, ``fov_masks``), guard camera
  poses (``camera_pose_looking_at``) and pyramid edges for plots (``fov_pyramid_lines``).
* :mod:`mavac.vision.visibility` -- hidden point removal (Open3D, Katz et al. 2007), exact
  visibility by ray casting (Open3D ``RaycastingScene``), their combination with the FOV
  (``visible_from``) and HPR's error rates against ray casting (``hpr_error_rates``).

Camera frame (MAVAC): optical axis = camera x, ``theta_a`` half-angle in the camera XY plane
(image width), ``theta_b`` in the XZ plane (image height), depth limit ``L_d`` along x.
Submodules import open3d lazily, inside the functions that need it.
"""
