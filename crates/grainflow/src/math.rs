//! The one place vector types come from: double-precision glam vectors.
//! (No fast-math anywhere: DEM results must be reproducible to the last bit.)

pub use glam::DVec3 as Vec3;

/// Mass of a solid sphere of radius `r` (m) and density `rho` (kg/m³), in kg.
#[inline]
pub fn sphere_mass(r: f64, rho: f64) -> f64 {
    4.0 / 3.0 * std::f64::consts::PI * r * r * r * rho
}

/// Moment of inertia of a solid sphere, I = (2/5)·m·r², in kg·m².
#[inline]
pub fn sphere_inertia(m: f64, r: f64) -> f64 {
    0.4 * m * r * r
}

/// Component `axis` (0 = x, 1 = y, 2 = z) of a vector.
#[inline]
pub fn component(v: Vec3, axis: usize) -> f64 {
    v.to_array()[axis]
}

/// `a` if `c`, else `b`, component by component: a select rather than a branch, so that loops
/// over contacts stay vectorisable.
#[inline(always)]
pub fn pick(c: bool, a: Vec3, b: Vec3) -> Vec3 {
    Vec3::select(glam::BVec3::splat(c), a, b)
}
