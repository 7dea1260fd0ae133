//! From a raw case file to a validated [`Case`]: SI values, engine objects, cross-field checks.

//!
//! `validate` reads the tables in a fixed order, one validator per table, each in its own
//! module on the field helpers of `fields`; the first mistake found is the one reported.

mod contact;
mod cylinders;
mod domain;
pub(crate) mod fields;
pub(crate) mod flow;
mod geometry;
mod materials;
mod meshes;
mod motion;
mod particles;
mod settings;
mod time;

pub use meshes::rotation_axis;

use crate::error::CaseError;
use crate::input;
use crate::raw::RawCase;
use crate::set::SetOverride;
use fields::{did_you_mean, require};
use grainflow::{Particles, SimulationConfig, Vec3};
use std::path::Path;

/// The case-file format version this program reads.
pub const CASE_VERSION: i64 = 1;

/// A validated case, ready to become a [`grainflow::Simulation`].
#[derive(Debug, Clone)]
pub struct Case {
    /// The case's title.
    pub title: String,
    /// Engine configuration.
    pub config: SimulationConfig,
    /// Initial particles.
    pub particles: Particles,
    /// Output settings.
    pub output: OutputSettings,
    /// The domain box (lower and upper corner), m.
    pub domain: (Vec3, Vec3),
    /// SHA-256 of the case text and every file it read, hex: ties outputs and checkpoints to
    /// their inputs.
    pub hash: String,
    /// Things the user should know (e.g. parameters the chosen model does not use).
    pub warnings: Vec<String>,
    /// `[particles] max_overlap`: the largest overlap allowed during the run, as a fraction of
    /// the smaller radius (the run's health check stops a run that exceeds it).
    pub max_overlap: f64,
    /// The mesh walls' names, in the order of `config.meshes`.
    pub mesh_names: Vec<String>,
    /// The point each mesh's torque is reported about in the time series (`torque_about`,
    /// else its rotation axis's origin, else the origin of coordinates), m.
    pub mesh_torque_about: Vec<Vec3>,
    /// `[parallel]`: on ranks, the slowest rank's work over the mean, less 1, beyond which
    /// their boxes are cut again (none: never).
    pub rebalance: Option<f64>,
    /// `[parallel] weigh`: what that imbalance is of (measured time by default).
    pub weigh: grainflow::domain::Weigh,
    /// True when `particles` is this rank's share of the case's initial particles (those of
    /// the box it starts with, in the file's order, handed out by rank 0), false when it is
    /// all of them.
    pub particles_are_share: bool,
}

/// Which of the case's initial particles (`[particles]`: its file and its list) a process
/// reads, checks and holds. Over ranks rank 0 reads them all and checks them as one process
/// does, then hands each rank its share: the other ranks never hold the whole set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Bed {
    /// All of them, their file passed through the relay like every other file.
    #[default]
    Every,
    /// All of them, their file opened here and not passed on (rank 0 of many).
    Here,
    /// None: another process reads and checks them. The checks that need them, and the time
    /// step taken from their sizes, are that process's; `config.time_step` is the case's
    /// rule before the particles are known, to be replaced by the one process's.
    Elsewhere,
}

/// `[output]`, validated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputSettings {
    /// Interval between outputs, s; `None` = 100 outputs over the run.
    pub interval: Option<f64>,
    /// Write particle snapshots.
    pub snapshots: bool,
    /// Interval between VTK frames, s; `None` = no VTK output.
    pub vtk_interval: Option<f64>,
}

/// Reads and validates a case file; particle files are read relative to its folder.
/// Both are read through [`crate::input`]: regular files only, within its size limits, the
/// particle file streamed.
pub fn load(path: &Path) -> Result<Case, CaseError> {
    let text = input::read_text(path, input::Kind::CaseFile)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let raw = parse_raw(&text, &path.display().to_string())?;
    from_raw_opened(raw, &text, &input::open_beside(&dir))
}

/// [`load`] with `--set` overrides applied to the file's keys before it is validated (see
/// [`SetOverride`]): a key set is validated exactly as if the file said it. The case hash
/// covers the overrides.
pub fn load_with(path: &Path, sets: &[SetOverride]) -> Result<Case, CaseError> {
    load_relayed(path, sets, &input::direct)
}

