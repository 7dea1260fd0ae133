//! Periodic boundaries: axes along which the domain box repeats.
//!
//! On a periodic axis a particle leaving through one face re-enters through the opposite one
//! (positions are wrapped after every step), and every pair interacts through its nearest
//! image. The box must be at least three neighbour cut-offs long on each periodic axis, so that
//! a particle never meets two images of the same neighbour.

use crate::math::Vec3;

/// The periodic axes of the domain box [lo, hi].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Periodic {
    /// Lower corner of the box, m.
    pub lo: Vec3,
    /// Upper corner of the box, m.
    pub hi: Vec3,
    /// Which of x, y, z are periodic.
    pub axes: [bool; 3],
}

impl Default for Periodic {
    fn default() -> Self {
        Periodic::NONE
    }
}

impl Periodic {
    /// No periodic axis.
    pub const NONE: Periodic = Periodic { lo: Vec3::ZERO, hi: Vec3::ZERO, axes: [false; 3] };

    /// True if at least one axis is periodic.
    pub fn any(&self) -> bool {
        self.axes.iter().any(|&a| a)
    }

    /// Checks that each periodic axis is at least three neighbour cut-offs
    /// (2·`max_radius` + `skin`) long, and that no wall faces a periodic axis.
    pub fn check(
        &self,
        max_radius: f64,
        skin: f64,
        walls: &[crate::wall::Wall],
    ) -> Result<(), crate::EngineError> {
        if !self.any() {
            return Ok(());
        }
        let cut = 2.0 * max_radius + skin;
        let l = self.lengths().to_array();
        for k in 0..3 {
            if self.axes[k] && (l[k] < 3.0 * cut || l[k].is_nan()) {
                return Err(crate::EngineError::InvalidValue {
                    what: format!("periodic length along {}", ["x", "y", "z"][k]),
                    value: format!("{}", l[k]),
                    valid: format!(
                        "a periodic box must be at least 3 neighbour cut-offs (3 × {cut:e} m) long"
                    ),
                });
            }
        }
        for w in walls {
            let nrm = w.normal.to_array();
            if (0..3).any(|k| self.axes[k] && nrm[k].abs() > 1e-12) {
                return Err(crate::EngineError::BadReference(format!(
                    "wall '{}' faces a periodic axis; periodic axes have no walls",
                    w.name
                )));
            }
        }
        Ok(())
    }

    /// Box lengths, m.
    pub fn lengths(&self) -> Vec3 {
        self.hi - self.lo
    }

    /// The nearest image of a separation vector on the periodic axes. Positions are kept
    /// inside the box, so separations lie within (−L, L) and one shift by L suffices.
    #[inline(always)]
    pub fn min_image(&self, d: Vec3) -> Vec3 {
        let mut d = d.to_array();
        let l = self.lengths().to_array();
        for k in 0..3 {
            if self.axes[k] {
                if d[k] > 0.5 * l[k] {
                    d[k] -= l[k];
                } else if d[k] < -0.5 * l[k] {
                    d[k] += l[k];
                }
            }
        }
        Vec3::from_array(d)
    }

    /// A position brought back into [lo, hi) on the periodic axes.
    #[inline(always)]
    pub fn wrap(&self, x: Vec3) -> Vec3 {
        let mut x = x.to_array();
        let (lo, l) = (self.lo.to_array(), self.lengths().to_array());
        for k in 0..3 {
            if self.axes[k] {
                let w = lo[k] + (x[k] - lo[k]).rem_euclid(l[k]);
                // rem_euclid can round up to exactly l for tiny negative offsets.
                x[k] = if w >= lo[k] + l[k] { lo[k] } else { w };
            }
        }
        Vec3::from_array(x)
    }
}
