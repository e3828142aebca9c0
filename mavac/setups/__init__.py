"""Kabir et al. (T-ASE 2017): setup planning, tool paths, Lissajous scrubbing, GPR parameter learning."""
