//! Contact geometry (reference: MFIX-DEM model §1–2).

use crate::math::Vec3;

/// Geometry of a contact, seen from particle i.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactGeometry {
    /// Unit normal from i's centre towards j's centre (or towards the wall).
    pub normal: Vec3,
    /// Overlap δ, m (≥ 0 in contact).
    pub overlap: f64,
    /// Distance from i's centre to the contact point (radical plane), m.
    pub lever_i: f64,
    /// Distance from j's centre to the contact point, m (0 for a wall).
    pub lever_j: f64,
}

/// Pair geometry if particles i and j touch, with MFIX's test d² ≤ (R_i + R_j − 1e-15)².
///
/// The contact point lies on the radical plane: a_i = (d² + R_i² − R_j²)/(2d), a_j = d − a_i
/// (for equal radii a_i = a_j = R − δ/2, not R), formed as d/2 ± (R_i − R_j)(R_i + R_j)/(2d)
/// so that the pair seen from j gives a_j and a_i to the bit.
#[inline(always)]
pub fn pair_contact(xi: Vec3, xj: Vec3, ri: f64, rj: f64) -> Option<ContactGeometry> {
    pair_contact_separation(xj - xi, ri, rj)
}

/// As [`pair_contact`], from the separation `dvec` = x_j − x_i (already the nearest image on
/// periodic axes).
#[inline(always)]
pub fn pair_contact_separation(dvec: Vec3, ri: f64, rj: f64) -> Option<ContactGeometry> {
    let d2 = dvec.length_squared();
    pair_touching(d2, ri, rj).then(|| pair_geometry(dvec, ri, rj))
}

/// MFIX's contact test for centres `d2` = |x_j − x_i|² apart: 0 < d² ≤ (R_i + R_j − 1e-15)².
#[inline(always)]
pub fn pair_touching(d2: f64, ri: f64, rj: f64) -> bool {
    let lim = ri + rj - 1e-15;
    // `&`, not `&&`: both tests are cheap, and a loop over pairs stays free of branches.
    // (A NaN distance counts as touching, as it always has: the health check reports it.)
    let apart = d2 > lim * lim;
    !apart & (d2 != 0.0)
}

/// The geometry of a pair that [`pair_touching`] found in contact, from their separation
/// `dvec` = x_j − x_i. Branch-free.
#[inline(always)]
pub fn pair_geometry(dvec: Vec3, ri: f64, rj: f64) -> ContactGeometry {
    let d = dvec.length_squared().sqrt();
    // Odd in (i, j): swapping the particles negates `t` exactly.
    let t = (ri - rj) * (ri + rj) / (2.0 * d);
    let half = 0.5 * d;
    ContactGeometry { normal: dvec / d, overlap: ri + rj - d, lever_i: half + t, lever_j: half - t }
}

/// [`pair_geometry`] with the lever arms left at zero (for a law that takes them from the
/// radii): the normal and overlap to the bit, one division fewer.
#[inline(always)]
pub fn pair_geometry_without_levers(dvec: Vec3, ri: f64, rj: f64) -> ContactGeometry {
    let d = dvec.length_squared().sqrt();
    ContactGeometry { normal: dvec / d, overlap: ri + rj - d, lever_i: 0.0, lever_j: 0.0 }
}

/// Geometry against a plane through `point` whose unit normal `wall_normal` points into the
/// space the particles occupy. In contact when δ = R − d ≥ 0, d the signed centre-to-plane
/// distance; the lever arm is d (not R).
#[inline(always)]
pub fn wall_contact(x: Vec3, r: f64, point: Vec3, wall_normal: Vec3) -> Option<ContactGeometry> {
    let d = (x - point).dot(wall_normal);
    let overlap = r - d;
    if overlap < 0.0 {
        return None;
    }
    Some(ContactGeometry { normal: -wall_normal, overlap, lever_i: d, lever_j: 0.0 })
}

/// Relative velocity at the contact point: v_r = v_i − v_j + (a_i·ω_i + a_j·ω_j) × n.
#[inline(always)]
pub fn relative_velocity(g: &ContactGeometry, vi: Vec3, vj: Vec3, wi: Vec3, wj: Vec3) -> Vec3 {
    relative_velocity_of_centres(g, vi - vj, wi, wj)
}

/// [`relative_velocity`] from the centres' relative velocity `dv` = v_i − v_j (the same bits:
/// the difference is the first operation either way).
#[inline(always)]
pub fn relative_velocity_of_centres(g: &ContactGeometry, dv: Vec3, wi: Vec3, wj: Vec3) -> Vec3 {
    dv + (g.lever_i * wi + g.lever_j * wj).cross(g.normal)
}
