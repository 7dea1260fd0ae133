//! Walls: infinite planes, each with its own material.

use crate::math::Vec3;

/// An infinite, immovable plane wall. Its unit `normal` points from the wall into the space
/// the particles occupy; a particle touches it when its centre is closer than its radius.
#[derive(Debug, Clone, PartialEq)]
pub struct Wall {
    /// A point on the plane, m.
    pub point: Vec3,
    /// Unit normal pointing into the particle space.
    pub normal: Vec3,
    /// Index into the simulation's wall materials.
    pub material: usize,
    /// A name for messages and output (e.g. "y_min").
    pub name: String,
}

impl Wall {
    /// A plane through `point` with normal `normal` (normalised here).
    pub fn plane(name: impl Into<String>, point: Vec3, normal: Vec3, material: usize) -> Self {
        Wall { point, normal: normal.normalize(), material, name: name.into() }
    }

    /// The six faces of the axis-aligned box [min, max] (MFIX's default walls), facing inwards,
    /// in the order x_min, x_max, y_min, y_max, z_min, z_max.
    pub fn domain_box(min: Vec3, max: Vec3, material: usize) -> Vec<Wall> {
        vec![
            Wall::plane("x_min", min, Vec3::X, material),
            Wall::plane("x_max", max, -Vec3::X, material),
            Wall::plane("y_min", min, Vec3::Y, material),
            Wall::plane("y_max", max, -Vec3::Y, material),
            Wall::plane("z_min", min, Vec3::Z, material),
            Wall::plane("z_max", max, -Vec3::Z, material),
        ]
    }

    /// Signed distance of a point from the plane (positive on the particle side), m.
    #[inline(always)]
    pub fn distance(&self, x: Vec3) -> f64 {
        (x - self.point).dot(self.normal)
    }
}
