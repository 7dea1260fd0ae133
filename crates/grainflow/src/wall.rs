//! Walls: infinite planes and infinite cylinders, each with its own material.

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

/// Which side of a [`Cylinder`]'s surface the particles are on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CylinderSide {
    /// Inside (a drum or a pipe): a particle touches it when |d⊥| + r > R.
    Inside,
    /// Outside (a rod): a particle touches it when |d⊥| − r < R.
    Outside,
}

/// An infinite circular cylinder wall: exact, without facets, of infinite length along its
/// axis. Its surface may turn about the axis at `omega` (a drum's shell): the wall's velocity
/// at a point x of the surface is ω·a × (x − o); the shape does not move.
#[derive(Debug, Clone, PartialEq)]
pub struct Cylinder {
    /// A name for messages and output.
    pub name: String,
    /// A point on the axis, m.
    pub origin: Vec3,
    /// The axis's unit direction.
    pub axis: Vec3,
    /// The radius, m.
    pub radius: f64,
    /// The particles' side.
    pub side: CylinderSide,
    /// Index into the simulation's wall materials.
    pub material: usize,
    /// The surface's angular velocity about `axis` (right-handed), rad/s.
    pub omega: f64,
}

/// Where a sphere's centre is relative to a [`Cylinder`]'s surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CylinderContact {
    /// Distance from the centre to the surface (on the particles' side; negative on the
    /// other side), m.
    pub distance: f64,
    /// Unit normal from the surface towards the centre.
    pub normal: Vec3,
    /// The nearest point of the surface, m.
    pub point: Vec3,
}

impl Cylinder {
    /// A cylinder about the axis through `origin` along `axis` (normalised here).
    pub fn new(
        name: impl Into<String>,
        origin: Vec3,
        axis: Vec3,
        radius: f64,
        side: CylinderSide,
        material: usize,
        omega: f64,
    ) -> Self {
        Cylinder { name: name.into(), origin, axis: axis.normalize(), radius, side, material, omega }
    }

    /// The component of `x − origin` normal to the axis, m.
    #[inline(always)]
    pub fn radial(&self, x: Vec3) -> Vec3 {
        let d = x - self.origin;
        d - self.axis * d.dot(self.axis)
    }

    /// Where the centre `x` is relative to the surface; `None` on the axis itself (no normal).
    #[inline]
    pub fn locate(&self, x: Vec3) -> Option<CylinderContact> {
        let d = self.radial(x);
        let rho = d.length();
        if rho.is_nan() || rho <= 0.0 {
            return None;
        }
        let out = d / rho;
        let (distance, normal) = match self.side {
            CylinderSide::Inside => (self.radius - rho, -out),
            CylinderSide::Outside => (rho - self.radius, out),
        };
        Some(CylinderContact { distance, normal, point: x - normal * distance })
    }

    /// The surface's velocity at the point `x`, m/s.
    #[inline(always)]
    pub fn velocity(&self, x: Vec3) -> Vec3 {
        if self.omega == 0.0 { Vec3::ZERO } else { (self.axis * self.omega).cross(x - self.origin) }
    }
}
