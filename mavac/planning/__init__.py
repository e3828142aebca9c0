"""Motion planning: RRT-Connect (OMPL) in a box of joint space with a Python validity checker
(:func:`mavac.planning.rrt.plan_rrt_connect`). OMPL is imported inside the function."""
