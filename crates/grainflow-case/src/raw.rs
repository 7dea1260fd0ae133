//! The case file as written: serde structures with every key, its unit and its default.
//! `docs/case-file.md` documents the same keys; a test checks that the two agree.

use serde::Deserialize;

/// The whole case file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCase {
    /// Case-file format version. Required; this program reads version 1.
    pub version: Option<i64>,
    /// Free text describing the case.
    #[serde(default)]
    pub title: String,
    /// The domain box and its walls. Required.
    pub domain: Option<RawDomain>,
    /// Body forces.
    #[serde(default)]
    pub physics: RawPhysics,
    /// Solids phases (materials of the particles). At least one.
    #[serde(default)]
    pub phases: Vec<RawPhase>,
    /// Wall materials. If absent, one material named "wall" exists.
    #[serde(default)]
    pub wall_materials: Vec<RawWallMaterial>,
    /// Extra infinite plane walls.
    #[serde(default)]
    pub walls: Vec<RawWall>,
    /// The contact model and its parameters. Required.
    pub contact: Option<RawContact>,
    /// Time stepping. Required.
    pub time: Option<RawTime>,
    /// Neighbour search.
    #[serde(default)]
    pub neighbor: RawNeighbor,
    /// Output.
    #[serde(default)]
    pub output: RawOutput,
    /// The particles. Required.
    pub particles: Option<RawParticles>,
    /// Prescribed particle motion.
    #[serde(default)]
    pub motion: Vec<RawMotion>,
}

/// `[domain]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawDomain {
    /// Lower corner of the box, m. Required.
    pub min: Option<[f64; 3]>,
    /// Upper corner of the box, m. Required.
    pub max: Option<[f64; 3]>,
    /// Whether the six faces of the box are walls (MFIX's default). Default true.
    #[serde(default = "yes")]
    pub walls: bool,
    /// Material of the six box walls. Default: the first wall material.
    pub wall_material: Option<String>,
}

fn yes() -> bool {
    true
}

/// `[physics]`
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawPhysics {
    /// Gravitational acceleration, m/s². Default [0, -9.80665, 0] (MFIX's default).
    pub gravity: Option<[f64; 3]>,
}

/// `[[phases]]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawPhase {
    /// Name, used by particles and contact tables. Required, unique.
    pub name: Option<String>,
    /// Reference diameter, m. Required.
    pub diameter: Option<f64>,
    /// Density, kg/m³. Required.
    pub density: Option<f64>,
    /// Young's modulus, Pa. Required by the Hertz model.
    pub youngs_modulus: Option<f64>,
    /// Poisson's ratio, in (-1, 0.5). Required by the Hertz model.
    pub poisson_ratio: Option<f64>,
}

/// `[[wall_materials]]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawWallMaterial {
    /// Name. Required, unique.
    pub name: Option<String>,
    /// Young's modulus, Pa. Required by the Hertz model.
    pub youngs_modulus: Option<f64>,
    /// Poisson's ratio, in (-1, 0.5). Required by the Hertz model.
    pub poisson_ratio: Option<f64>,
}

/// `[[walls]]`: an infinite plane.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawWall {
    /// Name for messages. Default "wall N".
    pub name: Option<String>,
    /// A point on the plane, m. Required.
    pub point: Option<[f64; 3]>,
    /// Normal pointing from the wall into the particle space (any length > 0). Required.
    pub normal: Option<[f64; 3]>,
    /// Wall material name. Default: the first wall material.
    pub material: Option<String>,
}

/// `[contact]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawContact {
    /// "lsd" (linear spring–dashpot, MFIX's default) or "hertz". Default "lsd".
    pub model: Option<String>,
    /// "mfix" (total displacement, MFIX 21.3) or "incremental_mindlin". Default "mfix".
    pub tangential: Option<String>,
    /// "mfix" (stored displacement kept as is), "project" or "rotate". Default "mfix".
    pub history: Option<String>,
    /// Lever arm of the tangential force: "mfix" (centre to radical plane: R − δ/2 between
    /// equal spheres, R − δ at a wall) or "radius" (R). Default "mfix".
    pub lever_arm: Option<String>,
    /// Normal damping from restitution: "mfix" (MFIX's formula for both laws) or
    /// "exact_restitution" (solved so that a normal impact rebounds with exactly e_n).
    /// Default "mfix".
    pub damping: Option<String>,
    /// Floor the normal force at zero so the dashpot never pulls at the end of a contact.
    /// Default false (MFIX).
    pub clip_attraction: Option<bool>,
    /// Defaults for every phase pair.
    #[serde(default)]
    pub particle: RawContactParams,
    /// Defaults for every phase–wall-material pair.
    #[serde(default)]
    pub wall: RawContactParams,
    /// Values for one phase pair, overriding `[contact.particle]`.
    #[serde(default)]
    pub pairs: Vec<RawContactParams>,
    /// Values for one phase and one wall material, overriding `[contact.wall]`.
    #[serde(default)]
    pub walls: Vec<RawContactParams>,
}

