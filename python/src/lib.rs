//! grainflow in Python: the `grainflow._grainflow` extension module, which the `grainflow`
//! package re-exports. A thin front end over the engine (`grainflow`) and the case layer
//! (`grainflow-case`): cases are read and validated exactly as `grainflow run` reads them, and
//! the simulation steps with the same bits.
//!
//! Views: `Simulation.particles.position` and its siblings are numpy arrays over the engine's
//! own storage, read-only, made without copying. While a view is alive, a call that changes
//! the simulation first hands the viewed storage over to the views (the engine goes on in a
//! copy, one per call): a view never dangles and never changes under its reader; it shows the
//! particles as they were when it was read.

use std::fmt::Display;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use grainflow::timestep::TimeStepRule;
use grainflow::{Particles, Simulation, Vec3};
use numpy::ndarray::{ArrayView1, ArrayView2};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

create_exception!(_grainflow, GrainflowError, PyException, "Base of grainflow's exceptions.");
create_exception!(
    _grainflow,
    CaseError,
    GrainflowError,
    "A case that cannot run: the message names the table, key and value, as `grainflow run` does."
);
create_exception!(
    _grainflow,
    EngineError,
    GrainflowError,
    "A request the simulation refuses (an unknown id, a value out of range, a run past its end)."
);
create_exception!(
    _grainflow,
    InternalError,
    GrainflowError,
    "A defect inside grainflow (a Rust panic); the simulation cannot be used afterwards."
);

// The views read `Vec3` as three f64 in a row.
const _: () = assert!(std::mem::size_of::<Vec3>() == 3 * std::mem::size_of::<f64>());

fn case_error(e: impl Display) -> PyErr {
    CaseError::new_err(e.to_string())
}

fn engine_error(e: impl Display) -> PyErr {
    EngineError::new_err(e.to_string())
}

/// The message of a caught panic.
fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic without a message".into())
}

/// `f`, with a panic turned into [`InternalError`].
fn guarded<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f))
        .unwrap_or_else(|p| Err(InternalError::new_err(format!("internal error: {}", panic_text(&*p)))))
}

/// The storage that one generation of views reads: the engine's until a change, then handed
/// over to them (see the module's doc).
#[pyclass(frozen, module = "grainflow._grainflow")]
struct Storage {
    held: Mutex<Option<Particles>>,
}

/// A simulation of a case, stepped from Python.
#[pyclass(name = "Simulation", module = "grainflow._grainflow")]
struct PySim {
    sim: Simulation,
    /// How the case's time step was chosen (a run's step count follows it).
    rule: TimeStepRule,
    t_start: f64,
    t_stop: f64,
    /// The case's hash, which checkpoints carry.
    hash: String,
    /// The meshes' names, and the points their torques are taken about, by mesh index.
    mesh_names: Vec<String>,
    torque_about: Vec<Vec3>,
    /// The storage the views of the current generation read, if any were made.
    views: Option<Py<Storage>>,
    /// Set when a panic left the simulation in an unknown state.
    broken: bool,
}

impl PySim {
    /// The simulation of `case`, from its start or (`restart`: a checkpoint, and whether it
    /// may be of another case) continued as `grainflow run --restart` continues it.
    fn from_loaded(
        case: grainflow_case::Case,
        threads: Option<usize>,
        restart: Option<(&Path, bool)>,
    ) -> PyResult<Self> {
        for w in &case.warnings {
            Python::attach(|py| {
                let warnings = py.import("warnings")?;
                warnings.call_method1("warn", (format!("grainflow: {w}"),)).map(|_| ())
            })?;
        }
        let (rule, t_start, t_stop) = (case.config.time_step, case.config.t_start, case.config.t_stop);
        let (hash, mesh_names, torque_about) = (case.hash.clone(), case.mesh_names, case.mesh_torque_about);
        let mut sim = match restart {
            None => Simulation::new(case.config, case.particles).map_err(engine_error)?,
            Some((path, any_case)) => {
                grainflow_run::run::restore_case(case.config, case.particles, path, any_case, &hash)
                    .map_err(engine_error)?
            }
        };
        if let Some(t) = threads {
            sim.set_threads(t).map_err(engine_error)?;
        }
        Ok(PySim { sim, rule, t_start, t_stop, hash, mesh_names, torque_about, views: None, broken: false })
    }

