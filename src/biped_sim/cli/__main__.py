"""``python -m biped_sim.cli``: the same as the ``biped-sim`` console script."""

from biped_sim.cli import main

main()
