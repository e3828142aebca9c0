"""Planning algorithms shared by both papers: RRT-Connect through OMPL (``rrt``), the
three-step greedy selection of spots and guards (``greedy``), and weighted set cover by
depth-first branch and bound with an integer-programming certificate (``setcover``, ``iess``),
and a short open tour through points (``tour``).
OMPL is imported inside the function that needs it."""