    /// The index of the phase `phase` (a name or an index; none: the only phase).
    fn phase_index(&self, phase: Option<&Bound<'_, PyAny>>) -> PyResult<usize> {
        let names: Vec<&str> = self.sim.phases().iter().map(|p| p.name.as_str()).collect();
        let Some(phase) = phase else {
            return if names.len() == 1 {
                Ok(0)
            } else {
                Err(engine_error(format!(
                    "the case has {} phases ({}): name one",
                    names.len(),
                    names.join(", ")
                )))
            };
        };
        if let Ok(name) = phase.extract::<String>() {
            return names.iter().position(|n| *n == name).ok_or_else(|| {
                engine_error(format!("no phase is named '{name}' (the case has {})", names.join(", ")))
            });
        }
        let k: i64 = phase.extract().map_err(|_| engine_error("phase: a phase's name or index"))?;
        usize::try_from(k)
            .ok()
            .filter(|&k| k < names.len())
            .ok_or_else(|| engine_error(format!("phase {k}: the case has phases 0 to {}", names.len() - 1)))
    }

    fn usable(&self) -> PyResult<()> {
        if self.broken {
            return Err(InternalError::new_err(
                "an earlier internal error left this simulation in an unknown state: make a new one",
            ));
        }
        Ok(())
    }

    /// Before a change: live views take over the storage they read.
    fn retire_views(&mut self, py: Python<'_>) {
        if let Some(s) = self.views.take()
            && unsafe { pyo3::ffi::Py_REFCNT(s.bind(py).as_ptr()) } > 1
        {
            let old = self.sim.swap_out_particles();
            *s.get().held.lock().unwrap_or_else(|e| e.into_inner()) = Some(old);
        }
    }

    /// The storage of the current generation of views.
    fn storage(&mut self, py: Python<'_>) -> PyResult<Py<Storage>> {
        if let Some(s) = &self.views {
            return Ok(s.clone_ref(py));
        }
        let s = Py::new(py, Storage { held: Mutex::new(None) })?;
        self.views = Some(s.clone_ref(py));
        Ok(s)
    }

    /// Steps `n` times without the GIL (fewer if the run ends first).
    fn advance(&mut self, py: Python<'_>, n: u64) -> PyResult<()> {
        self.usable()?;
        self.retire_views(py);
        let sim = &mut self.sim;
        let done = py.detach(|| catch_unwind(AssertUnwindSafe(|| sim.advance(n))));
        done.map_err(|p| {
            self.broken = true;
            InternalError::new_err(format!("internal error: {}", panic_text(&*p)))
        })
    }

    /// The step a run to `t` ends at (as `grainflow run` counts steps for `t_stop = t`).
    fn steps_until(&self, t: f64) -> PyResult<u64> {
        if !t.is_finite() || t <= self.t_start {
            return Err(engine_error(format!(
                "until = {t} s: the end of a run must be finite and after the start time {} s",
                self.t_start
            )));
        }
        if t > self.t_stop {
            return Err(engine_error(format!(
                "until = {t} s is after the case's end time t_stop = {} s: set a later t_stop in the case",
                self.t_stop
            )));
        }
        let (span, dt) = (t - self.t_start, self.sim.dt());
        Ok(self.rule.steps(span, dt))
    }

    /// The slots of `ids`, each an id of a particle of the simulation.
    fn slots_of(&self, ids: &[i64]) -> PyResult<Vec<usize>> {
        let p = self.sim.particles();
        ids.iter()
            .map(|&id| {
                u32::try_from(id)
                    .ok()
                    .and_then(|id| p.index_of(id))
                    .ok_or_else(|| engine_error(format!("no particle has id {id}")))
            })
            .collect()
    }

    /// Sets one vector of the particles `ids` (checked: known ids, finite values, one row each).
    fn set_vectors(
        &mut self,
        py: Python<'_>,
        what: &str,
        ids: &[i64],
        values: ArrayView2<'_, f64>,
        field: fn(&mut Particles) -> &mut Vec<Vec3>,
    ) -> PyResult<()> {
        self.usable()?;
        if values.shape() != [ids.len(), 3] {
            return Err(engine_error(format!(
                "{what}: {} ids need {} rows of 3 values, got an array of shape {:?}",
                ids.len(),
                ids.len(),
                values.shape()
            )));
        }
        if let Some(k) = values.rows().into_iter().position(|r| r.iter().any(|v| !v.is_finite())) {
            return Err(engine_error(format!("{what}: the values for particle {} are not finite", ids[k])));
        }
        let slots = self.slots_of(ids)?;
        self.retire_views(py);
        let v = field(self.sim.particles_mut());
        for (row, &i) in values.rows().into_iter().zip(&slots) {
            v[i] = Vec3::new(row[0], row[1], row[2]);
        }
        Ok(())
    }
}

