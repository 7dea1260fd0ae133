"""Type stubs of grainflow's Python package. Units are SI: m, s, kg, N, rad."""

from os import PathLike
from typing import Any, Callable, Dict, Mapping, Optional, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike]

__version__: str

class GrainflowError(Exception):
    """Base of grainflow's exceptions."""

class CaseError(GrainflowError):
    """A case that cannot run; the message names the table, key and value, as `grainflow run` does."""

class EngineError(GrainflowError):
    """A request the simulation refuses: an unknown id, a value out of range, a run past its end."""

class InternalError(GrainflowError):
    """A defect inside grainflow (a Rust panic); the simulation cannot be used afterwards."""

class ParticleViews:
    """The particles of a simulation, by slot. Each attribute is a read-only numpy view of the
    engine's storage, made without copying; a view held across a change keeps showing the
    particles as they were when it was read."""

    @property
    def ids(self) -> npt.NDArray[np.uint32]:
        """Ids, (N,)."""
    @property
    def phase(self) -> npt.NDArray[np.uint32]:
        """Phase index of each particle, (N,); `Simulation.phases` names them."""
    @property
    def radius(self) -> npt.NDArray[np.float64]:
        """Radii, m, (N,)."""
    @property
    def mass(self) -> npt.NDArray[np.float64]:
        """Masses, kg, (N,)."""
    @property
    def position(self) -> npt.NDArray[np.float64]:
        """Positions, m, (N, 3)."""
    @property
    def velocity(self) -> npt.NDArray[np.float64]:
        """Velocities, m/s, (N, 3)."""
    @property
    def omega(self) -> npt.NDArray[np.float64]:
        """Angular velocities, rad/s, (N, 3)."""
    @property
    def force(self) -> npt.NDArray[np.float64]:
        """Contact forces of the last force evaluation, N, (N, 3)."""
    @property
    def torque(self) -> npt.NDArray[np.float64]:
        """Contact torques of the last force evaluation, N·m, (N, 3)."""
    def __len__(self) -> int: ...

class Mesh:
    """A mesh of a simulation: where it is, the load on it, and its motion from now on."""

    @property
    def name(self) -> str: ...
    @property
    def translation(self) -> list[float]:
        """The translation of its pose now, m."""
    @property
    def rotation(self) -> list[float]:
        """The rotation of its pose now, a unit quaternion (x, y, z, w)."""
    @property
    def force(self) -> list[float]:
        """The force of the particles on it at the last force evaluation, N."""
    @property
    def torque(self) -> list[float]:
        """The torque of that load about the case's point for it, N·m."""
    def set_omega(
        self, omega: float, axis: Optional[list[float]] = None, origin: Optional[list[float]] = None
    ) -> None:
        """Turns at `omega` rad/s from now on, about `axis` through `origin` (m; both default to
        its motion's if it turns), from where it is."""
    def set_velocity(self, velocity: list[float]) -> None:
        """Moves at `velocity` m/s from now on (zero stops it where it is)."""

