"""Studies built on runs: limit cycles, continuation, compliant-to-rigid convergence, the drop test,
validation against published and analytic numbers, and comparisons with measured step periods."""
