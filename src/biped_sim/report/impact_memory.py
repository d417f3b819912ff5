"""The figure of the impact-memory scan (:mod:`biped_sim.studies.impact_memory`), and the script that makes it.

    python -m biped_sim.report.impact_memory [OUT_DIR]     # default docs/figures

scans the default walker's restitution from 0.2 to 0.6 (leg inertia 0.0049 kg m^2, as in issue 20's
reproduction; minimal coordinates, which give the same periods to 1e-7 s) under both memories and writes
``impact_memory_scan.png/.svg``: each step period minus its value at the first restitution, one line per
step, the rebound count below.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from biped_sim.config import derive, load_config
from biped_sim.plots import COLUMN_WIDTH_IN, save_figure, styled
from biped_sim.studies.impact_memory import MEMORIES, MemoryScan, memory_scan
from biped_sim.sweep import study_executor

DOC_VALUES = np.round(np.arange(0.2, 0.6 + 1e-9, 0.0025), 4)
DOC_OVERRIDES = {"walker.leg_inertia": 0.0049, "formulation.kind": "minimal", "simulation.t_end": 4.0}


@styled
def memory_scan_figure(scan: MemoryScan) -> Figure:
    """Per memory: each step period against the key (relative to its first value, ms); rebounds below."""
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 4.2), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True, height_ratios=[2, 2, 1])
    for ax, memory in zip(axes[:2], MEMORIES, strict=True):
        periods = scan.periods[memory]
        for step in range(1, scan.steps):  # step 1 (from the release) hardly depends on the contact
            ax.plot(scan.values, 1e3 * (periods[:, step] - periods[0, step]), label=f"step {step + 1}")
        ax.set_ylabel("T - T(first) [ms]")
        ax.set_title(f"impact_memory: {memory}; largest change {1e3 * scan.largest_jump(memory):.2f} ms")
    axes[0].legend(ncol=3, loc="best")
    for i, memory in enumerate(MEMORIES):
        axes[2].step(scan.values, scan.rebounds[memory], where="mid", label=memory, linestyle=("-", "--")[i])
    axes[2].set_ylabel("rebounds")
    axes[2].set_xlabel(scan.key)
    axes[2].legend(loc="best")
    return fig


def main(argv: list[str] | None = None) -> None:
    """Run the documented scan and write its figure (2 local workers)."""
    argv = sys.argv[1:] if argv is None else argv
    out_dir = Path(argv[0] if argv else "docs/figures")
    config = derive(load_config("configs/round_foot_walker.yaml"), DOC_OVERRIDES)
    with study_executor("local", 2) as executor:
        scan = memory_scan(config, DOC_VALUES, executor=executor)
    for memory in MEMORIES:
        jump, rebounds = 1e3 * scan.largest_jump(memory), scan.rebounds[memory].max()
        print(f"{memory}: largest change {jump:.3f} ms, at most {rebounds} rebounds")
    print("\n".join(str(p) for p in save_figure(memory_scan_figure(scan), out_dir, "impact_memory_scan")))


if __name__ == "__main__":
    main()
