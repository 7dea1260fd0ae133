//! The case file as written: serde structures with every key, its unit and its default.
//! `docs/case-file.md` documents the same keys; a test checks that the two agree.

use serde::{Deserialize, Serialize};

/// The whole case file.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawCase {
    /// Case-file format version. Required; this program reads version 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub version: Option<i64>,
    /// Free text describing the case.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub title: String,
    /// The domain box and its walls. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub domain: Option<RawDomain>,
    /// Body forces.
    #[serde(default, skip_serializing_if = "crate::mfix::is_empty_table")]
    pub physics: RawPhysics,
    /// Solids phases (materials of the particles). At least one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub phases: Vec<RawPhase>,
    /// Wall materials. If absent, one material named "wall" exists.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub wall_materials: Vec<RawWallMaterial>,
    /// Extra infinite plane walls.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<RawWall>,
    /// Triangle-mesh walls read from STL or OBJ files.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub meshes: Vec<RawMesh>,
    /// Infinite cylinder walls (drums, pipes, rods), exact.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cylinders: Vec<RawCylinder>,
    /// The contact model and its parameters. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<RawContact>,
    /// Time stepping. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time: Option<RawTime>,
    /// Neighbour search.
    #[serde(default, skip_serializing_if = "crate::mfix::is_empty_table")]
    pub neighbor: RawNeighbor,
    /// Output.
    #[serde(default, skip_serializing_if = "crate::mfix::is_empty_table")]
    pub output: RawOutput,
    /// A run spread over MPI ranks.
    #[serde(default, skip_serializing_if = "crate::mfix::is_empty_table")]
    pub parallel: RawParallel,
    /// The particles. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub particles: Option<RawParticles>,
    /// Prescribed particle motion.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub motion: Vec<RawMotion>,
    /// Particles poured in during the run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub insertions: Vec<RawInsertion>,
    /// Where particles leave the run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outlets: Vec<RawOutlet>,
}

/// `[domain]`
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawDomain {
    /// Lower corner of the box, m. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min: Option<[f64; 3]>,
    /// Upper corner of the box, m. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max: Option<[f64; 3]>,
    /// Which faces of the box are walls: `true` (all six, MFIX's default; faces on periodic
    /// axes excepted), `false` (none), or a list of faces such as ["x_min", "z_min"].
    #[serde(default)]
    pub walls: WallSelection,
    /// Periodic axes, e.g. ["x", "y"]. Default none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub periodic: Option<Vec<String>>,
    /// Material of the six box walls. Default: the first wall material.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_material: Option<String>,
    /// A particle leaving the box through a face that is not periodic: "stop" the run
    /// (default) or "remove" it (counted as the outlet "domain").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leaving: Option<String>,
}

/// `[domain] walls`: all faces, none, or the named ones.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum WallSelection {
    /// All six faces (true) or none (false).
    All(bool),
    /// The named faces: "x_min", "x_max", "y_min", "y_max", "z_min", "z_max".
    Faces(Vec<String>),
}

impl Default for WallSelection {
    fn default() -> Self {
        WallSelection::All(true)
    }
}

/// `[physics]`
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawPhysics {
    /// Gravitational acceleration, m/s². Default [0, -9.80665, 0] (MFIX's default).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gravity: Option<[f64; 3]>,
}

/// `[[phases]]`
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawPhase {
    /// Name, used by particles and contact tables. Required, unique.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Reference diameter, m. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub diameter: Option<f64>,
    /// Density, kg/m³. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub density: Option<f64>,
    /// Young's modulus, Pa. Required by the Hertz model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f64>,
    /// Poisson's ratio, in (-1, 0.5). Required by the Hertz model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub poisson_ratio: Option<f64>,
}

/// `[[wall_materials]]`
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawWallMaterial {
    /// Name. Required, unique.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Young's modulus, Pa. Required by the Hertz model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f64>,
    /// Poisson's ratio, in (-1, 0.5). Required by the Hertz model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub poisson_ratio: Option<f64>,
}

/// `[[walls]]`: an infinite plane.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawWall {
    /// Name for messages. Default "wall N".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A point on the plane, m. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point: Option<[f64; 3]>,
    /// Normal pointing from the wall into the particle space (any length > 0). Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 3]>,
    /// Wall material name. Default: the first wall material.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
}

