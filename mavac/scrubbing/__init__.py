"""Kabir et al. execution: plane-slicing multi-pass tool paths (``toolpath``), the Lissajous
force oscillation (``lissajous``), GPR operating-parameter learning (``gpr``) and the execution
pipeline that ties them to the setup plan, the simulated wear and stain perception
(``execution``)."""
