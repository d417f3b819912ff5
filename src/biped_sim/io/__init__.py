"""Storage: atomic writes, HDF5 trajectories, run summaries and per-step tables, provenance."""