impl Drop for PySim {
    fn drop(&mut self) {
        // Views outliving the simulation keep its storage.
        if self.views.is_some() {
            Python::attach(|py| self.retire_views(py));
        }
    }
}

/// A case's tables (a dict) as TOML, refusing what TOML cannot hold, by its key.
fn to_toml(v: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    let bad = |what: &str| case_error(format!("`{key}`: {what} cannot be written in a case file"));
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return v.extract::<i64>().map(toml::Value::Integer).map_err(|_| bad("an integer beyond 64 bits"));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::map::Map::new();
        for (k, x) in d.iter() {
            let name: String = k.extract().map_err(|_| bad("a table key that is not a string"))?;
            let path = if key.is_empty() { name.clone() } else { format!("{key}.{name}") };
            t.insert(name, to_toml(&x, &path)?);
        }
        return Ok(toml::Value::Table(t));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: Vec<toml::Value> = v
            .try_iter()?
            .enumerate()
            .map(|(k, x)| to_toml(&x?, &format!("{key}[{k}]")))
            .collect::<PyResult<_>>()?;
        return Ok(toml::Value::Array(items));
    }
    // numpy scalars and arrays, and anything else with a list or a number behind it.
    if let Ok(list) = v.call_method0("tolist")
        && !list.is(v)
    {
        return to_toml(&list, key);
    }
    Err(bad(&format!("a value of type {}", v.get_type().name()?)))
}

