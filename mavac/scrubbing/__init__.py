"""Kabir et al. execution: plane-slicing multi-pass tool paths (``toolpath``), the Lissajous
force oscillation (``lissajous``) and GPR operating-parameter learning (``gpr``)."""
