//! Particles poured in: the regions they are placed in, the sizes they are drawn from and
//! their placement without overlaps.
//!
//! - [`psd`] — size distributions (uniform, normal, log-normal, a discrete table by number or
//!   by mass) and mixtures of phases, sampled from a seeded stream.
//! - [`region`] — where particles go: a box, a cylinder, the inside of a closed mesh.
//! - [`place`] — centres for a list of diameters inside a region, clear of the particles
//!   already there, the walls, the meshes and the periodic images.
//!
//! The random stream is [`InsertRng`] (ChaCha with 8 rounds): its seed, stream and word
//! position are its whole state, which a checkpoint stores, so a restart draws what the
//! uninterrupted run would have drawn.

pub mod place;
pub mod psd;
pub mod region;

/// The random stream of an insertion.
pub type InsertRng = rand_chacha::ChaCha8Rng;

use crate::math::Vec3;
use crate::state::ParticleInit;
use psd::Mixture;
use region::Region;

/// Particles poured into a region: what, how many, when, how fast.
#[derive(Debug, Clone, PartialEq)]
pub struct Insertion {
    /// The name, for messages and outputs.
    pub name: String,
    /// Where the particles are placed (each wholly inside).
    pub region: Region,
    /// The phases and sizes they are drawn from.
    pub mixture: Mixture,
    /// How much in all; `None`: no limit (a rate insertion goes on to the end of the run).
    pub amount: Option<Amount>,
    /// When.
    pub schedule: Schedule,
    /// Their velocity when placed, m/s (their spin is zero).
    pub velocity: Vec3,
    /// The seed of the insertion's random stream.
    pub seed: u64,
    /// Particles given as they are (read from a file) rather than drawn: inserted all at once
    /// at [`Schedule::Once`]'s time where they are, with their own velocities and spins, ids
    /// following the largest there has been; `region` and `mixture` then describe them
    /// ([`Insertion::of_given`]). Empty for drawn particles.
    pub given: Vec<ParticleInit>,
    /// Given particles that overlap a particle present when they come in by more than this
    /// fraction of the smaller radius are reported in a notice ([`crate::Simulation::flow_notices`]);
    /// one at the centre of a present particle stops the run (its contact has no normal).
    pub max_initial_overlap: f64,
    /// Centres placed at exactly this z, m: a run in the plane z = `plane_z` (MFIX's 2-D
    /// decks), whose spheres must start in it bit for bit to stay in it (the slightest offset
    /// grows when a bed in the plane is compressed). The region then holds the spheres at
    /// that z to within the placement's margin, so the snap changes a centre's distance to
    /// neighbours in the plane only to second order. `None`: anywhere in the region.
    pub plane_z: Option<f64>,
}

/// The default of [`Insertion::max_initial_overlap`] (the case file's
/// `[particles] max_initial_overlap`).
pub const DEFAULT_MAX_INITIAL_OVERLAP: f64 = 0.05;

impl Insertion {
    /// The insertion of the `given` particles, as they are, at time `at`: its region their
    /// bounding box, its mixture one part per phase and density spanning their diameters.
    /// None if `given` is empty.
    pub fn of_given(name: String, at: f64, given: Vec<ParticleInit>) -> Option<Insertion> {
        let first = given.first()?;
        let (mut lo, mut hi) = (first.position, first.position);
        let mut parts: Vec<psd::MixturePart> = Vec::new();
        for p in &given {
            let r = Vec3::splat(p.radius);
            (lo, hi) = (lo.min(p.position - r), hi.max(p.position + r));
            let d = 2.0 * p.radius;
            match parts.iter_mut().find(|q| q.phase == p.phase && q.density == p.density) {
                // One diameter is a constant size (a uniform range needs min < max); two or
                // more span a uniform range.
                Some(q) => match q.sizes {
                    psd::SizeDistribution::Constant { diameter } if diameter != d => {
                        q.sizes =
                            psd::SizeDistribution::Uniform { min: diameter.min(d), max: diameter.max(d) };
                    }
                    psd::SizeDistribution::Uniform { ref mut min, ref mut max } => {
                        (*min, *max) = (min.min(d), max.max(d));
                    }
                    _ => {}
                },
                None => parts.push(psd::MixturePart {
                    phase: p.phase,
                    density: p.density,
                    fraction: 0.0,
                    sizes: psd::SizeDistribution::Constant { diameter: d },
                }),
            }
        }
        let n = given.len() as u64;
        let share = 1.0 / parts.len() as f64;
        for q in &mut parts {
            q.fraction = share;
        }
        Some(Insertion {
            name,
            region: Region::Box { lo, hi },
            mixture: Mixture { parts, basis: psd::Basis::Number },
            amount: Some(Amount::Count(n)),
            schedule: Schedule::Once { at },
            velocity: Vec3::ZERO,
            seed: 0,
            given,
            max_initial_overlap: DEFAULT_MAX_INITIAL_OVERLAP,
            plane_z: None,
        })
    }
}

/// How much an insertion puts in, in all.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Amount {
    /// A number of particles.
    Count(u64),
    /// Particles whose volume is this fraction of the region's volume.
    VolumeFraction(f64),
    /// A mass, kg.
    Mass(f64),
}

/// When an insertion places its particles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Schedule {
    /// All at once, at the first step that starts at or after `at`, s.
    Once {
        /// Time, s.
        at: f64,
    },
    /// At a rate, in batches: one at `start` and then every `every` seconds, batch k bringing
    /// the insertion's total to what the rate gives by `start + (k + 1)·every` (and no more
    /// than [`Insertion::amount`]).
    Rate {
        /// How fast.
        rate: Rate,
        /// The first batch's time, s.
        start: f64,
        /// Time between batches, s.
        every: f64,
    },
}

/// The rate of a rate insertion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rate {
    /// Particles per second.
    Particles(f64),
    /// Kilograms per second.
    Mass(f64),
}

/// Where particles leave the simulation: they are removed and counted.
#[derive(Debug, Clone, PartialEq)]
pub struct Outlet {
    /// The name, for messages and outputs.
    pub name: String,
    /// Which centres have left.
    pub shape: OutletShape,
}

/// Which particles an outlet removes: those whose centre is …
#[derive(Debug, Clone, PartialEq)]
pub enum OutletShape {
    /// … inside the region.
    Region(Region),
    /// … beyond the plane through `point`, on the side its `normal` points to.
    Plane {
        /// A point of the plane, m.
        point: Vec3,
        /// The plane's normal (need not be a unit vector), pointing out of the simulation.
        normal: Vec3,
    },
    /// … outside the box on the axes marked (the domain box, whose non-periodic faces a
    /// particle leaves through).
    OutsideBox {
        /// Lower corner, m.
        lo: Vec3,
        /// Upper corner, m.
        hi: Vec3,
        /// The axes on which leaving the box counts.
        axes: [bool; 3],
    },
}

impl OutletShape {
    /// True if a particle centred at `x` has left through the outlet.
    pub fn has_left(&self, x: Vec3) -> bool {
        match self {
            OutletShape::Region(r) => r.contains(x),
            OutletShape::Plane { point, normal } => (x - *point).dot(*normal) > 0.0,
            OutletShape::OutsideBox { lo, hi, axes } => {
                (0..3).any(|k| axes[k] && !(x[k] >= lo[k] && x[k] <= hi[k]))
            }
        }
    }
}
