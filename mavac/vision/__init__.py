"""Vision, shared perception of both papers.

* :mod:`mavac.vision.camera` -- MAVAC's emulated camera: FOV pyramid test (``fov_mask``,
  ``fov_masks``), guard camera poses (``camera_pose_looking_at``), pyramid edges for plots.
* :mod:`mavac.vision.visibility` -- hidden point removal (Open3D, Katz et al. 2007), exact
  visibility by ray casting (Open3D ``RaycastingScene``), the choice between them as one value
  (``Visibility``, defined in :mod:`mavac.params`: method and HPR radius, ``visible(...)``), its
  combination with the FOV (``visible_from``) and HPR's error rates against ray casting
  (``hpr_error_rates``).
* :mod:`mavac.vision.stain` -- stain images, K-means stain masks, C_p and the N_c-colour
  quantisation into passes (Kabir, Sec. VII).
* :mod:`mavac.vision.rgbd` -- back-projection of RGB-D pixels to 3-D points (pinhole, OpenCV frame).
* :mod:`mavac.vision.icp` -- registration of a part's CAD mesh to a point cloud (Kabir, Sec. VII).

Camera frame (MAVAC): optical axis = camera x, ``theta_a`` half-angle in the camera XY plane
(image width), ``theta_b`` in the XZ plane (image height), depth limit ``L_d`` along x.
Submodules import open3d lazily, inside the functions that need it.
"""
