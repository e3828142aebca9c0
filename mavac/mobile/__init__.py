"""MAVAC offline planning: reachability map, spots, guards, coverage/overlap, non-observed
surfaces, and :func:`mavac.mobile.plan.plan_inspection` (one call from a machine mesh to an
ordered inspection pose set). Submodules import their heavy dependencies lazily."""
