"""A mapped basin's files: basin.h5 (grid, outcome, steps, gait, resolved config and provenance) and basin.csv."""

from __future__ import annotations

import json
from pathlib import Path

from biped_sim.io.atomic import write_text_atomic, write_with
from biped_sim.io.provenance import provenance
from biped_sim.studies.basin import OUTCOMES, Basin


def write_basin(basin: Basin, out_dir: Path) -> list[Path]:
    """basin.h5 (grid, outcome, steps, gait, resolved config and provenance) and basin.csv, atomically."""
    import h5py

    spec = basin.spec
    doc = basin.to_json()
    h5_path, csv_path = out_dir / "basin.h5", out_dir / "basin.csv"

    def write_h5(tmp: Path) -> None:
        with h5py.File(tmp, "w") as f:
            f.create_dataset("x", data=spec.x.values)
            f.create_dataset("y", data=spec.y.values)
            f.create_dataset("outcome", data=basin.outcome)
            f.create_dataset("steps", data=basin.steps)
            f["x"].attrs["key"] = spec.x.config_key
            f["y"].attrs["key"] = spec.y.config_key
            f["outcome"].attrs["codes"] = json.dumps(dict(enumerate(OUTCOMES)))
            for name, value in (doc["fixed_point"] or {}).items():
                f.attrs[f"fixed_point_{name}"] = value
            for name in ("n_cells", "fraction_walking", "fraction_converged", "converged_tolerance", "steps"):
                f.attrs[name] = doc[name]
            f.attrs["notes"] = json.dumps(basin.notes)
            f.attrs["parameter_gaits"] = json.dumps(basin.parameter_gaits)
            f.attrs["config"] = json.dumps(spec.config.model_dump(mode="json"), sort_keys=True)
            f.attrs["config_hash"] = spec.config.hash()
            for name, value in provenance().items():
                f.attrs[name] = value

    write_with(h5_path, write_h5)
    lines = [f"{spec.x.key},{spec.y.key},outcome,steps"]
    for j, y_value in enumerate(spec.y.values):
        for i, x_value in enumerate(spec.x.values):
            lines.append(f"{float(x_value)!r},{float(y_value)!r},{OUTCOMES[basin.outcome[j, i]]},{basin.steps[j, i]}")
    write_text_atomic(csv_path, "\n".join(lines) + "\n")
    return [h5_path, csv_path]