/// Contact parameters; every key optional so that tables can be layered. The same table form
/// serves `[contact.particle]`, `[contact.wall]`, `[[contact.pairs]]` (which also take
/// `phases`) and `[[contact.walls]]` (which also take `phase` and `material`).
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawContactParams {
    /// `[[contact.pairs]]` only: the two phase names (may be equal).
    pub phases: Option<[String; 2]>,
    /// `[[contact.walls]]` only: the phase name.
    pub phase: Option<String>,
    /// `[[contact.walls]]` only: the wall material name. Default: the first wall material.
    pub material: Option<String>,
    /// Normal stiffness, N/m (LSD; required there).
    pub kn: Option<f64>,
    /// Tangential/normal stiffness ratio, in [0, 1] (LSD). Default 2/7.
    pub kt_fac: Option<f64>,
    /// Tangential/normal damping ratio, in [0, 1] (LSD). Default 0.5.
    pub etat_fac: Option<f64>,
    /// Normal restitution, in (0, 1]. Default 1.
    pub en: Option<f64>,
    /// Tangential restitution, in (0, 1] (Hertz; required there).
    pub et: Option<f64>,
    /// Coulomb friction coefficient, >= 0. Default 0.
    pub mu: Option<f64>,
    /// Rolling friction length, m, >= 0. Default 0.
    pub mu_roll: Option<f64>,
}

/// `[time]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawTime {
    /// End time, s. Required.
    pub t_stop: Option<f64>,
    /// Start time, s. Default 0.
    pub t_start: Option<f64>,
    /// Explicit time step, s. Default: MFIX's rule (TCOLL / dtsolid_factor).
    pub dt: Option<f64>,
    /// MFIX's DTSOLID_FACTOR, >= 10. Default 50. Not allowed together with `dt`.
    pub dtsolid_factor: Option<f64>,
    /// "euler" (MFIX's default), "adams_bashforth" or "velocity_verlet". Default "euler".
    pub integrator: Option<String>,
    /// Run even with an explicit `dt` above the contact law's stability limit. Default false.
    pub force_dt: Option<bool>,
}

/// `[neighbor]`
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawNeighbor {
    /// Verlet-list skin, m, >= 0. Default 0.2 × the largest radius.
    pub skin: Option<f64>,
}

/// `[output]`
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawOutput {
    /// Interval between outputs, s (rounded to a whole number of steps). Default: 100
    /// outputs over the run.
    pub interval: Option<f64>,
    /// Write particle snapshots (CSV) at every output. Default true.
    pub snapshots: Option<bool>,
    /// Interval between VTK frames (particles, contacts, walls for ParaView), s, rounded to
    /// whole steps. Default: no VTK output.
    pub vtk_interval: Option<f64>,
}

/// `[particles]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawParticles {
    /// A particle file, relative to the case file's folder.
    pub file: Option<String>,
    /// "mfix" (legacy particle_input.dat) or "csv". Default from the extension: .csv → csv,
    /// anything else → mfix.
    pub format: Option<String>,
    /// Largest initial overlap allowed, as a fraction of the smaller radius (particle pairs)
    /// or of the radius (walls). Default 0.05.
    pub max_initial_overlap: Option<f64>,
    /// Particles listed inline.
    #[serde(default)]
    pub list: Vec<RawParticle>,
}

/// `[[particles.list]]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawParticle {
    /// Stable id, >= 1, unique. Default: its 1-based position among all particles.
    pub id: Option<u32>,
    /// Phase name. Required.
    pub phase: Option<String>,
    /// Centre, m. Required.
    pub position: Option<[f64; 3]>,
    /// Velocity, m/s. Default 0.
    pub velocity: Option<[f64; 3]>,
    /// Angular velocity, rad/s. Default 0.
    pub angular_velocity: Option<[f64; 3]>,
    /// Diameter, m. Default: the phase's diameter.
    pub diameter: Option<f64>,
}

/// `[[motion]]`
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawMotion {
    /// Ids the rule applies to: one id, or `[first, last]` inclusive. Required.
    pub particles: Option<IdSelection>,
    /// "hold" (fixed at the initial position, at rest) or "follow". Required.
    pub rule: Option<String>,
    /// For "follow": the leader's id.
    pub leader: Option<u32>,
    /// For "follow": the leader of particle k is particle k + leader_offset.
    pub leader_offset: Option<i64>,
    /// For "follow": axes on which the position copies the leader's, e.g. ["x", "z"].
    pub axes: Option<Vec<String>>,
}

/// One id or an inclusive range.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum IdSelection {
    /// A single id.
    One(u32),
    /// `[first, last]`, inclusive.
    Range([u32; 2]),
}
