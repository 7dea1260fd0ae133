"""grainflow: a discrete element method engine for granular flows, scripted from Python.

Cases are read and validated exactly as ``grainflow run`` reads them, and a simulation stepped
from Python in any chunks has the same bits as the command-line run. Units are SI throughout.
"""

import csv as _csv

import numpy as _np

from ._grainflow import (
    CaseError,
    EngineError,
    GrainflowError,
    InternalError,
    Mesh,
    ParticleViews,
    Simulation,
    __version__,
)

__all__ = [
    "CaseError",
    "EngineError",
    "GrainflowError",
    "InternalError",
    "Mesh",
    "ParticleViews",
    "Simulation",
    "read_timeseries",
    "__version__",
]


def read_timeseries(path):
    """The columns of a run's ``timeseries.csv``, by header name, as float64 numpy arrays."""
    with open(path, newline="") as f:
        rows = list(_csv.reader(f))
    if not rows:
        raise EngineError(f"{path}: an empty time series (no header row)")
    header, body = rows[0], rows[1:]
    for k, row in enumerate(body):
        if len(row) != len(header):
            raise EngineError(
                f"{path}: row {k + 2} has {len(row)} values for {len(header)} columns"
            )
    columns = list(zip(*body)) if body else [()] * len(header)
    return {name: _np.array(col, dtype=_np.float64) for name, col in zip(header, columns)}
