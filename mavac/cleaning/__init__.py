"""MAVAC online (Algorithm 1) in simulation, on the offline plan of :mod:`mavac.inspection`.

One module per concept:

* :mod:`~mavac.cleaning.heaps` -- dust heaps of a trial and their pybullet bodies;
* :mod:`~mavac.cleaning.detection` -- HSV segmentation, blobs, back-projection to nodes D;
* :mod:`~mavac.cleaning.filters` -- the paper's filters (sensor depth range, reach; optional tip distance,
  duplicates);
* :mod:`~mavac.cleaning.clustering` -- DBSCAN areas in TSP (or short-path) order;
* :mod:`~mavac.cleaning.approach` -- eq. 5 approach points, IK, collision checks;
* :mod:`~mavac.cleaning.motion` -- RRT-Connect arm motions against the machine;
* :mod:`~mavac.cleaning.vacuum` -- linear moves (optional spiral) under Cartesian impedance, suction;
* :mod:`~mavac.cleaning.scene` -- the simulated cell;
* :mod:`~mavac.cleaning.timing` -- base travel and the simulated time per activity;
* :mod:`~mavac.cleaning.misses` -- why each uncleaned heap was missed;
* :mod:`~mavac.cleaning.readings` -- the paper's text and the authors' code as two readings;
* :mod:`~mavac.cleaning.trial` -- ``run_trial``: the whole loop, scored;
* :mod:`~mavac.cleaning.replay` -- the trial's motion on the simulated clock, and how far the arm moved;
* :mod:`~mavac.cleaning.systematic` -- ``run_systematic``: the systematic baseline, a raster over every
  surface dust can rest on, scored the same way.
"""