/// `[[meshes]]`: a triangle-mesh wall, immovable, read from an STL (ASCII or binary) or OBJ
/// file. Its coordinates become the case's by p′ = R·(s·p) + t: `scale` first, then `rotate`
/// (about x, then y, then z), then `translate`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawMesh {
    /// Name for messages. Required, unique among the meshes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The mesh file (`.stl` or `.obj`), relative to the case file's folder. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// Wall material name. Default: the first wall material.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Metres per file unit (1e-3 for a file in millimetres), > 0. Default 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// Rotations about the x, y and z axes, degrees, applied in that order after `scale`.
    /// Default [0, 0, 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rotate: Option<[f64; 3]>,
    /// Translation, m, applied last. Default [0, 0, 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f64; 3]>,
    /// Reverse every triangle's winding, turning its normal round (a file whose normals point
    /// away from the particles). Default false.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flip_normals: Option<bool>,
    /// Leave out triangles of zero area instead of refusing the file. Default false.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skip_degenerate: Option<bool>,
    /// How the mesh moves. Default: it does not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion: Option<RawMeshMotion>,
    /// A velocity of the surface in its own plane, the mesh not moving (a belt, a drum's shell
    /// turning in place). Default: none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface: Option<RawMeshSurface>,
    /// The point the time series' torque on the mesh is taken about, m. Default: the axis's
    /// `origin` of a rotating mesh (or turning surface), else [0, 0, 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub torque_about: Option<[f64; 3]>,
}

/// `[[cylinders]]`: an infinite circular cylinder wall, exact (no facets), its surface at
/// rest or turning about its axis (a drum's shell).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawCylinder {
    /// Name for messages and the time series. Required, unique among the cylinders.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A point on the axis, m. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 3]>,
    /// The axis's direction (normalised; not zero). Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    /// The radius, m, > 0. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// Where the particles are: "inside" (a drum or pipe) or "outside" (a rod). Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub side: Option<String>,
    /// Wall material name. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// The surface's angular velocity about `axis` (right-handed), rad/s. Default 0; not
    /// with `rpm`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub omega: Option<f64>,
    /// The same in revolutions per minute. Not with `omega`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rpm: Option<f64>,
}

/// `[meshes.motion]`: how a mesh moves, timed from the run's start time.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawMeshMotion {
    /// "translate", "rotate" or "oscillate". Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
    /// translate: the velocity, m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity: Option<[f64; 3]>,
    /// rotate: the axis direction (right-hand rule; normalised).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    /// rotate: a point on the axis, m. Default [0, 0, 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 3]>,
    /// rotate: angular velocity, rad/s (or `rpm`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub omega: Option<f64>,
    /// rotate: revolutions per minute (or `omega`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rpm: Option<f64>,
    /// rotate: time over which the angular velocity rises linearly from rest, s. Default 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ramp: Option<f64>,
    /// oscillate: the displacement's amplitude, m (its direction is the oscillation's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<[f64; 3]>,
    /// oscillate: frequency, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency: Option<f64>,
    /// Any kind: the time the motion starts, s (the mesh is as loaded before it; the motion's
    /// clock starts there). Default: the run's start time.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start: Option<f64>,
    /// Any kind: the time the motion stops, s (the mesh stays where it got to). Default: never.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stop: Option<f64>,
}

/// `[meshes.surface]`: a surface velocity, either `velocity` or a turning (`axis`, `origin`,
/// `omega` or `rpm`).
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawMeshSurface {
    /// The surface's velocity, m/s (its normal component at a contact is removed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity: Option<[f64; 3]>,
    /// The axis the surface turns about.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    /// A point on that axis, m. Default [0, 0, 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 3]>,
    /// Angular velocity, rad/s (or `rpm`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub omega: Option<f64>,
    /// Revolutions per minute (or `omega`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rpm: Option<f64>,
    /// A key-frame file in MFIX's format (relative to the case file): the velocity (or the
    /// angular velocity) is multiplied by its value at the time.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub keyframes: Option<String>,
    /// Which of the key-frame file's variables is the factor, from 1. Default 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub keyframe_column: Option<i64>,
}