/// A case file read as `grainflow run` reads it (a TOML case, or an MFIX deck with its
/// `KEY=VALUE` overrides and motion file); a TOML case takes overrides as `--set` does, by
/// dotted keys (`{"time.t_stop": 0.1}`).
fn load_case(
    path: &Path,
    overrides: &[(String, Bound<'_, PyAny>)],
    motion: Option<&Path>,
) -> PyResult<grainflow_case::Case> {
    if grainflow_case::mfix::is_deck(path) {
        let sets: Vec<String> =
            overrides.iter().map(|(k, v)| Ok(format!("{k}={}", v.str()?))).collect::<PyResult<_>>()?;
        return grainflow_case::mfix::load(path, &sets, motion).map(|d| d.case).map_err(case_error);
    }
    if motion.is_some() {
        return Err(case_error(format!(
            "motion applies to MFIX decks (*.dat, *.mfx) only; {} is a TOML case file: put the rules in its [[motion]] tables",
            path.display()
        )));
    }
    let sets = overrides
        .iter()
        .map(|(k, v)| {
            let value = to_toml(v, k)?;
            grainflow_case::SetOverride::parse(&format!("{k}={value}")).map_err(case_error)
        })
        .collect::<PyResult<Vec<_>>>()?;
    grainflow_case::load_with(path, &sets).map_err(|e| match e {
        // Syntax and read errors name the file already; the others name table and key.
        grainflow_case::CaseError::Syntax(_) | grainflow_case::CaseError::Read { .. } => case_error(e),
        _ => case_error(format!("{}: {e}", path.display())),
    })
}

/// Case text validated as a case file in `base_dir` (which the files it names are read from).
fn parse_case(text: &str, base_dir: &Path) -> PyResult<grainflow_case::Case> {
    let read = |name: &str| -> Result<String, grainflow_case::CaseError> {
        let path = base_dir.join(name);
        std::fs::read_to_string(&path).map_err(|source| grainflow_case::CaseError::Read { path, source })
    };
    grainflow_case::parse(text, "case text", &read).map_err(case_error)
}

fn dict_items<'py>(d: Option<&Bound<'py, PyDict>>) -> PyResult<Vec<(String, Bound<'py, PyAny>)>> {
    d.map_or(Ok(Vec::new()), |d| {
        d.iter()
            .map(|(k, v)| {
                Ok((k.extract::<String>().map_err(|_| case_error("an override's key must be a string"))?, v))
            })
            .collect()
    })
}

#[pymethods]
impl PySim {
    /// Reads a TOML case or an MFIX deck, exactly as `grainflow run` does.
    #[staticmethod]
    #[pyo3(signature = (path, threads=None, overrides=None, motion=None))]
    fn from_case(
        path: PathBuf,
        threads: Option<usize>,
        overrides: Option<&Bound<'_, PyDict>>,
        motion: Option<PathBuf>,
    ) -> PyResult<Self> {
        guarded(|| {
            let case = load_case(&path, &dict_items(overrides)?, motion.as_deref())?;
            Self::from_loaded(case, threads, None)
        })
    }

    /// A case given as the text of a case file; the files it names are read from `base_dir`.
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=PathBuf::from("."), threads=None))]
    fn from_case_text(text: &str, base_dir: PathBuf, threads: Option<usize>) -> PyResult<Self> {
        guarded(|| Self::from_loaded(parse_case(text, &base_dir)?, threads, None))
    }

    /// A case given as a dict of its tables (the case file's structure, in Python values).
    #[staticmethod]
    #[pyo3(signature = (d, base_dir=PathBuf::from("."), threads=None))]
    fn from_dict(d: &Bound<'_, PyDict>, base_dir: PathBuf, threads: Option<usize>) -> PyResult<Self> {
        guarded(|| {
            let text = toml::to_string(&to_toml(d.as_any(), "")?).map_err(case_error)?;
            Self::from_loaded(parse_case(&text, &base_dir)?, threads, None)
        })
    }

    /// Continues from a checkpoint written by `checkpoint` or by `grainflow run`, for `case`
    /// (the case file it was written for, or one changed on purpose with
    /// `accept_changed_case=True`).
    #[staticmethod]
    #[pyo3(signature = (path, case, threads=None, accept_changed_case=false))]
    fn restart(
        path: PathBuf,
        case: PathBuf,
        threads: Option<usize>,
        accept_changed_case: bool,
    ) -> PyResult<Self> {
        guarded(|| {
            Self::from_loaded(load_case(&case, &[], None)?, threads, Some((&path, accept_changed_case)))
        })
    }

    /// Takes `n` steps (fewer if the run ends first), without holding the GIL.
    #[pyo3(signature = (n=1))]
    fn step(&mut self, py: Python<'_>, n: u64) -> PyResult<()> {
        self.advance(py, n)
    }

    /// Runs to the step `grainflow run` ends at for `t_stop = until` (default: the case's end),
    /// calling `callback(sim)` every `every` s of simulated time and at the end. A callback
    /// that raises stops the run at the last completed step, and its exception propagates.
    #[pyo3(signature = (until=None, every=None, callback=None))]
    fn run(
        slf: &Bound<'_, Self>,
        until: Option<f64>,
        every: Option<f64>,
        callback: Option<Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let py = slf.py();
        let (end, dt) = {
            let s = slf.borrow();
            s.usable()?;
            (s.steps_until(until.unwrap_or(s.t_stop))?, s.sim.dt())
        };
        let chunk = match every {
            None => u64::MAX,
            Some(e) if e.is_finite() && e > 0.0 => ((e / dt).round() as u64).max(1),
            Some(e) => return Err(engine_error(format!("every = {e} s: must be a positive time"))),
        };
        loop {
            let now = slf.borrow().sim.step_index();
            if now >= end {
                break;
            }
            let n = chunk.min(end - now);
            slf.borrow_mut().advance(py, n)?;
            if let Some(f) = &callback {
                f.call1((slf,))?;
            }
        }
        Ok(())
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }

    /// The time step, s.
    #[getter]
    fn dt(&self) -> f64 {
        self.sim.dt()
    }

    /// Steps taken since the run's start.
    #[getter]
    fn step_count(&self) -> u64 {
        self.sim.step_index()
    }

    /// Steps of the whole run (to the case's t_stop).
    #[getter]
    fn total_steps(&self) -> u64 {
        self.sim.total_steps()
    }

    /// The case's end time, s.
    #[getter]
    fn t_stop(&self) -> f64 {
        self.t_stop
    }

    /// The phases' names, by phase index.
    #[getter]
    fn phases(&self) -> Vec<String> {
        self.sim.phases().iter().map(|p| p.name.clone()).collect()
    }

    /// The particles, as read-only numpy views of the engine's storage.
    #[getter]
    fn particles(slf: &Bound<'_, Self>) -> ParticleViews {
        ParticleViews { sim: slf.clone().unbind() }
    }

    /// Sets the velocities (m/s) of the particles `ids`, one row of 3 each.
    fn set_velocity(
        &mut self,
        py: Python<'_>,
        ids: PyReadonlyArray1<'_, i64>,
        v: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let ids = ids.as_array().to_vec();
        guarded(|| self.set_vectors(py, "set_velocity", &ids, v.as_array(), |p| &mut p.velocity))
    }

    /// Sets the angular velocities (rad/s) of the particles `ids`, one row of 3 each.
    fn set_omega(
        &mut self,
        py: Python<'_>,
        ids: PyReadonlyArray1<'_, i64>,
        w: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let ids = ids.as_array().to_vec();
        guarded(|| self.set_vectors(py, "set_omega", &ids, w.as_array(), |p| &mut p.omega))
    }

    /// Moves the particles `ids` to positions `x` (m), one row of 3 each.
    fn set_position(
        &mut self,
        py: Python<'_>,
        ids: PyReadonlyArray1<'_, i64>,
        x: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let ids = ids.as_array().to_vec();
        guarded(|| self.set_vectors(py, "set_position", &ids, x.as_array(), |p| &mut p.position))
    }

    /// Adds particles between steps at `positions` (m, one row of 3 each) with `diameters`
    /// (m), velocities (m/s) and spins (rad/s) zero unless given, of `phase` (its name or
    /// index; the only phase by default) and its density; returns their new ids. The books
    /// count them as added. Overlaps are not checked: the contact law pushes them apart.
    #[pyo3(signature = (positions, diameters, velocities=None, phase=None, omega=None))]
    fn insert<'py>(
        &mut self,
        py: Python<'py>,
        positions: PyReadonlyArray2<'_, f64>,
        diameters: PyReadonlyArray1<'_, f64>,
        velocities: Option<PyReadonlyArray2<'_, f64>>,
        phase: Option<&Bound<'_, PyAny>>,
        omega: Option<PyReadonlyArray2<'_, f64>>,
    ) -> PyResult<Bound<'py, PyArray1<u32>>> {
        self.usable()?;
        let (x, d) = (positions.as_array(), diameters.as_array());
        let n = d.len();
        let rows = |what: &str, a: &ArrayView2<'_, f64>| -> PyResult<()> {
            if a.shape() == [n, 3] {
                Ok(())
            } else {
                Err(engine_error(format!(
                    "insert: {n} diameters need {what} of shape ({n}, 3), got {:?}",
                    a.shape()
                )))
            }
        };
        rows("positions", &x)?;
        let v = velocities.as_ref().map(|v| v.as_array());
        let w = omega.as_ref().map(|w| w.as_array());
        if let Some(v) = &v {
            rows("velocities", v)?;
        }
        if let Some(w) = &w {
            rows("omega", w)?;
        }
        let k = self.phase_index(phase)?;
        let density = self.sim.phases()[k].density;
        let first = self.sim.next_free_id();
        if first + n as u64 > u32::MAX as u64 {
            return Err(engine_error(format!("insert: ids beyond {} are not supported", u32::MAX)));
        }
        let row = |a: &Option<ArrayView2<'_, f64>>, i: usize| {
            a.as_ref().map_or(Vec3::ZERO, |a| Vec3::new(a[[i, 0]], a[[i, 1]], a[[i, 2]]))
        };
        let new: Vec<grainflow::state::ParticleInit> = (0..n)
            .map(|i| grainflow::state::ParticleInit {
                id: (first + i as u64) as u32,
                phase: k as u32,
                radius: 0.5 * d[i],
                density,
                position: Vec3::new(x[[i, 0]], x[[i, 1]], x[[i, 2]]),
                velocity: row(&v, i),
                omega: row(&w, i),
            })
            .collect();
        self.retire_views(py);
        guarded(|| self.sim.insert(&new).map_err(engine_error))?;
        let ids: Vec<u32> = new.iter().map(|q| q.id).collect();
        Ok(PyArray1::from_vec(py, ids))
    }

    /// Removes the particles `ids` between steps (each must exist); returns how many. The
    /// books count them as taken.
    fn remove(&mut self, py: Python<'_>, ids: PyReadonlyArray1<'_, i64>) -> PyResult<usize> {
        self.usable()?;
        let ids = ids.as_array().to_vec();
        self.slots_of(&ids)?;
        let ids: Vec<u32> = ids.iter().map(|&i| i as u32).collect();
        self.retire_views(py);
        guarded(|| self.sim.remove_ids(&ids).map_err(engine_error))
    }

    /// The mass books: for `initial`, `inserted` (by the case's insertions), `added` (by
    /// `insert`), `removed` (by outlets), `taken` (by `remove`) and `present`, a (count, kg)
    /// pair each, and `closes`: initial + inserted + added = present + removed + taken, exactly
    /// (in the books' mass quanta).
    fn books<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let b = self.sim.flow_books();
        let out = PyDict::new(py);
        let pair = |t: grainflow::Tally| (t.count, b.mass(t));
        out.set_item("initial", pair(b.initial))?;
        out.set_item("inserted", pair(b.inserted_total()))?;
        out.set_item("added", pair(b.added))?;
        out.set_item("removed", pair(b.removed_total()))?;
        out.set_item("taken", pair(b.taken))?;
        out.set_item("present", pair(b.present))?;
        out.set_item("closes", b.close())?;
        Ok(out)
    }

    /// The contacts of the current state, as arrays: `id` (the particle the normal points
    /// from), `other` (the partner: "particle", or the wall's, mesh's or cylinder's name),
    /// `other_id` (the partner particle's id, −1 for a wall), `triangle` (a mesh's triangle,
    /// −1 otherwise), `point` and `normal` (N×3, m), `overlap` (m), `normal_force` and
    /// `tangential_force` (N).
    fn contacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.usable()?;
        let c = guarded(|| Ok(self.sim.contacts()))?;
        let ids = &self.sim.particles().id;
        let (walls, cylinders) = (self.sim.walls(), self.sim.cylinders());
        let mut other = Vec::with_capacity(c.len());
        let (mut other_id, mut triangle) = (Vec::with_capacity(c.len()), Vec::with_capacity(c.len()));
        for k in &c {
            let (name, id, t) = match k.other {
                grainflow::ContactPartner::Particle(j) => ("particle".to_string(), ids[j] as i64, -1),
                grainflow::ContactPartner::Wall(w) => (walls[w].name.clone(), -1, -1),
                grainflow::ContactPartner::Mesh { mesh, triangle } => (
                    self.mesh_names.get(mesh).cloned().unwrap_or_else(|| format!("mesh {mesh}")),
                    -1,
                    triangle as i64,
                ),
                grainflow::ContactPartner::Cylinder(k) => (cylinders[k].name.clone(), -1, -1),
            };
            other.push(name);
            other_id.push(id);
            triangle.push(t);
        }
        let vecs = |f: fn(&grainflow::ContactInfo) -> Vec3| -> PyResult<Bound<'py, PyArray2<f64>>> {
            let flat: Vec<f64> = c.iter().flat_map(|k| f(k).to_array()).collect();
            PyArray1::from_vec(py, flat).reshape([c.len(), 3])
        };
        let out = PyDict::new(py);
        out.set_item("id", PyArray1::from_vec(py, c.iter().map(|k| ids[k.particle]).collect()))?;
        out.set_item("other", other)?;
        out.set_item("other_id", PyArray1::from_vec(py, other_id))?;
        out.set_item("triangle", PyArray1::from_vec(py, triangle))?;
        out.set_item("point", vecs(|k| k.point)?)?;
        out.set_item("normal", vecs(|k| k.normal)?)?;
        out.set_item("overlap", PyArray1::from_vec(py, c.iter().map(|k| k.overlap).collect()))?;
        out.set_item("normal_force", PyArray1::from_vec(py, c.iter().map(|k| k.normal_force).collect()))?;
        out.set_item(
            "tangential_force",
            PyArray1::from_vec(py, c.iter().map(|k| k.tangential_force).collect()),
        )?;
        Ok(out)
    }

    /// The meshes by name, each a `Mesh`: its pose and load, and its motion to set.
    #[getter]
    fn meshes<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyDict>> {
        let py = slf.py();
        let out = PyDict::new(py);
        for (index, name) in slf.borrow().mesh_names.iter().enumerate() {
            out.set_item(name, MeshHandle { sim: slf.clone().unbind(), index, name: name.clone() })?;
        }
        Ok(out)
    }

    /// Writes a checkpoint to `path` (written whole or not at all), which
    /// `Simulation.restart` and `grainflow run --restart` continue from. The motions set on
    /// meshes from Python are in it: a restart goes on with them, not with the case's.
    fn checkpoint(&self, path: PathBuf) -> PyResult<()> {
        self.usable()?;
        guarded(|| {
            grainflow_run::output::write_atomic_with(&path, |w| self.sim.write_checkpoint(&self.hash, w))
                .map_err(|e| engine_error(format!("{}: {e}", path.display())))
        })
    }

    /// Writes the particles, in id order, as a VTK PolyData file (`.vtp`, as `grainflow run`
    /// writes its frames: points with `id`, `phase`, `radius`, `velocity`,
    /// `angular_velocity`, `force`, `contacts`), and with `contacts` the contacts as lines to
    /// that second file. Each file is written whole or not at all.
    #[pyo3(signature = (path, contacts=None))]
    fn write_vtk(&self, path: PathBuf, contacts: Option<PathBuf>) -> PyResult<()> {
        self.usable()?;
        guarded(|| {
            let (p, c) = self.sim.in_id_order();
            let write = |path: &Path, text: String| {
                grainflow_run::output::write_atomic_with(path, |w| {
                    std::io::Write::write_all(w, text.as_bytes())
                })
                .map_err(|e| engine_error(format!("{}: {e}", path.display())))
            };
            write(&path, grainflow_run::vtk::particles_vtp(&p, &c))?;
            if let Some(cpath) = contacts {
                write(&cpath, grainflow_run::vtk::contacts_vtp(&p, &c))?;
            }
            Ok(())
        })
    }

    /// Kinetic energies (J) and the largest overlap over radius, as a dict.
    fn diagnostics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = self.sim.diagnostics();
        let out = PyDict::new(py);
        out.set_item("kinetic_translational", d.kinetic_translational)?;
        out.set_item("kinetic_rotational", d.kinetic_rotational)?;
        out.set_item("potential", d.potential)?;
        out.set_item("elastic", d.elastic)?;
        out.set_item("max_overlap_ratio", d.max_overlap_ratio)?;
        Ok(out)
    }

    fn __repr__(&self) -> String {
        format!(
            "<grainflow.Simulation: {} particles, step {} of {}, t = {} s>",
            self.sim.particles().len(),
            self.sim.step_index(),
            self.sim.total_steps(),
            self.sim.time()
        )
    }

    /// Raises InternalError from inside the engine's call guard: for the tests of that path.
    #[staticmethod]
    fn _panic_for_test() -> PyResult<()> {
        guarded(|| panic!("a panic raised on purpose"))
    }
}