/// [`load_with`] with the files the case names (particles, meshes, key frames) passed
/// through `relay` (see [`input::Relay`]); the case file itself is read here.
pub fn load_relayed(path: &Path, sets: &[SetOverride], relay: &input::Relay<'_>) -> Result<Case, CaseError> {
    load_scoped(path, sets, relay, Bed::Every)
}

/// [`load_relayed`] with the initial particles read as `bed` says (see [`Bed`]).
pub fn load_scoped(
    path: &Path,
    sets: &[SetOverride],
    relay: &input::Relay<'_>,
    bed: Bed,
) -> Result<Case, CaseError> {
    let text = input::read_text(path, input::Kind::CaseFile)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let (raw, source) = if sets.is_empty() {
        (parse_raw(&text, &path.display().to_string())?, text.clone())
    } else {
        parse_raw_with(&text, &path.display().to_string(), sets)?
    };
    let here = input::open_beside(&dir);
    from_raw_scoped(raw, &source, &input::relayed(&here, relay), &here, bed)
}

/// [`parse`] with `--set` overrides (see [`load_with`]).
pub fn parse_with(
    text: &str,
    origin: &str,
    read_file: &dyn Fn(&str) -> Result<String, CaseError>,
    sets: &[SetOverride],
) -> Result<Case, CaseError> {
    let (raw, source) = parse_raw_with(text, origin, sets)?;
    from_raw(raw, &source, read_file)
}

/// The raw case with the overrides applied, and the text its hash covers: the file's, then
/// each override. The file is read as it is first, so that its own mistakes are reported at
/// their lines; a mistake only the overrides make names them.
fn parse_raw_with(text: &str, origin: &str, sets: &[SetOverride]) -> Result<(RawCase, String), CaseError> {
    use serde::Deserialize;
    parse_raw(text, origin)?;
    let mut table: toml::Table = toml::from_str(input::strip_bom(text))
        .map_err(|e| CaseError::Syntax(did_you_mean(format!("{origin}: {e}"))))?;
    let mut source = text.to_string();
    for set in sets {
        set.apply(&mut table).map_err(CaseError::Syntax)?;
        source.push_str(&format!("\0--set\0{}={}", set.path, set.text));
    }
    let shown: Vec<String> = sets.iter().map(|s| format!("{}={}", s.path, s.text)).collect();
    let raw = RawCase::deserialize(toml::Value::Table(table)).map_err(|e| {
        CaseError::Syntax(did_you_mean(format!(
            "{origin} with --set {}: {}",
            shown.join(" --set "),
            e.to_string().trim_end()
        )))
    })?;
    Ok((raw, source))
}

fn parse_raw(text: &str, origin: &str) -> Result<RawCase, CaseError> {
    toml::from_str(input::strip_bom(text))
        .map_err(|e| CaseError::Syntax(did_you_mean(format!("{origin}: {e}"))))
}

/// Validates case-file text. `origin` names it in messages; `read_file` reads a particle file
/// named in the case.
pub fn parse(
    text: &str,
    origin: &str,
    read_file: &dyn Fn(&str) -> Result<String, CaseError>,
) -> Result<Case, CaseError> {
    let raw = parse_raw(text, origin)?;
    from_raw(raw, text, read_file)
}

/// Validates a case built in memory rather than read from TOML (an MFIX deck translated by
/// [`crate::mfix`]) exactly as [`parse`] validates a case file. `source` is the text the case
/// was made from: the case hash covers it and every file read through `read_file`.
pub fn from_raw(
    raw: RawCase,
    source: &str,
    read_file: &dyn Fn(&str) -> Result<String, CaseError>,
) -> Result<Case, CaseError> {
    from_raw_opened(raw, source, &input::open_text(read_file))
}

/// [`from_raw`] with particle files opened as streams.
pub(crate) fn from_raw_opened(
    raw: RawCase,
    source: &str,
    open: &input::Opener<'_>,
) -> Result<Case, CaseError> {
    from_raw_scoped(raw, source, open, open, Bed::Every)
}

