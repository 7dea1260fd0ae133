//! Phases (particle materials) and wall materials.

use crate::contact::limits;
use crate::error::EngineError;
use crate::math::sphere_mass;

/// A solids phase: MFIX's `D_P0`, `RO_S0` and, for the Hertzian model, `E_YOUNG`, `V_POISSON`.
///
/// The reference diameter and density define the phase's reference mass, which sets the
/// effective masses used for damping and for the time step (as in MFIX), whatever the sizes
/// of the individual particles.
#[derive(Debug, Clone, PartialEq)]
pub struct Phase {
    /// Name used in case files and messages.
    pub name: String,
    /// Reference diameter, m.
    pub diameter: f64,
    /// Material density, kg/m³.
    pub density: f64,
    /// Young's modulus E, Pa (Hertzian model only).
    pub youngs_modulus: Option<f64>,
    /// Poisson's ratio ν, dimensionless, in (−1, 0.5) (Hertzian model only).
    pub poisson_ratio: Option<f64>,
}

impl Phase {
    /// Reference mass (4/3)·π·(d/2)³·ρ, kg.
    pub fn mass(&self) -> f64 {
        sphere_mass(0.5 * self.diameter, self.density)
    }

    /// Reference radius, m.
    pub fn radius(&self) -> f64 {
        0.5 * self.diameter
    }

    pub(crate) fn validate(&self) -> Result<(), EngineError> {
        let who = format!("phase '{}'", self.name);
        limits::DIAMETER.check(&who, "diameter", self.diameter)?;
        limits::DENSITY.check(&who, "density", self.density)?;
        let m = self.mass();
        if !(m.is_finite() && m >= f64::MIN_POSITIVE) {
            return Err(EngineError::BadReference(format!(
                "{who}: diameter {:e} m and density {:e} kg/m³ give a particle mass of {m:e} kg, beyond what double precision can hold; are they in SI units (m, kg/m³)?",
                self.diameter, self.density
            )));
        }
        validate_elastic(&who, self.youngs_modulus, self.poisson_ratio)
    }
}

/// A wall material: MFIX's `EW_YOUNG` and `VW_POISSON`.
#[derive(Debug, Clone, PartialEq)]
pub struct WallMaterial {
    /// Name used in case files and messages.
    pub name: String,
    /// Young's modulus E, Pa (Hertzian model only).
    pub youngs_modulus: Option<f64>,
    /// Poisson's ratio ν in (−1, 0.5) (Hertzian model only).
    pub poisson_ratio: Option<f64>,
}

impl WallMaterial {
    pub(crate) fn validate(&self) -> Result<(), EngineError> {
        validate_elastic(&format!("wall material '{}'", self.name), self.youngs_modulus, self.poisson_ratio)
    }
}

fn validate_elastic(who: &str, e: Option<f64>, nu: Option<f64>) -> Result<(), EngineError> {
    if let Some(e) = e {
        limits::YOUNGS.check(who, "youngs_modulus", e)?;
    }
    if let Some(nu) = nu {
        limits::POISSON.check(who, "poisson_ratio", nu)?;
    }
    Ok(())
}
