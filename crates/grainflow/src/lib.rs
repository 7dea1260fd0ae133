//! # grainflow — a soft-sphere discrete element method engine
//!
//! The engine reproduces the MFIX-DEM soft-sphere model (linear spring–dashpot and Hertzian
//! contacts, tangential spring with a Coulomb cap, MFIX's time-step rule and its Euler and
//! Adams–Bashforth integrators) and offers better-behaved variants beside it, each selected by
//! name, never silently.
//!
//! ## Units
//! Everything is SI: metres, kilograms, seconds, newtons, pascals, radians. Hertzian stiffnesses
//! are in N/m^1.5, linear ones in N/m, damping coefficients in kg/s (linear) or kg/(s·m^0.25)
//! (Hertzian).
//!
//! ## One time step, module by module
//! 1. [`neighbor`] — broad phase: linked cells with a skin give the candidate pairs and
//!    particle–wall pairs; contact history survives rebuilds and re-sorts. A particle's
//!    identity is its id: a slot is only where it is stored, changed only by insertion,
//!    removal and re-sorting ([`Simulation::insert`], [`Simulation::remove_ids`],
//!    [`Simulation::sort_spatially`]), which carry every history with its particles;
//!    checkpoints name the pairs by ids.
//! 2. [`contact`] — fine phase and contact laws: geometry, normal and tangential forces, Coulomb
//!    cap, torques ([`contact::law`]), coefficients derived from the inputs
//!    ([`contact::coefficients`]).
//! 3. [`wall`] — planes (the six faces of the domain box, or any infinite plane) and infinite
//!    cylinders (drums, pipes, rods; [`SimulationConfig::cylinders`], after the meshes);
//!    [`surface`] shows every wall as polygons for display, as its contact source describes it.
//! 4. [`integrate`] — MFIX's Euler and Adams–Bashforth steps, and velocity Verlet.
//! 5. [`motion`] — prescribed particle motion applied after every step; user hooks run through
//!    [`Simulation::run_with`].
//! 6. [`observe`] — energies, contact counts and overlaps for output.
//!
//! [`Simulation`] ties the stages together; [`timestep`] holds MFIX's time-step rule.
//! [`mesh`] holds the geometry of triangle-mesh walls (STL and OBJ input, topology, sphere–mesh
//! contacts, triangle grids); the force evaluation takes the meshes of
//! [`SimulationConfig::meshes`] after the pairs.

pub mod boundary;
pub mod checkpoint;
pub mod contact;
pub mod domain;
pub mod error;
pub mod forces;
pub mod insertion;
pub mod integrate;
pub mod material;
pub mod math;
pub mod mesh;
pub mod motion;
pub mod neighbor;
pub mod observe;
pub mod simulation;
pub mod state;
pub mod surface;
mod threads;
pub mod timestep;
pub mod wall;

pub use boundary::Periodic;
pub use contact::{
    ContactLaw, ContactParams, HistoryFrame, LeverArm, NormalDamping, NormalModel, TangentialModel,
};
pub use error::EngineError;
pub use integrate::Integrator;
pub use material::{Phase, WallMaterial};
pub use math::Vec3;
pub use motion::{MotionRule, PrescribedMotion};
pub use observe::Diagnostics;
pub use simulation::{
    ContactInfo, ContactPartner, DomainStats, FlowBooks, MemoryUse, MeshLoad, ResortRule, Simulation,
    SimulationConfig, StageTimes, Tally, ThreadReport,
};
pub use state::Particles;
pub use surface::{Surface, SurfaceKind};
pub use timestep::{TimeStepChoice, TimeStepRule};
pub use wall::{Cylinder, CylinderSide, Wall};
