//! The walls' surfaces for display: each contact source with a surface (plane walls, meshes,
//! cylinders; the particle pairs have none) describes it as polygons with per-polygon data
//! ([`Surface`]), and [`Simulation::surfaces`] collects them in the sources' order. A writer
//! (the VTK series of `grainflow-run`) needs to know no kind of wall: it writes a fixed surface
//! once, as `<stem>.vtp`, and a moving one in every frame, as `<stem>_<step>.vtp` listed in
//! `<stem>.pvd`.
//!
//! The surfaces are for the eye only: the contacts are computed on the walls themselves (an
//! infinite plane, an exact cylinder), not on these polygons.

use crate::Simulation;
use crate::math::Vec3;
use crate::wall::Wall;

/// Facets round a cylinder's tube in its surface (display only: the contact is exact).
pub const TUBE_FACETS: usize = 64;

/// A kind of surface a contact source shows: the stem of its files and whether it moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SurfaceKind {
    /// The stem of its files (`walls`, `meshes_fixed`, `meshes`, `cylinders`).
    pub stem: &'static str,
    /// Whether it moves: shown anew at every frame (else once).
    pub moves: bool,
}

/// The values of one cell-data array: one value per polygon.
#[derive(Debug, Clone, PartialEq)]
pub enum CellValues {
    /// Integers (indices, materials).
    Int(Vec<i32>),
    /// Real scalars.
    Real(Vec<f64>),
    /// Vectors (normals).
    Vector(Vec<Vec3>),
}

/// A named cell-data array.
#[derive(Debug, Clone, PartialEq)]
pub struct CellData {
    /// Its name (shown in ParaView).
    pub name: &'static str,
    /// Its values, polygon after polygon.
    pub values: CellValues,
}

/// A surface where it is now, as polygons: points, each polygon's corners (indices into the
/// points), and data per polygon.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// What surface it is.
    pub kind: SurfaceKind,
    /// The points, m.
    pub points: Vec<Vec3>,
    /// The polygons' corners, polygon after polygon, as indices into `points`.
    pub corners: Vec<usize>,
    /// Where each polygon ends in `corners` (the first starts at 0).
    pub ends: Vec<usize>,
    /// Data per polygon, array after array.
    pub cell_data: Vec<CellData>,
}

impl Surface {
    /// A surface of `kind` without polygons yet.
    pub fn new(kind: SurfaceKind) -> Self {
        Surface { kind, points: Vec::new(), corners: Vec::new(), ends: Vec::new(), cell_data: Vec::new() }
    }

    /// Adds a polygon with these corners (indices into `points`).
    pub fn push_polygon(&mut self, corners: impl IntoIterator<Item = usize>) {
        self.corners.extend(corners);
        self.ends.push(self.corners.len());
    }

    /// Its number of polygons.
    pub fn polygons(&self) -> usize {
        self.ends.len()
    }
}

/// Which surfaces [`Simulation::surfaces`] gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Which {
    /// Every surface.
    All,
    /// Only those that move (for a frame).
    Moving,
}

impl Which {
    /// True if a surface of `kind` is wanted.
    pub fn wants(self, kind: SurfaceKind) -> bool {
        self == Which::All || kind.moves
    }
}

impl Simulation {
    /// The surfaces of the walls where they are now, in the contact sources' order (plane
    /// walls, meshes, cylinders); the infinite walls are shown within the box [lo, hi].
    pub fn surfaces(&self, lo: Vec3, hi: Vec3, which: Which) -> Vec<Surface> {
        self.sources.surfaces(self, lo, hi, which)
    }
}

/// Every kind of surface the contact sources can show, in their order (a case shows those of
/// its walls: see [`Simulation::surfaces`]).
pub fn surface_kinds() -> Vec<SurfaceKind> {
    crate::forces::source::Sources::surface_kinds()
}

/// The eight corners of the box [lo, hi]: corner k takes hi in x if bit 0 of k is set, in y
/// for bit 1, in z for bit 2.
pub fn box_corners(lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|k| {
        Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// The part of an infinite plane inside the box [lo, hi], as a convex polygon (empty if the
/// plane misses the box).
pub fn clip_plane_to_box(wall: &Wall, lo: Vec3, hi: Vec3) -> Vec<Vec3> {
    let corner = box_corners(lo, hi);
    let scale = (hi - lo).length();
    let eps = 1e-12 * scale;
    let mut pts: Vec<Vec3> = Vec::new();
    let mut add = |x: Vec3| {
        if !pts.iter().any(|q| (*q - x).length() <= 1e-9 * scale) {
            pts.push(x);
        }
    };
    for a in 0..8 {
        for bit in [1, 2, 4] {
            if a & bit != 0 {
                continue;
            }
            let (pa, pb) = (corner[a], corner[a | bit]);
            let (da, db) = (wall.distance(pa), wall.distance(pb));
            if da.abs() <= eps {
                add(pa);
            }
            if db.abs() <= eps {
                add(pb);
            }
            if (da < -eps && db > eps) || (da > eps && db < -eps) {
                add(pa + (pb - pa) * (da / (da - db)));
            }
        }
    }
    if pts.len() < 3 {
        return Vec::new();
    }
    let centre = pts.iter().copied().sum::<Vec3>() / pts.len() as f64;
    let u = (pts[0] - centre).normalize();
    let v = wall.normal.cross(u);
    pts.sort_by(|a, b| {
        let (da, db) = (*a - centre, *b - centre);
        da.dot(v).atan2(da.dot(u)).total_cmp(&db.dot(v).atan2(db.dot(u)))
    });
    pts
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box face clips to the face itself (4 corners); a plane through a diagonal of the
    /// cube's faces clips to a rectangle; the plane x + y + z = 1.5 through the unit cube's
    /// centre clips to the regular hexagon through the six edge midpoints; a plane beside the
    /// box to nothing.
    #[test]
    fn planes_clip_to_their_polygons_in_the_box() {
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        let face = Wall::plane("z_min", lo, Vec3::Z, 0);
        assert_eq!(clip_plane_to_box(&face, lo, hi).len(), 4);
        let diagonal = Wall::plane("d", lo, Vec3::new(1.0, -1.0, 0.0), 0);
        assert_eq!(clip_plane_to_box(&diagonal, lo, hi).len(), 4);
        let hexagon = clip_plane_to_box(&Wall::plane("h", Vec3::splat(0.5), Vec3::ONE, 0), lo, hi);
        assert_eq!(hexagon.len(), 6);
        // Each corner is an edge midpoint: at the centre's distance sqrt(2)/2 (a cube edge's
        // midpoint from the cube's centre), to rounding.
        for x in &hexagon {
            assert!(((*x - Vec3::splat(0.5)).length() - 0.5f64.sqrt()).abs() < 1e-12, "{x:?}");
        }
        let beside = Wall::plane("b", Vec3::new(2.0, 0.0, 0.0), Vec3::X, 0);
        assert!(clip_plane_to_box(&beside, lo, hi).is_empty());
    }
}
