"""MAVAC offline (inspection planning): reachability map, spots, guards, coverage and overlap,
non-observed surfaces, and :func:`mavac.inspection.inspection_plan.plan_inspection`, one call from a
machine mesh to the ordered pose set T. Heavy dependencies are imported inside functions."""
