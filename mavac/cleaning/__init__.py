"""MAVAC online (Algorithm 1): dust detection from the guard poses, clustering into areas,
approaches with RRT-Connect and vacuuming under impedance control. Not built yet: this package
is where it will live (the offline plan it starts from is :mod:`mavac.inspection`)."""
