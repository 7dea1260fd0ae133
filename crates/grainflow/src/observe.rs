//! Quantities users watch: energies, contacts, overlaps.

/// A snapshot of global quantities after a step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Diagnostics {
    /// Simulated time, s.
    pub time: f64,
    /// Steps taken.
    pub step: u64,
    /// Translational kinetic energy Σ½mv², J.
    pub kinetic_translational: f64,
    /// Rotational kinetic energy Σ½Iω², J.
    pub kinetic_rotational: f64,
    /// Gravitational potential energy −Σm·g·x (zero at the origin), J.
    pub potential: f64,
    /// Elastic energy in the normal springs of the current contacts, J.
    pub elastic: f64,
    /// Number of particle–particle and particle–wall contacts of the current state.
    pub contacts: usize,
    /// Largest overlap divided by the smaller radius of the contact, of the current state.
    pub max_overlap_ratio: f64,
}

impl Diagnostics {
    /// Kinetic + potential + elastic energy, J.
    pub fn total_energy(&self) -> f64 {
        self.kinetic_translational + self.kinetic_rotational + self.potential + self.elastic
    }
}
