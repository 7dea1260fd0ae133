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