/// `[contact]`
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawContact {
    /// "lsd" (linear spring–dashpot, MFIX's default), "hertz" or "jkr" (JKR cohesion, as
    /// LAMMPS's `pair granular … jkr`; with `damping = "tsuji"`). Default "lsd".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// "mfix" (total displacement, MFIX 21.3) or "incremental_mindlin". Default "mfix".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tangential: Option<String>,
    /// "mfix" (stored displacement kept as is), "project" or "rotate". Default "mfix".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub history: Option<String>,
    /// Lever arm of the tangential force: "mfix" (centre to radical plane: R − δ/2 between
    /// equal spheres, R − δ at a wall), "radius" (R) or "lammps_granular" (LAMMPS `pair
    /// granular`'s: velocity with R, torque with R − δ/2 between particles and R at walls).
    /// Default "mfix".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lever_arm: Option<String>,
    /// Normal damping: "mfix" (MFIX's formula from e_n for both laws), "exact_restitution"
    /// (solved so that a normal impact rebounds with exactly e_n), "mass_velocity" (LAMMPS's:
    /// γ·m_eff with `gamma_n`, `gamma_t`) or "tsuji" (LAMMPS's: α(e_n)·√(m_eff K_n)).
    /// Default "mfix".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<String>,
    /// Floor the normal force at zero so the dashpot never pulls at the end of a contact.
    /// Default false (MFIX).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clip_attraction: Option<bool>,
    /// Tangential force beyond the Coulomb limit: "mfix" (along the spring, spring reset to
    /// the cone) or "lammps" (spring plus dashpot scaled to the limit). Default "mfix".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coulomb: Option<String>,
    /// Whose radii and masses a contact's stiffness and damping take: "own" (each contact's
    /// particles', as LAMMPS; the time step from the smallest particle) or "phase" (the phases'
    /// reference diameters and densities, as MFIX). Default "own"; MFIX decks use "phase".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sizes: Option<String>,
    /// Defaults for every phase pair.
    #[serde(default, skip_serializing_if = "crate::mfix::is_empty_table")]
    pub particle: RawContactParams,
    /// Defaults for every phase–wall-material pair.
    #[serde(default, skip_serializing_if = "crate::mfix::is_empty_table")]
    pub wall: RawContactParams,
    /// Values for one phase pair, overriding `[contact.particle]`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pairs: Vec<RawContactParams>,
    /// Values for one phase and one wall material, overriding `[contact.wall]`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<RawContactParams>,
}

/// Contact parameters; every key optional so that tables can be layered. The same table form
/// serves `[contact.particle]`, `[contact.wall]`, `[[contact.pairs]]` (which also take
/// `phases`) and `[[contact.walls]]` (which also take `phase` and `material`).
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawContactParams {
    /// `[[contact.pairs]]` only: the two phase names (may be equal).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub phases: Option<[String; 2]>,
    /// `[[contact.walls]]` only: the phase name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub phase: Option<String>,
    /// `[[contact.walls]]` only: the wall material name. Default: the first wall material.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Normal stiffness, N/m (LSD; required there).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kn: Option<f64>,
    /// Tangential/normal stiffness ratio, in [0, 1] (LSD). Default 2/7.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kt_fac: Option<f64>,
    /// Tangential/normal damping ratio, in [0, 1] (LSD). Default 0.5.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub etat_fac: Option<f64>,
    /// Normal restitution, in (0, 1]. Default 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub en: Option<f64>,
    /// Tangential restitution, in (0, 1] (Hertz; required there).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub et: Option<f64>,
    /// Coulomb friction coefficient, >= 0. Default 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// Rolling friction length, m, >= 0. Default 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu_roll: Option<f64>,
    /// Normal damping per unit effective mass γ_n, 1/s (`damping = "mass_velocity"`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gamma_n: Option<f64>,
    /// Tangential damping per unit effective mass γ_t, 1/s (`damping = "mass_velocity"`;
    /// default γ_n/2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gamma_t: Option<f64>,
    /// Hertz: K_n in N/m^1.5, given directly instead of (4/3)E*√R* from E and ν.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hertz_kn: Option<f64>,
    /// Hertz: K_t in N/m^1.5, given directly instead of 8G*√R*.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hertz_kt: Option<f64>,
    /// JKR: surface energy γ, J/m², > 0 (LAMMPS's; the work of adhesion is 2γ and the
    /// pull-off force 3πγR*). Required there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface_energy: Option<f64>,
}

