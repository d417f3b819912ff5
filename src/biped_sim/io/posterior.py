"""Posterior samples of a calibration, as the fit writes them and the uncertainty study reads them.

``FIT_DIR/posterior.h5`` (plain h5py):

* ``samples`` (n_samples x n_parameters, float64): draws of the fitted config keys, burn-in removed and
  thinned, one row a sample; ``parameters`` (strings): the dotted config keys, one per column;
* ``log_probability`` (n_samples): the log posterior of each row;
* root attributes: ``config`` (the resolved base config as YAML: the fitted keys are overwritten by each
  sample), ``config_hash`` and the provenance of :func:`biped_sim.io.provenance.provenance`; the fit adds
  the sampler's diagnostics (``acceptance_fraction``, ``autocorrelation_time``, ``discard``, ``thin``,
  ``seed``);
* optional datasets beside them (the fit writes ``chain``, steps x walkers x parameters, and
  ``chain_log_probability``, the whole chain before burn-in and thinning).

The file is written atomically; reading checks its layout and gives one-line errors naming the file.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from biped_sim.errors import ConfigError
from biped_sim.io.atomic import write_with

POSTERIOR_FILE = "posterior.h5"


@dataclass(frozen=True)
class Posterior:
    """Posterior draws of config keys: ``samples[i, j]`` is draw i of ``parameters[j]``."""

    parameters: tuple[str, ...]
    samples: np.ndarray
    log_probability: np.ndarray
    config_yaml: str

    def __post_init__(self) -> None:
        if self.samples.ndim != 2 or self.samples.shape[1] != len(self.parameters):
            raise ValueError(f"samples must be (n, {len(self.parameters)}), not {self.samples.shape}")
        if self.log_probability.shape != (self.samples.shape[0],):
            raise ValueError("log_probability must hold one value per sample")


def write_posterior(
    path: str | Path,
    posterior: Posterior,
    attributes: dict[str, Any],
    datasets: dict[str, np.ndarray] | None = None,
) -> None:
    """Write ``posterior`` to ``path`` atomically, with ``attributes`` (hash, provenance) on the root and
    optional further ``datasets`` (read_posterior ignores them)."""
    buffer = io.BytesIO()
    with h5py.File(buffer, "w", track_order=True) as f:
        for key, value in attributes.items():
            f.attrs[key] = value
        f.attrs["config"] = posterior.config_yaml
        f.create_dataset("samples", data=np.asarray(posterior.samples, dtype=np.float64), track_times=False)
        names = np.array(list(posterior.parameters), dtype=h5py.string_dtype())
        f.create_dataset("parameters", data=names, track_times=False)
        f.create_dataset("log_probability", data=np.asarray(posterior.log_probability, dtype=np.float64))
        for name, data in (datasets or {}).items():
            f.create_dataset(name, data=np.asarray(data, dtype=np.float64), track_times=False)
    image = buffer.getvalue()
    write_with(path, lambda tmp: tmp.write_bytes(image))


def read_posterior(location: str | Path) -> Posterior:
    """The posterior in ``location`` (a fit directory or the ``posterior.h5`` file itself)."""
    path = Path(location)
    if path.is_dir():
        path = path / POSTERIOR_FILE
    if not path.is_file():
        raise ConfigError(str(path), "no posterior here (run the fit with its Bayesian mode first)")
    try:
        with h5py.File(path, "r") as f:
            samples = np.asarray(f["samples"][()], dtype=np.float64)
            parameters = tuple(name.decode() if isinstance(name, bytes) else str(name) for name in f["parameters"][()])
            log_probability = np.asarray(f["log_probability"][()], dtype=np.float64)
            config_yaml = str(f.attrs["config"])
    except (OSError, KeyError) as exc:
        raise ConfigError(str(path), f"not a posterior file ({type(exc).__name__}: {str(exc)[:80]})") from None
    try:
        posterior = Posterior(parameters, samples, log_probability, config_yaml)
    except ValueError as exc:
        raise ConfigError(str(path), str(exc)) from None
    if samples.shape[0] == 0 or not np.all(np.isfinite(samples)):
        raise ConfigError(str(path), "the posterior holds no samples, or non-finite ones")
    return posterior
