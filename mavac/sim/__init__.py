"""Simulation shared by both papers. Today: ``wear``, the SIMULATED Preston-law stain removal
that stands in for Kabir et al.'s physical scrubbing (it is our model, not the papers' physics).
The pybullet worlds and controllers of the online stages are to come here."""