/// `[time]`
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawTime {
    /// End time, s. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t_stop: Option<f64>,
    /// Start time, s. Default 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t_start: Option<f64>,
    /// Explicit time step, s. Default: MFIX's rule (TCOLL / dtsolid_factor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// MFIX's DTSOLID_FACTOR, >= 10. Default 50. Not allowed together with `dt`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dtsolid_factor: Option<f64>,
    /// "euler" (MFIX's default), "adams_bashforth" or "velocity_verlet". Default "euler".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub integrator: Option<String>,
    /// Run even with an explicit `dt` above the contact law's stability limit. Default false.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force_dt: Option<bool>,
}

/// `[neighbor]`
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawNeighbor {
    /// Verlet-list skin, m, >= 0. Default 0.2 × the largest radius.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skin: Option<f64>,
}

/// `[parallel]`
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawParallel {
    /// Cut the ranks' boxes again when the slowest rank's work exceeds the mean by more
    /// than `threshold`. Default true.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rebalance: Option<bool>,
    /// That excess, as a fraction of the mean, >= 0. Default 0.1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub threshold: Option<f64>,
    /// What is weighed: "time" (each rank's measured busy time; default) or "work" (the
    /// particles and their list partners, counted).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weigh: Option<String>,
}

/// `[output]`
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawOutput {
    /// Interval between outputs, s (rounded to a whole number of steps). Default: 100
    /// outputs over the run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interval: Option<f64>,
    /// Write particle snapshots (CSV) at every output. Default true.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub snapshots: Option<bool>,
    /// Interval between VTK frames (particles, contacts, walls for ParaView), s, rounded to
    /// whole steps. Default: no VTK output.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vtk_interval: Option<f64>,
}

/// `[particles]`
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawParticles {
    /// A particle file, relative to the case file's folder.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// "mfix" (legacy particle_input.dat) or "csv". Default from the extension: .csv → csv,
    /// anything else → mfix.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub format: Option<String>,
    /// Largest initial overlap allowed, as a fraction of the smaller radius (particle pairs)
    /// or of the radius (walls). Default 0.05.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_initial_overlap: Option<f64>,
    /// Largest overlap allowed during the run, as a fraction of the smaller radius: the run's
    /// health check stops a run whose largest overlap exceeds it. Default 0.5; must lie in
    /// (0, 1] and be at least `max_initial_overlap`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_overlap: Option<f64>,
    /// Slot order of the particles in memory: "input" (as listed) or "spatial" (sorted into
    /// bins of half the neighbour cut-off, x fastest, then y, then z, so that neighbours sit
    /// close in memory — faster for large beds). Default "input". Results do not depend on it
    /// beyond rounding of sums.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<String>,
    /// Re-sorting during the run along a space-filling curve, so that a flowing bed keeps the
    /// memory order of a fresh one: "auto" (when the order has decayed: the neighbour pairs lie
    /// twice as far apart in memory as after the last sort), "never", or every N steps.
    /// Default "auto". Results do not depend on it (bit for bit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resort: Option<RawResort>,
    /// Particles listed inline.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub list: Vec<RawParticle>,
}

/// `[particles] resort`: a word or a step count.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum RawResort {
    /// "auto" or "never".
    Word(String),
    /// Every so many steps.
    Steps(i64),
}

/// `[[particles.list]]`
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawParticle {
    /// Stable id, >= 1, unique. Default: its 1-based position among all particles.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub id: Option<u32>,
    /// Phase name. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub phase: Option<String>,
    /// Centre, m. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<[f64; 3]>,
    /// Velocity, m/s. Default 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity: Option<[f64; 3]>,
    /// Angular velocity, rad/s. Default 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angular_velocity: Option<[f64; 3]>,
    /// Diameter, m. Default: the phase's diameter.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub diameter: Option<f64>,
}

/// `[[motion]]`
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawMotion {
    /// Ids the rule applies to: one id, or `[first, last]` inclusive. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub particles: Option<IdSelection>,
    /// "hold" (fixed at the initial position, at rest) or "follow". Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rule: Option<String>,
    /// For "follow": the leader's id.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leader: Option<u32>,
    /// For "follow": the leader of particle k is particle k + leader_offset.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leader_offset: Option<i64>,
    /// For "follow": axes on which the position copies the leader's, e.g. ["x", "z"].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axes: Option<Vec<String>>,
}