class Simulation:
    """A simulation of a case, stepped from Python with the bits of `grainflow run`."""

    @staticmethod
    def from_case(
        path: _Path,
        threads: Optional[int] = None,
        overrides: Optional[Mapping[str, Any]] = None,
        motion: Optional[_Path] = None,
    ) -> "Simulation":
        """Reads a TOML case or an MFIX deck as `grainflow run` does. `overrides`: for a deck,
        MFIX keywords (`{"TSTOP": 0.1}`); for a TOML case, dotted keys as `--set` takes them
        (`{"time.t_stop": 0.1}`). `motion`: a deck's motion file. Raises CaseError."""
    @staticmethod
    def from_case_text(text: str, base_dir: _Path = ".", threads: Optional[int] = None) -> "Simulation":
        """The text of a case file; the files it names are read from `base_dir`."""
    @staticmethod
    def from_dict(d: Mapping[str, Any], base_dir: _Path = ".", threads: Optional[int] = None) -> "Simulation":
        """A case file's tables as a dict of Python values (numbers, strings, lists, dicts)."""
    @staticmethod
    def restart(
        path: _Path, case: _Path, threads: Optional[int] = None, accept_changed_case: bool = False
    ) -> "Simulation":
        """Continues from a checkpoint (of `checkpoint` or `grainflow run`) for the case file
        `case`; a checkpoint of another case only with `accept_changed_case`. Raises EngineError."""
    def step(self, n: int = 1) -> None:
        """Takes `n` steps (fewer if the run ends first), without holding the GIL."""
    def run(
        self,
        until: Optional[float] = None,
        every: Optional[float] = None,
        callback: Optional[Callable[["Simulation"], Any]] = None,
    ) -> None:
        """Runs to the step `grainflow run` ends at for t_stop = `until` (s; default the case's
        t_stop, which it may not pass), calling `callback(sim)` every `every` s of simulated
        time. A callback that raises stops the run at the last completed step; its exception
        propagates unchanged."""
    @property
    def time(self) -> float:
        """Simulated time, s."""
    @property
    def dt(self) -> float:
        """The time step, s."""
    @property
    def step_count(self) -> int:
        """Steps taken since the run's start."""
    @property
    def total_steps(self) -> int:
        """Steps of the whole run, to the case's t_stop."""
    @property
    def t_stop(self) -> float:
        """The case's end time, s."""
    @property
    def phases(self) -> list[str]:
        """The phases' names, by phase index."""
    @property
    def particles(self) -> ParticleViews:
        """The particles, as read-only numpy views."""
    def set_velocity(self, ids: npt.NDArray[np.int64], v: npt.NDArray[np.float64]) -> None:
        """Sets the velocities (m/s, one row of 3 per id). Raises EngineError for an unknown id,
        a shape that does not fit or a value that is not finite, changing nothing."""
    def set_omega(self, ids: npt.NDArray[np.int64], w: npt.NDArray[np.float64]) -> None:
        """Sets the angular velocities (rad/s), as `set_velocity`."""
    def set_position(self, ids: npt.NDArray[np.int64], x: npt.NDArray[np.float64]) -> None:
        """Moves the particles to `x` (m), as `set_velocity`."""
    def insert(
        self,
        positions: npt.NDArray[np.float64],
        diameters: npt.NDArray[np.float64],
        velocities: Optional[npt.NDArray[np.float64]] = None,
        phase: Optional[Union[str, int]] = None,
        omega: Optional[npt.NDArray[np.float64]] = None,
    ) -> npt.NDArray[np.uint32]:
        """Adds particles (positions m, diameters m, velocities m/s, spins rad/s) of `phase`
        (name or index; the only phase by default); returns their new ids."""
    def remove(self, ids: npt.NDArray[np.int64]) -> int:
        """Removes the particles `ids` (each must exist); returns how many."""
    def books(self) -> Dict[str, Any]:
        """The mass books as (count, kg) pairs: initial, inserted, added, removed, taken,
        present; and `closes`."""
    def contacts(self) -> Dict[str, Any]:
        """The contacts now: id, other, other_id, triangle, point (m), normal, overlap (m),
        normal_force and tangential_force (N)."""
    @property
    def meshes(self) -> Dict[str, Mesh]:
        """The meshes by name."""
    def checkpoint(self, path: _Path) -> None:
        """Writes a checkpoint, whole or not at all. Motions set on meshes from Python are in
        it: a restart goes on with them."""
    def write_vtk(self, path: _Path, contacts: Optional[_Path] = None) -> None:
        """Writes the particles (id order) as a VTK .vtp file, and the contacts to `contacts`."""
    def diagnostics(self) -> Dict[str, float]:
        """kinetic_translational, kinetic_rotational, potential, elastic (J), max_overlap_ratio."""

def read_timeseries(path: _Path) -> Dict[str, npt.NDArray[np.float64]]:
    """The columns of a run's timeseries.csv, by header name."""
