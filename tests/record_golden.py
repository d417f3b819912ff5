"""Re-record tests/data/golden_summaries.json: ``python -m tests.record_golden [CASE ...]`` (``make golden``).

Each case (a bundled config and ``--set`` overrides) is simulated again and its summary.json stored, less what
changes from run to run or commit to commit (``UNRECORDED``). The cases, their overrides and their
``arithmetic`` (what their numbers pass through, which sets how tests/test_golden.py compares them) are kept;
the file's ``classes`` say what each arithmetic allows. Give case names to re-record only those. Re-record
after a change that moves numbers on purpose (or after merging one), and say in the commit which and why;
the recorded numbers of every class but ``compiled`` depend a little on the CPU (``recorded_on``).

Re-recordings (why the numbers moved):

* ``kneed_walker_compliant`` (issue 31, the bundled compass built by the described walkers' builder): the
  body that rolls on the stance foot starts with its centre of mass's velocity taken about the contact point,
  omega x (com - contact), as the compass builder had it, instead of the hip's velocity plus omega x (com - hip);
  the kneed walker's start moved by one ulp (1.4e-17 m/s in the stance shank's vertical velocity), its adaptive
  steps with it: step periods by 1.5e-9 relative, lengths 2.6e-9, speed 7.9e-10, the dissipated energies 1e-8,
  the slip per step 1.3e-6 (a difference of nearly equal positions); every compass case is unchanged, bit for bit.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim import load_config, simulate

ROOT = Path(__file__).resolve().parents[1]
GOLDEN_PATH = ROOT / "tests" / "data" / "golden_summaries.json"
UNRECORDED = ("version", "config_hash", "wall_time_s")


def read_golden(path: Path = GOLDEN_PATH) -> dict[str, Any]:
    """The golden file: ``about``, ``classes`` (tolerances per arithmetic), ``recorded_on`` and ``cases``."""
    return json.loads(path.read_text())


def simulated_summary(case: dict[str, Any]) -> dict[str, Any]:
    """The summary of one case as summary.json holds it (JSON round trip), less ``UNRECORDED``."""
    result = simulate(load_config(ROOT / case["config"], case["overrides"]))
    summary: dict[str, Any] = json.loads(json.dumps(result.summary))
    return {key: value for key, value in summary.items() if key not in UNRECORDED}


def arithmetic_here() -> dict[str, Any]:
    """What the non-compiled numbers depend on here: numpy's version and SIMD dispatch (what
    NPY_DISABLE_CPU_FEATURES limits), and OpenBLAS's kernels if forced (OPENBLAS_CORETYPE)."""
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__  # as numpy.show_runtime

    return {
        "numpy": np.__version__,
        "simd": [name for name in __cpu_dispatch__ if __cpu_features__[name]],
        "openblas_coretype": os.environ.get("OPENBLAS_CORETYPE"),
    }


def record(names: list[str], path: Path = GOLDEN_PATH) -> dict[str, list[str]]:
    """Re-simulate ``names`` (all cases when empty) and write the file; returns, per case re-recorded, the recorded
    keys whose values changed (bit for bit) and, as ``+key``, the keys the summary has gained."""
    golden = read_golden(path)
    unknown = sorted(set(names) - set(golden["cases"]))
    if unknown:
        raise SystemExit(f"unknown golden case(s): {', '.join(unknown)}; known: {', '.join(golden['cases'])}")
    changes = {}
    for name in names or list(golden["cases"]):
        case = golden["cases"][name]
        summary = simulated_summary(case)
        moved = [key for key, value in case["summary"].items() if summary.get(key) != value]
        changes[name] = moved + [f"+{key}" for key in summary if key not in case["summary"]]
        case["summary"] = summary
    golden["recorded_on"] = arithmetic_here()
    path.write_text(json.dumps(golden, indent=1) + "\n")
    return changes


def main(argv: list[str]) -> None:
    for name, changed in record(argv).items():
        print(f"{name}: {', '.join(changed) if changed else 'nothing moved'}")
    print(f"written: {GOLDEN_PATH}")


if __name__ == "__main__":
    main(sys.argv[1:])
