"""An uncertainty study's files: ``uncertainty.h5`` (everything) and ``samples.csv`` (one row a sample).

``uncertainty.h5``: ``keys`` (strings) and ``values`` (runs x keys), ``unit`` (the design in the unit cube,
absent for posterior samples), ``status`` (strings), one dataset per scalar output (NaN where a sample has
none), ``periods`` (runs x step number, NaN past a sample's last step), ``bands/`` (step, count, quantiles,
quantile levels); root attributes: ``statistics``, ``sobol``, ``surrogate`` and ``notes`` (JSON), the resolved
config and its hash, the samples' source, and the provenance. Both files are written atomically.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from biped_sim.io.atomic import json_safe, write_text_atomic, write_with
from biped_sim.io.provenance import provenance
from biped_sim.studies.uncertainty.statistics import BAND_QUANTILES, column, period_matrix
from biped_sim.studies.uncertainty.study import Uncertainty, output_names

H5_FILE, CSV_FILE = "uncertainty.h5", "samples.csv"


def _h5_image(study: Uncertainty) -> bytes:
    """The bytes of uncertainty.h5, built in memory: HDF5 never writes to the disk itself, so that a full disk is one
    Python OSError when the bytes are written, not an error inside the HDF5 library."""
    import h5py

    names = output_names(study.spec.config)
    doc = study.to_json()
    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        f.create_dataset("keys", data=np.array(list(study.spec.keys), dtype=h5py.string_dtype()))
        f.create_dataset("values", data=study.values)
        if study.unit is not None:
            f.create_dataset("unit", data=study.unit)
        f.create_dataset("status", data=np.array([o["status"] for o in study.outputs], dtype=h5py.string_dtype()))
        for name in names:
            f.create_dataset(name, data=column(study.outputs, name))
        f.create_dataset("periods", data=period_matrix(study.outputs))
        bands = f.create_group("bands")
        for name, data in study.bands.items():
            bands.create_dataset(name, data=data)
        bands.attrs["quantile_levels"] = np.array(BAND_QUANTILES)
        for name in ("statistics", "sobol", "surrogate", "notes"):
            f.attrs[name] = json.dumps(json_safe(doc[name]))
        f.attrs["source"] = json.dumps(study.spec.source())
        f.attrs["config"] = json.dumps(study.spec.config.model_dump(mode="json"), sort_keys=True)
        f.attrs["config_hash"] = study.spec.config.hash()
        for name, value in provenance().items():
            f.attrs[name] = value
    return buffer.getvalue()


def samples_csv(study: Uncertainty) -> str:
    """One row per sample: its index, the keys' values, status, reason, steps and the scalar outputs."""
    names = output_names(study.spec.config)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["sample", *study.spec.keys, "status", "reason", "n_steps", *names])
    for i, (row, record) in enumerate(zip(study.values, study.outputs, strict=True)):
        scalars = ["" if record.get(n) is None or not np.isfinite(record[n]) else repr(float(record[n])) for n in names]
        writer.writerow([i, *(repr(float(v)) for v in row), record["status"], record.get("reason") or "",
                         record["n_steps"], *scalars])  # fmt: skip
    return buffer.getvalue()


def write_study(study: Uncertainty, out_dir: Path) -> list[Path]:
    """uncertainty.h5 and samples.csv in ``out_dir``, atomically; returns their paths."""
    out_dir.mkdir(parents=True, exist_ok=True)
    h5_path, csv_path = out_dir / H5_FILE, out_dir / CSV_FILE
    image = _h5_image(study)
    write_with(h5_path, lambda tmp: tmp.write_bytes(image))
    write_text_atomic(csv_path, samples_csv(study))
    return [h5_path, csv_path]
