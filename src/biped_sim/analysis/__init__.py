"""Analysis: gait metrics, energy audit, drop test, limit cycles, validation."""