/// A mesh of a simulation: where it is, the load on it, and its motion from now on.
#[pyclass(frozen, name = "Mesh", module = "grainflow._grainflow")]
struct MeshHandle {
    sim: Py<PySim>,
    index: usize,
    name: String,
}

impl MeshHandle {
    fn set(&self, py: Python<'_>, motion: grainflow::mesh::MeshMotion) -> PyResult<()> {
        let mut s = self.sim.bind(py).borrow_mut();
        s.usable()?;
        let m = self.index;
        guarded(|| s.sim.set_mesh_motion(m, motion).map_err(engine_error))
    }
}

fn unit(a: [f64; 3], what: &str) -> PyResult<Vec3> {
    let v = Vec3::from_array(a);
    let n = v.length();
    if n.is_finite() && n > 0.0 {
        Ok(v / n)
    } else {
        Err(engine_error(format!("{what}: a non-zero finite vector")))
    }
}

#[pymethods]
impl MeshHandle {
    /// The mesh's name in the case.
    #[getter]
    fn name(&self) -> String {
        self.name.clone()
    }

    /// The translation of its pose now, m (from the mesh as loaded).
    #[getter]
    fn translation(&self, py: Python<'_>) -> [f64; 3] {
        self.sim.bind(py).borrow().sim.mesh_pose(self.index).translation.to_array()
    }

