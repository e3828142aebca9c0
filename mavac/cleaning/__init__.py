"""MAVAC online (Algorithm 1): detect dust from the guard poses, cluster it into areas, plan
approaches with RRT-Connect and vacuum under impedance control, in the pybullet world of
:mod:`mavac.sim`."""
