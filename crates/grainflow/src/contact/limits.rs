//! Valid ranges of the contact and material inputs, shared by the engine's own checks and by
//! the case-file layer (which reports them with the key that holds the value).

use crate::error::EngineError;

/// A closed or half-open interval with the sentence that explains it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// Lower bound.
    pub lo: f64,
    /// True if the lower bound itself is excluded.
    pub lo_open: bool,
    /// Upper bound.
    pub hi: f64,
    /// True if the upper bound itself is excluded.
    pub hi_open: bool,
    /// What is valid, for messages.
    pub valid: &'static str,
}

impl Range {
    /// True if `v` is finite and inside the range.
    pub fn contains(&self, v: f64) -> bool {
        v.is_finite()
            && (if self.lo_open { v > self.lo } else { v >= self.lo })
            && (if self.hi_open { v < self.hi } else { v <= self.hi })
    }

    /// `Ok` if `v` is inside, else an [`EngineError::InvalidValue`] naming `who` and `key`.
    pub fn check(&self, who: &str, key: &str, v: f64) -> Result<(), EngineError> {
        if self.contains(v) {
            Ok(())
        } else {
            Err(EngineError::invalid(format!("{who} {key}"), v, self.valid))
        }
    }
}

const fn range(lo: f64, lo_open: bool, hi: f64, hi_open: bool, valid: &'static str) -> Range {
    Range { lo, lo_open, hi, hi_open, valid }
}

/// Normal restitution e_n.
pub const EN: Range = range(0.0, true, 1.0, false, "must lie in (0, 1]");
/// Tangential restitution e_t (Hertz).
pub const ET: Range = range(0.0, true, 1.0, false, "must lie in (0, 1]");
/// KT_FAC / KT_W_FAC.
pub const KT_FAC: Range = range(0.0, false, 1.0, false, "must lie in [0, 1]");
/// DES_ETAT_FAC / DES_ETAT_W_FAC.
pub const ETAT_FAC: Range = range(0.0, false, 1.0, false, "must lie in [0, 1]");
/// Friction coefficient μ.
pub const MU: Range = range(0.0, false, f64::MAX, false, "must be >= 0");
/// Rolling friction length μ_r.
pub const MU_ROLL: Range = range(0.0, false, f64::MAX, false, "must be >= 0 (a length in m)");
/// Linear normal stiffness k_n.
pub const KN: Range = range(0.0, true, f64::MAX, false, "must be positive (N/m)");
/// Poisson's ratio ν.
pub const POISSON: Range = range(-1.0, true, 0.5, true, "must lie in (-1, 0.5)");
/// Young's modulus E.
pub const YOUNGS: Range = range(0.0, true, f64::MAX, false, "must be positive (Pa)");
/// Particle or phase diameter.
pub const DIAMETER: Range = range(0.0, true, f64::MAX, false, "must be a positive length (m)");
/// Density.
pub const DENSITY: Range = range(0.0, true, f64::MAX, false, "must be positive (kg/m³)");
/// Damping per unit mass γ_n, γ_t.
pub const GAMMA: Range = range(0.0, false, f64::MAX, false, "must be >= 0 (1/s)");
/// Surface energy γ of a cohesive contact (JKR).
pub const SURFACE_ENERGY: Range = range(0.0, true, f64::MAX, false, "must be positive (J/m²)");