    /// The rotation of its pose now, a unit quaternion (x, y, z, w).
    #[getter]
    fn rotation(&self, py: Python<'_>) -> [f64; 4] {
        self.sim.bind(py).borrow().sim.mesh_pose(self.index).rotation.to_array()
    }

    /// The force the particles exerted on it at the last force evaluation, N.
    #[getter]
    fn force(&self, py: Python<'_>) -> [f64; 3] {
        let s = self.sim.bind(py).borrow();
        s.sim.mesh_load(self.index, Vec3::ZERO).force.to_array()
    }

    /// The torque of that load about the case's point for this mesh (its `torque_about`,
    /// else the origin), N·m.
    #[getter]
    fn torque(&self, py: Python<'_>) -> [f64; 3] {
        let s = self.sim.bind(py).borrow();
        let about = s.torque_about.get(self.index).copied().unwrap_or(Vec3::ZERO);
        s.sim.mesh_load(self.index, about).torque.to_array()
    }

    /// From now on, turns at `omega` rad/s about the axis through `origin` (m) along `axis`
    /// (right-hand rule); both default to those of its motion if it turns. It goes on from
    /// where it is. Between steps, e.g. in a `run` callback.
    #[pyo3(signature = (omega, axis=None, origin=None))]
    fn set_omega(
        &self,
        py: Python<'_>,
        omega: f64,
        axis: Option<[f64; 3]>,
        origin: Option<[f64; 3]>,
    ) -> PyResult<()> {
        let now = self.sim.bind(py).borrow().sim.meshes()[self.index].motion;
        let (axis0, origin0) = match now {
            grainflow::mesh::MeshMotion::Rotate { axis, origin, .. } => (Some(axis), Some(origin)),
            _ => (None, None),
        };
        let axis = match axis {
            Some(a) => unit(a, "axis")?,
            None => axis0
                .ok_or_else(|| engine_error(format!("mesh '{}' does not turn: give the axis", self.name)))?,
        };
        let origin = match origin {
            Some(o) => Vec3::from_array(o),
            None => origin0.ok_or_else(|| {
                engine_error(format!("mesh '{}' does not turn: give the origin", self.name))
            })?,
        };
        self.set(py, grainflow::mesh::MeshMotion::Rotate { origin, axis, omega, ramp: 0.0 })
    }

