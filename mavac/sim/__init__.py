"""Simulation: worlds, controllers and simulated cleaning models (dust, scrubbing)."""