/// [`from_raw_opened`] with the initial particles read as `bed` says, their file (for
/// [`Bed::Here`]) through `open_bed`.
fn from_raw_scoped(
    raw: RawCase,
    source: &str,
    open: &input::Opener<'_>,
    open_bed: &input::Opener<'_>,
    bed: Bed,
) -> Result<Case, CaseError> {
    use sha2::{Digest, Sha256};
    // The hash covers the case text and every file it reads, in the order read: the bytes
    // are hashed as the reader takes them, and a reader that succeeds reads to the end.
    let hasher = std::cell::RefCell::new(Sha256::new());
    hasher.borrow_mut().update(source.as_bytes());
    let hashing = |open: &input::Opener<'_>, name: &str| {
        let reader = open(name)?;
        let mut h = hasher.borrow_mut();
        h.update(b"\0file\0");
        h.update(name.as_bytes());
        h.update(b"\0");
        drop(h);
        Ok(input::Stream::new(std::io::BufReader::new(Hashing { inner: reader, hasher: &hasher }), name))
    };
    let hashing_open = |name: &str| hashing(open, name);
    let hashing_open_bed = |name: &str| hashing(if bed == Bed::Here { open_bed } else { open }, name);
    // Mesh files are read whole, as bytes (a binary STL is not text), and hashed the same way.
    let hashing_read = |name: &str| -> Result<Vec<u8>, CaseError> {
        use std::io::Read;
        let mut bytes = Vec::new();
        open(name)?
            .read_to_end(&mut bytes)
            .map_err(|source| CaseError::Read { path: name.into(), source })?;
        let mut h = hasher.borrow_mut();
        h.update(b"\0file\0");
        h.update(name.as_bytes());
        h.update(b"\0");
        h.update(&bytes);
        Ok(bytes)
    };
    let mut case = validate(raw, &hashing_open, &hashing_read, (&hashing_open_bed, bed))?;
    case.hash = hasher.into_inner().finalize().iter().map(|b| format!("{b:02x}")).collect();
    Ok(case)
}

/// A reader that adds every byte it passes to the case hash.
struct Hashing<'h> {
    inner: Box<dyn std::io::BufRead>,
    hasher: &'h std::cell::RefCell<sha2::Sha256>,
}

impl std::io::Read for Hashing<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        use sha2::Digest;
        let n = self.inner.read(buf)?;
        self.hasher.borrow_mut().update(&buf[..n]);
        Ok(n)
    }
}

/// Default of `[particles] max_initial_overlap`.
pub const DEFAULT_MAX_INITIAL_OVERLAP: f64 = 0.05;

/// Default of `[particles] max_overlap`: half the smaller radius.
pub const DEFAULT_MAX_OVERLAP: f64 = 0.5;

/// `version` at the top level: the format this program reads.
fn version(v: Option<i64>) -> Result<(), CaseError> {
    match v {
        None => {
            return Err(CaseError::missing(
                "top level",
                "version",
                format!("the case-file format version; this program reads version {CASE_VERSION}"),
            ));
        }
        Some(CASE_VERSION) => {}
        Some(v) => {
            return Err(CaseError::invalid(
                "top level",
                "version",
                v,
                format!("this program reads case-file version {CASE_VERSION}"),
            ));
        }
    }
    Ok(())
}

/// Opens a particle file named in the case as a stream.
type OpenStream<'a, 'h> = dyn Fn(&str) -> Result<input::Stream<'h>, CaseError> + 'a;