    /// From now on, moves at `velocity` m/s (zero stops it where it is).
    fn set_velocity(&self, py: Python<'_>, velocity: [f64; 3]) -> PyResult<()> {
        self.set(py, grainflow::mesh::MeshMotion::Translate { velocity: Vec3::from_array(velocity) })
    }

    fn __repr__(&self) -> String {
        format!("<grainflow.Mesh '{}'>", self.name)
    }
}

/// The particles of a simulation: each attribute a read-only numpy view, made without copying.
#[pyclass(frozen, module = "grainflow._grainflow")]
struct ParticleViews {
    sim: Py<PySim>,
}

/// A read-only view of `len` rows of `cols` values of type `T` at `ptr`, kept alive by `owner`.
fn view<'py, T: numpy::Element>(
    py: Python<'py>,
    ptr: *const T,
    len: usize,
    cols: Option<usize>,
    owner: Py<Storage>,
) -> PyResult<Bound<'py, PyAny>> {
    // An empty Vec's pointer is dangling but aligned and never read.
    let array = match cols {
        None => {
            let a = unsafe { ArrayView1::from_shape_ptr(len, ptr) };
            unsafe { PyArray1::borrow_from_array(&a, owner.into_bound(py).into_any()) }.into_any()
        }
        Some(c) => {
            let a = unsafe { ArrayView2::from_shape_ptr((len, c), ptr) };
            unsafe { PyArray2::borrow_from_array(&a, owner.into_bound(py).into_any()) }.into_any()
        }
    };
    let kwargs = PyDict::new(py);
    kwargs.set_item("write", false)?;
    array.call_method("setflags", (), Some(&kwargs))?;
    Ok(array)
}