/// One id or an inclusive range.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum IdSelection {
    /// A single id.
    One(u32),
    /// `[first, last]`, inclusive.
    Range([u32; 2]),
}

/// `[[insertions]]`: particles poured into a region, all at once (`at`) or at a rate
/// (`rate` or `mass_rate`, in batches every `every` seconds from `start`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawInsertion {
    /// Name for messages and outputs. Required, unique among the insertions.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Where the particles are placed. Required, unless they come from `file`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub region: Option<RawRegion>,
    /// A particle file (CSV: id,phase,x,y,z,diameter,u,v,w) whose particles come in as they
    /// are, all at once at `at`, instead of drawn ones.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// How many particles in all (or `volume_fraction` or `mass`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub count: Option<u64>,
    /// The particles' volume in all, as a fraction of the region's volume.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub volume_fraction: Option<f64>,
    /// The particles' mass in all, kg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// All at once at this time, s. Default: the start time (when there is no rate).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at: Option<f64>,
    /// Particles per second.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate: Option<f64>,
    /// Kilograms per second.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass_rate: Option<f64>,
    /// A rate's first batch, s. Default: the start time.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start: Option<f64>,
    /// Time between a rate's batches, s. Default 0.01.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub every: Option<f64>,
    /// The particles' velocity when placed, m/s. Default [0, 0, 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity: Option<[f64; 3]>,
    /// Seed of the insertion's random stream. Default: its position among the insertions.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Every centre placed at exactly this z, m (a run in that plane). Default: none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plane_z: Option<f64>,
    /// How the phases' `fraction`s are meant: "number" (default) or "mass".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fractions_by: Option<String>,
    /// The phases poured, with their size distributions. At least one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub phases: Vec<RawInsertPhase>,
}

/// `[[insertions.phases]]`: one phase of an insertion and its size distribution.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawInsertPhase {
    /// The phase's name. Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub phase: Option<String>,
    /// Its share of the insertion (by `fractions_by`). Default 1 when it is the only phase.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fraction: Option<f64>,
    /// "constant" (default), "uniform", "normal", "lognormal", "table" or "cdf".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub distribution: Option<String>,
    /// constant: the diameter, m. Default: the phase's diameter.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub diameter: Option<f64>,
    /// normal, lognormal: the mean diameter, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mean: Option<f64>,
    /// normal, lognormal: the standard deviation of the diameter, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f64>,
    /// uniform, normal, lognormal: the smallest diameter, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_diameter: Option<f64>,
    /// uniform, normal, lognormal: the largest diameter, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_diameter: Option<f64>,
    /// table, cdf: the diameters, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub diameters: Option<Vec<f64>>,
    /// table: each diameter's share (by `weights_by`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weights: Option<Vec<f64>>,
    /// table: "number" (default) or "mass".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weights_by: Option<String>,
    /// cdf: P(D ≤ d) at each of `diameters`, by number, linear between them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cdf: Option<Vec<f64>>,
}

/// `[insertions.region]`, `[outlets.region]`: a box, a cylinder, or the inside of a closed
/// mesh.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawRegion {
    /// "box", "cylinder", "mesh" or "face" (a stream through a disc). Required.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
    /// box: the lower corner, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min: Option<[f64; 3]>,
    /// box: the upper corner, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max: Option<[f64; 3]>,
    /// cylinder: the centre of one end; face: the disc's centre, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub base: Option<[f64; 3]>,
    /// cylinder: the direction from `base` to the other end.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    /// cylinder: the distance between its ends, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length: Option<f64>,
    /// cylinder, face: the radius, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// mesh: the name of a closed `[[meshes]]` entry whose inside is the region.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
}

/// `[[outlets]]`: particles whose centres enter the region, or cross the plane, are removed
/// and counted.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RawOutlet {
    /// Name for messages and outputs. Required, unique among the outlets.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The region (or `point` and `normal`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub region: Option<RawRegion>,
    /// A point of the plane, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point: Option<[f64; 3]>,
    /// The plane's normal, pointing out of the simulation: centres beyond the plane on this
    /// side are removed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 3]>,
}