/// The raw case as a [`Case`]: each table validated in turn, then the checks across tables.
/// `open` streams a particle file, `read_bytes` reads a mesh file; the initial particles are
/// read as `bed` says, their file through `open_bed`.
fn validate<'h>(
    raw: RawCase,
    open: &dyn Fn(&str) -> Result<input::Stream<'h>, CaseError>,
    read_bytes: &dyn Fn(&str) -> Result<Vec<u8>, CaseError>,
    (open_bed, bed): (&OpenStream<'_, 'h>, Bed),
) -> Result<Case, CaseError> {
    let mut warnings = Vec::new();
    version(raw.version)?;
    let domain = require(raw.domain, "top level", "[domain]", "the domain box: min and max corners in m")?;
    let (min, max) = domain::corners(&domain)?;
    let phases = materials::phases(&raw.phases, &raw.wall_materials)?;
    let mut wall_materials = materials::wall_materials(&raw.wall_materials)?;
    let domain::Walls { axes, periodic, walls } =
        domain::walls(&domain, &raw.walls, (min, max), &wall_materials)?;
    let meshes::MeshSet { walls: meshes, names: mesh_names, torque_about: mesh_torque_about } =
        meshes::meshes(
            &raw.meshes,
            raw.time.as_ref(),
            (min, max),
            &wall_materials,
            read_bytes,
            &mut warnings,
        )?;
    let cylinders = cylinders::cylinders(&raw.cylinders, &wall_materials)?;
    let has_walls = !walls.is_empty() || !meshes.is_empty() || !cylinders.is_empty();
    let contact::Tables { law, pair_params, wall_params } =
        contact::contact(raw.contact, &phases, &mut wall_materials, has_walls, &mut warnings)?;
    let time = time::time(raw.time, &law, &phases)?;
    let settings::Settings { gravity, skin, output, rebalance, weigh } =
        settings::settings(&raw.physics, &raw.neighbor, &raw.output, &raw.parallel)?;

    // Insertions and outlets.
    let mesh_set = flow::Meshes { walls: &meshes, names: &mesh_names };
    let read_particles = |file: &str| crate::particles::read_csv_from(&mut open(file)?, &phases);
    let flow_domain = flow::Domain { lo: min, hi: max, periodic: axes };
    let mut insertions =
        flow::insertions(&raw.insertions, &phases, &mesh_set, time.t_start, &flow_domain, &read_particles)?;
    let outlets = flow::outlets(&raw.outlets, &mesh_set, domain.leaving.as_deref(), &flow_domain)?;

    let particles::Bed { particles, resort, max_overlap, max_initial_overlap } = particles::particles(
        raw.particles,
        !insertions.is_empty(),
        &phases,
        (open_bed, bed),
        (min, max),
        axes,
        skin,
        &mut warnings,
    )?;
    let motion = motion::motion(&raw.motion, (bed != Bed::Elsewhere).then_some(&particles))?;
    let (run_overlap, max_overlap) = particles::overlaps(max_overlap, max_initial_overlap)?;
    geometry::check(
        &motion,
        &particles,
        &walls,
        &meshes,
        &mesh_names,
        (min, max),
        max_overlap,
        &raw.insertions,
        &mut insertions,
        periodic.as_ref(),
        skin,
        (time.t_start, time.t_stop),
        &mut warnings,
    )?;
    // The largest radius any particle has or is inserted with.
    let r_max = insertions
        .iter()
        .flat_map(|ins| &ins.mixture.parts)
        .map(|part| 0.5 * part.sizes.max_diameter())
        .fold(particles.max_radius(), f64::max);
    cylinders::check(&particles, &cylinders, max_overlap, periodic.as_ref().map(|p| (p, r_max)))?;
    let time_step = if bed == Bed::Elsewhere {
        time.time_step
    } else {
        time::step(
            &time,
            &law,
            &phases,
            &wall_materials,
            &pair_params,
            &wall_params,
            &particles,
            &insertions,
            &meshes,
            &mesh_names,
            &mut warnings,
        )?
    };
    let (integrator, t_start, t_stop) = (time.integrator, time.t_start, time.t_stop);

    let config = SimulationConfig {
        phases,
        wall_materials,
        walls,
        meshes,
        cylinders,
        law,
        pair_params,
        wall_params,
        integrator,
        time_step,
        t_start,
        t_stop,
        gravity,
        skin,
        motion,
        periodic,
        resort,
        insertions,
        outlets,
    };
    Ok(Case {
        title: raw.title,
        config,
        particles,
        output,
        domain: (min, max),
        hash: String::new(),
        warnings,
        max_overlap: run_overlap,
        mesh_names,
        mesh_torque_about,
        rebalance,
        weigh,
        particles_are_share: false,
    })
}