impl ParticleViews {
    fn vectors<'py>(&self, py: Python<'py>, pick: fn(&Particles) -> &[Vec3]) -> PyResult<Bound<'py, PyAny>> {
        let mut s = self.sim.bind(py).borrow_mut();
        s.usable()?;
        let owner = s.storage(py)?;
        let v = pick(s.sim.particles());
        view(py, v.as_ptr() as *const f64, v.len(), Some(3), owner)
    }

    fn scalars<'py, T: numpy::Element>(
        &self,
        py: Python<'py>,
        pick: fn(&Particles) -> &[T],
    ) -> PyResult<Bound<'py, PyAny>> {
        let mut s = self.sim.bind(py).borrow_mut();
        s.usable()?;
        let owner = s.storage(py)?;
        let v = pick(s.sim.particles());
        view(py, v.as_ptr(), v.len(), None, owner)
    }
}

#[pymethods]
impl ParticleViews {
    /// Ids (uint32), by slot.
    #[getter]
    fn ids<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.scalars(py, |p| &p.id)
    }

    /// Phase index of each particle (uint32; `Simulation.phases` names them).
    #[getter]
    fn phase<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.scalars(py, |p| &p.phase)
    }

    /// Radii, m.
    #[getter]
    fn radius<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.scalars(py, |p| &p.radius)
    }

    /// Masses, kg.
    #[getter]
    fn mass<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.scalars(py, |p| &p.mass)
    }

    /// Positions, m (N×3).
    #[getter]
    fn position<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.vectors(py, |p| &p.position)
    }

    /// Velocities, m/s (N×3).
    #[getter]
    fn velocity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.vectors(py, |p| &p.velocity)
    }

    /// Angular velocities, rad/s (N×3).
    #[getter]
    fn omega<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.vectors(py, |p| &p.omega)
    }

    /// Contact forces of the last evaluation, N (N×3).
    #[getter]
    fn force<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.vectors(py, |p| &p.force)
    }

    /// Contact torques of the last evaluation, N·m (N×3).
    #[getter]
    fn torque<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.vectors(py, |p| &p.torque)
    }

    fn __len__(&self, py: Python<'_>) -> usize {
        self.sim.bind(py).borrow().sim.particles().len()
    }
}

#[pymodule]
fn _grainflow(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<PySim>()?;
    m.add_class::<ParticleViews>()?;
    m.add_class::<MeshHandle>()?;
    m.add("GrainflowError", py.get_type::<GrainflowError>())?;
    m.add("CaseError", py.get_type::<CaseError>())?;
    m.add("EngineError", py.get_type::<EngineError>())?;
    m.add("InternalError", py.get_type::<InternalError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
