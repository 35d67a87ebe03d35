"""Pure functions from simulation results to figures."""
