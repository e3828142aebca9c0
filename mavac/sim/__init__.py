"""Simulation shared by both papers: pybullet worlds, controllers, and the simulated dust and
wear models (``wear``: Preston-law stain removal). Everything here is simulated, not the papers'
physics."""
