//! Where particles are placed: an axis-aligned box, a solid cylinder, or the inside of a closed
//! triangle mesh.
//!
//! A region answers four questions: its bounding box, its volume, whether it contains a point
//! and whether it holds a whole sphere (the sphere inside, touching the boundary at most). The
//! last is its [`clearance`](Region::clearance) — the radius of the largest sphere about a
//! point that it holds — compared with the sphere's radius.
//!
//! ## The inside of a mesh
//! [`InsideMesh`] decides whether a point is inside by counting the crossings of the vertical
//! ray above it with the surface, signed by the side each triangle faces (a winding number:
//! +1 inside a closed outward-oriented surface, 0 outside). The triangles are binned in
//! vertical columns over the mesh's footprint in x–y, so that a query meets the triangles of
//! its column only, a few for a fine closed surface, not the whole mesh.
//!
//! A vertical ray through a vertex or along an edge of the surface's projection would be
//! counted by several triangles, or by none. It never is here: the ray is tested against each
//! projected triangle with exact orientation predicates (a floating-point filter with an exact
//! expansion fallback, after Shewchuk 1997) and the tie where the point lies exactly on a
//! projected edge is broken by a symbolic perturbation of the point, to (x + ε, y + ε²) for an
//! infinitesimal ε (simulation of simplicity, Edelsbrunner & Mücke 1990). The perturbed point
//! lies on no projected edge, so each crossing of the surface is counted once, by exactly one
//! triangle, whatever the mesh's vertices are; triangles seen edge-on from above (vertical
//! walls) have no interior in projection and are never counted. Only the height of a crossing
//! is computed in floating point, so that a point within rounding of the surface itself may
//! be classified either way.

use crate::math::Vec3;
use crate::mesh::{Mesh, closest_point_on_triangle};
use std::f64::consts::PI;
use thiserror::Error;

/// A region that particles are placed in. Lengths in metres.
#[derive(Debug, Clone, PartialEq)]
pub enum Region {
    /// The axis-aligned box [`lo`, `hi`].
    Box {
        /// Lower corner, m.
        lo: Vec3,
        /// Upper corner, m.
        hi: Vec3,
    },
    /// A solid circular cylinder: the points within `radius` of the segment from `base` to
    /// `base + length·axis/|axis|`.
    Cylinder {
        /// Centre of one end disc, m.
        base: Vec3,
        /// Direction from `base` to the other end; any non-zero length (the methods use its
        /// direction; [`Region::cylinder`] stores it normalised).
        axis: Vec3,
        /// Distance between the end discs, m.
        length: f64,
        /// Radius, m.
        radius: f64,
    },
    /// The inside of a closed, outward-oriented triangle mesh.
    Mesh(Box<InsideMesh>),
}

/// A region that cannot be used: the message says what is wrong and what would do.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RegionError {
    /// A coordinate, direction or length that is not a finite number.
    #[error("{region} region: {what} is {value}, not a finite number")]
    NotFinite {
        /// `box` or `cylinder`.
        region: &'static str,
        /// Which value.
        what: String,
        /// The value as given.
        value: String,
    },
    /// An extent, length or radius that is not positive.
    #[error("{region} region: {what} is {value:e} m; it must be positive")]
    NotPositive {
        /// `box` or `cylinder`.
        region: &'static str,
        /// Which extent.
        what: String,
        /// The value, m.
        value: f64,
    },
    /// A cylinder whose axis is the zero vector.
    #[error("cylinder region: the axis is the zero vector; it must give the cylinder's direction")]
    ZeroAxis,
    /// A mesh with an edge of one triangle: its inside is not defined.
    #[error(
        "mesh region '{mesh}': the edge from {from} to {to} belongs to one triangle only, so the \
         mesh is not closed; a region must be the inside of a closed surface"
    )]
    Open {
        /// The mesh's name.
        mesh: String,
        /// The edge's first vertex, m.
        from: Vec3,
        /// Its second vertex, m.
        to: Vec3,
    },
    /// A closed mesh whose normals point inwards (or a surface enclosing no volume).
    #[error(
        "mesh region '{mesh}': its signed volume is {volume:e} m³, not positive, so its normals \
         point inwards; reverse its winding (e.g. with flip_normals)"
    )]
    Inward {
        /// The mesh's name.
        mesh: String,
        /// The signed volume, m³.
        volume: f64,
    },
}

impl Region {
    /// A cylinder, its axis stored normalised.
    pub fn cylinder(base: Vec3, axis: Vec3, length: f64, radius: f64) -> Region {
        let n = axis.length();
        let axis = if n > 0.0 && n.is_finite() { axis / n } else { axis };
        Region::Cylinder { base, axis, length, radius }
    }

    /// The inside of `mesh` (see [`InsideMesh::new`]); [`check`](Self::check) tells whether it
    /// is closed and outward-oriented.
    pub fn mesh(mesh: &Mesh) -> Region {
        Region::Mesh(Box::new(InsideMesh::new(mesh)))
    }

    /// Checks that the region is usable: finite coordinates, a positive extent along each axis
    /// (a box), a non-zero axis and a positive length and radius (a cylinder), a closed
    /// (every edge shared by exactly two triangles) and outward-oriented (positive signed
    /// volume) surface (a mesh).
    pub fn check(&self) -> Result<(), RegionError> {
        let finite = |region: &'static str, what: &str, v: Vec3| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(RegionError::NotFinite { region, what: what.into(), value: format!("{v}") })
            }
        };
        let positive = |region: &'static str, what: String, v: f64| {
            if !v.is_finite() {
                Err(RegionError::NotFinite { region, what, value: format!("{v}") })
            } else if v <= 0.0 {
                Err(RegionError::NotPositive { region, what, value: v })
            } else {
                Ok(())
            }
        };
        match self {
            Region::Box { lo, hi } => {
                finite("box", "the lower corner", *lo)?;
                finite("box", "the upper corner", *hi)?;
                for (k, name) in ["x", "y", "z"].iter().enumerate() {
                    let e = hi.to_array()[k] - lo.to_array()[k];
                    positive("box", format!("the extent along {name} (hi.{name} − lo.{name})"), e)?;
                }
                Ok(())
            }
            Region::Cylinder { base, axis, length, radius } => {
                finite("cylinder", "the base", *base)?;
                finite("cylinder", "the axis", *axis)?;
                if axis.length_squared() == 0.0 {
                    return Err(RegionError::ZeroAxis);
                }
                positive("cylinder", "the length".into(), *length)?;
                positive("cylinder", "the radius".into(), *radius)
            }
            Region::Mesh(m) => m.check(),
        }
    }

    /// The axis-aligned bounding box (min, max), m.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Region::Box { lo, hi } => (*lo, *hi),
            Region::Cylinder { base, axis, length, radius } => {
                let a = axis.normalize();
                let top = *base + *length * a;
                // The end discs reach r·√(1 − a_k²) from their centres along axis k.
                let reach = Vec3::from_array(a.to_array().map(|c| radius * (1.0 - c * c).max(0.0).sqrt()));
                (base.min(top) - reach, base.max(top) + reach)
            }
            Region::Mesh(m) => (m.lo, m.hi),
        }
    }

    /// The volume, m³ (a mesh's by the divergence theorem: the sum of the signed volumes of the
    /// tetrahedra its triangles make with a fixed point).
    pub fn volume(&self) -> f64 {
        match self {
            Region::Box { lo, hi } => (*hi - *lo).to_array().iter().product(),
            Region::Cylinder { length, radius, .. } => PI * radius * radius * length,
            Region::Mesh(m) => m.volume,
        }
    }

    /// True if `x` is inside the region or on its boundary (for a mesh: to the rounding of the
    /// surface's height above the point).
    pub fn contains(&self, x: Vec3) -> bool {
        match self {
            Region::Mesh(m) => m.contains(x),
            _ => self.clearance(x, 0.0) >= 0.0,
        }
    }

    /// True if the whole sphere of radius `r` about `x` is inside the region (touching the
    /// boundary at most): [`clearance`](Self::clearance)`(x, r) ≥ r`.
    pub fn holds_sphere(&self, x: Vec3, r: f64) -> bool {
        self.clearance(x, r) >= r
    }

    /// The radius of the largest sphere about `x` that the region holds — the distance from
    /// `x` to the boundary — or `reach` if that is smaller (m): so that a mesh is searched
    /// for triangles within `reach` only. Negative if `x` is outside (for a box or a cylinder
    /// minus the depth beyond the nearest violated face, for a mesh −∞).
    pub fn clearance(&self, x: Vec3, reach: f64) -> f64 {
        match self {
            Region::Box { lo, hi } => {
                let (d0, d1) = (x - *lo, *hi - x);
                d0.min(d1).min_element().min(reach)
            }
            Region::Cylinder { base, axis, length, radius } => {
                cylinder_clearance(x, *base, axis.normalize(), *length, *radius, true).min(reach)
            }
            Region::Mesh(m) => m.clearance(x, reach),
        }
    }
}

/// The clearance of `x` in the cylinder (`base`, unit `axis`, `length`, `radius`): the
/// smallest of its distances to the mantle and, if `caps`, to the end discs' planes.
pub(crate) fn cylinder_clearance(
    x: Vec3,
    base: Vec3,
    axis: Vec3,
    length: f64,
    radius: f64,
    caps: bool,
) -> f64 {
    let d = x - base;
    let t = d.dot(axis);
    let radial = (d - t * axis).length();
    let side = radius - radial;
    if caps { side.min(t).min(length - t) } else { side }
}

/// The inside of a closed triangle mesh, prepared for point and sphere queries: the triangles'
/// corners and bounding boxes, binned in vertical columns (see the [module doc](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct InsideMesh {
    name: String,
    corners: Vec<[Vec3; 3]>,
    /// Each triangle's bounding box (min, max).
    boxes: Vec<(Vec3, Vec3)>,
    /// Each triangle's exact orientation seen from +z: +1 facing up, −1 down, 0 edge-on.
    facing: Vec<i8>,
    lo: Vec3,
    hi: Vec3,
    volume: f64,
    /// An edge of one triangle, if any: the mesh is then open.
    open_edge: Option<(Vec3, Vec3)>,
    columns: Columns,
}

/// Triangles binned by the columns their x–y bounding boxes meet.
#[derive(Debug, Clone, PartialEq)]
struct Columns {
    lo: [f64; 2],
    cell: [f64; 2],
    n: [usize; 2],
    /// Triangles of column c: `triangles[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    triangles: Vec<u32>,
}

/// Columns per triangle that the binning aims at: a column about a triangle wide, so that a
/// ray meets a few triangles per sheet of a fine surface.
const COLUMNS_PER_TRIANGLE: usize = 2;
/// The most columns a mesh's binning may have.
const MAX_COLUMNS: usize = 1 << 22;

impl InsideMesh {
    /// The inside of `mesh` (its corners are copied). Any mesh is accepted;
    /// [`Region::check`] refuses one that is open or inward-oriented, whose inside is not
    /// defined.
    pub fn new(mesh: &Mesh) -> InsideMesh {
        let corners: Vec<[Vec3; 3]> = (0..mesh.triangle_count() as u32).map(|t| mesh.corners(t)).collect();
        let open_edge = mesh.edges().iter().find(|e| e.triangles().len() != 2).map(|e| {
            let v = mesh.vertices();
            (v[e.vertices[0] as usize], v[e.vertices[1] as usize])
        });
        InsideMesh::of_corners(mesh.name(), corners, open_edge)
    }

    /// The inside of the surface of `corners` (a mesh's triangles where it is now), named
    /// `name`; `open_edge` an edge of one triangle only, if the surface has one (its inside is
    /// then not defined, and [`Region::check`] refuses it).
    pub fn of_corners(name: &str, corners: Vec<[Vec3; 3]>, open_edge: Option<(Vec3, Vec3)>) -> InsideMesh {
        let (lo, hi) = corners
            .iter()
            .flatten()
            .fold((Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        let boxes: Vec<(Vec3, Vec3)> =
            corners.iter().map(|&[a, b, c]| (a.min(b).min(c), a.max(b).max(c))).collect();
        let facing = corners.iter().map(|&[a, b, c]| orient2d([a.x, a.y], [b.x, b.y], [c.x, c.y])).collect();
        // Signed tetrahedra from the bounding box's centre: their coordinates are then about
        // half the mesh's size, whatever its position.
        let o = 0.5 * (lo + hi);
        let volume = corners.iter().map(|&[a, b, c]| (a - o).dot((b - o).cross(c - o))).sum::<f64>() / 6.0;
        let columns = Columns::new(lo, hi, &boxes);
        InsideMesh { name: name.to_string(), corners, boxes, facing, lo, hi, volume, open_edge, columns }
    }

    /// The mesh's name, for messages.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The signed volume enclosed, m³ (positive for an outward-oriented closed surface).
    pub fn volume(&self) -> f64 {
        self.volume
    }

    /// The number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.corners.len()
    }

    /// The triangles' corners, m.
    pub fn corners(&self) -> &[[Vec3; 3]] {
        &self.corners
    }

    /// The bounding box (min, max), m.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.lo, self.hi)
    }

    fn check(&self) -> Result<(), RegionError> {
        if let Some((from, to)) = self.open_edge {
            return Err(RegionError::Open { mesh: self.name.clone(), from, to });
        }
        if self.volume.is_nan() || self.volume <= 0.0 {
            return Err(RegionError::Inward { mesh: self.name.clone(), volume: self.volume });
        }
        Ok(())
    }

    /// True if `x` is inside the surface, or on it (to the rounding of the height of the
    /// surface above the point): the winding number of the vertical ray above `x` is not
    /// zero (see the [module doc](self)).
    pub fn contains(&self, x: Vec3) -> bool {
        if x.cmplt(self.lo).any() || x.cmpgt(self.hi).any() {
            return false;
        }
        let p = [x.x, x.y];
        let mut winding = 0i32;
        for &t in self.columns.at(p) {
            let t = t as usize;
            let (lo, hi) = self.boxes[t];
            let up = self.facing[t];
            // Beside the triangle's footprint, wholly below the point, or seen edge-on.
            if p[0] < lo.x || p[0] > hi.x || p[1] < lo.y || p[1] > hi.y || x.z > hi.z || up == 0 {
                continue;
            }
            let [a, b, c] = self.corners[t];
            let (a2, b2, c2) = ([a.x, a.y], [b.x, b.y], [c.x, c.y]);
            if orient2d_perturbed(a2, b2, p) != up
                || orient2d_perturbed(b2, c2, p) != up
                || orient2d_perturbed(c2, a2, p) != up
            {
                continue;
            }
            // The height of the triangle's plane over p, from the barycentric weights (the
            // signed areas, all of the triangle's sign), kept within the triangle's heights.
            let (wa, wb, wc) = (area2(b2, c2, p), area2(c2, a2, p), area2(a2, b2, p));
            let sum = wa + wb + wc;
            let z = if sum != 0.0 { (wa * a.z + wb * b.z + wc * c.z) / sum } else { 0.5 * (lo.z + hi.z) };
            let z = z.clamp(lo.z, hi.z);
            if z == x.z {
                return true;
            }
            if z > x.z {
                winding += i32::from(up);
            }
        }
        winding != 0
    }

    /// The distance from `x` to the surface, or `reach` if that is smaller, if `x` is inside;
    /// −∞ if it is outside (m). Searches the triangles within `reach` of `x` only.
    pub fn clearance(&self, x: Vec3, reach: f64) -> f64 {
        if !self.contains(x) {
            return f64::NEG_INFINITY;
        }
        self.distance_within(x, reach)
    }

    /// True if the whole sphere of radius `r` about `x` is inside: `x` inside and no triangle
    /// closer than `r`.
    pub fn holds_sphere(&self, x: Vec3, r: f64) -> bool {
        self.clearance(x, r) >= r
    }

    /// The distance from `x` to the nearest triangle, or `reach` if that is smaller.
    fn distance_within(&self, x: Vec3, reach: f64) -> f64 {
        let mut best = reach;
        if reach.is_nan() || reach <= 0.0 {
            return best;
        }
        let (c0, c1) =
            (self.columns.index([x.x - reach, x.y - reach]), self.columns.index([x.x + reach, x.y + reach]));
        for cy in c0[1]..=c1[1] {
            for cx in c0[0]..=c1[0] {
                for &t in self.columns.list(cx, cy) {
                    let (lo, hi) = self.boxes[t as usize];
                    // The distance to the bounding box bounds the distance to the triangle.
                    let out = (lo - x).max(x - hi).max(Vec3::ZERO);
                    if out.length_squared() >= best * best {
                        continue;
                    }
                    let q = closest_point_on_triangle(x, self.corners[t as usize]).point;
                    best = best.min((x - q).length());
                }
            }
        }
        best
    }
}

impl Columns {
    fn new(lo: Vec3, hi: Vec3, boxes: &[(Vec3, Vec3)]) -> Columns {
        let span = [(hi.x - lo.x).max(0.0), (hi.y - lo.y).max(0.0)];
        let target = (COLUMNS_PER_TRIANGLE * boxes.len()).clamp(1, MAX_COLUMNS) as f64;
        let area = span[0] * span[1];
        let side = if area > 0.0 { (area / target).sqrt() } else { span[0].max(span[1]).max(1.0) };
        let n = span.map(|s| ((s / side).ceil() as usize).clamp(1, MAX_COLUMNS));
        let cell = [0, 1].map(|k| if span[k] > 0.0 { span[k] / n[k] as f64 } else { 1.0 });
        let mut columns =
            Columns { lo: [lo.x, lo.y], cell, n, start: vec![0; n[0] * n[1] + 1], triangles: Vec::new() };
        let ranges: Vec<([usize; 2], [usize; 2])> =
            boxes.iter().map(|(l, h)| (columns.index([l.x, l.y]), columns.index([h.x, h.y]))).collect();
        for (l, h) in &ranges {
            for cy in l[1]..=h[1] {
                for cx in l[0]..=h[0] {
                    columns.start[cy * n[0] + cx + 1] += 1;
                }
            }
        }
        for c in 0..n[0] * n[1] {
            columns.start[c + 1] += columns.start[c];
        }
        let mut fill = columns.start.clone();
        columns.triangles = vec![0; columns.start[n[0] * n[1]] as usize];
        for (t, (l, h)) in ranges.iter().enumerate() {
            for cy in l[1]..=h[1] {
                for cx in l[0]..=h[0] {
                    let c = cy * n[0] + cx;
                    columns.triangles[fill[c] as usize] = t as u32;
                    fill[c] += 1;
                }
            }
        }
        columns
    }

    /// The column of a point, clamped to the grid.
    fn index(&self, p: [f64; 2]) -> [usize; 2] {
        [0, 1].map(|k| {
            let f = ((p[k] - self.lo[k]) / self.cell[k]).floor();
            if f >= 0.0 { (f as usize).min(self.n[k] - 1) } else { 0 }
        })
    }

    fn list(&self, cx: usize, cy: usize) -> &[u32] {
        let c = cy * self.n[0] + cx;
        &self.triangles[self.start[c] as usize..self.start[c + 1] as usize]
    }

    /// The triangles of the column of `p` (a point within the grid's footprint).
    fn at(&self, p: [f64; 2]) -> &[u32] {
        let [cx, cy] = self.index(p);
        self.list(cx, cy)
    }
}

/// Twice the signed area of the triangle a, b, c in floating point (its rounding unbounded
/// relative to a small result).
fn area2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0])
}

/// The sign of the orientation of c relative to the directed line a → b, with c moved to
/// (c.x + ε, c.y + ε²) for an infinitesimal ε > 0 when it lies exactly on the line: never 0
/// unless a and b coincide.
fn orient2d_perturbed(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let s = orient2d(a, b, c);
    if s != 0 {
        return s;
    }
    // d/dε of (b − a) × (c − a) is (a.y − b.y), then (b.x − a.x) at order ε².
    let s = sign(a[1] - b[1]);
    if s != 0 { s } else { sign(b[0] - a[0]) }
}

fn sign(v: f64) -> i8 {
    if v > 0.0 {
        1
    } else if v < 0.0 {
        -1
    } else {
        0
    }
}

/// Shewchuk's bound on the rounding of the floating-point orientation: (3 + 16ε)ε, ε = 2⁻⁵³.
const CCW_ERROR_BOUND: f64 = (3.0 + 16.0 * f64::EPSILON / 2.0) * (f64::EPSILON / 2.0);

/// The exact sign of (a − c) × (b − c): +1 if a, b, c turn counter-clockwise, −1 clockwise,
/// 0 collinear (Shewchuk's orient2d: the floating-point value when its error bound proves the
/// sign, else the exact value as an expansion). Exact for all finite inputs whose products
/// neither overflow nor underflow.
pub(crate) fn orient2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let left = (a[0] - c[0]) * (b[1] - c[1]);
    let right = (a[1] - c[1]) * (b[0] - c[0]);
    let det = left - right;
    let sum = if left > 0.0 {
        if right <= 0.0 {
            return sign(det);
        }
        left + right
    } else if left < 0.0 {
        if right >= 0.0 {
            return sign(det);
        }
        -left - right
    } else {
        return sign(det);
    };
    let bound = CCW_ERROR_BOUND * sum;
    if det >= bound || -det >= bound {
        return sign(det);
    }
    orient2d_exact(a, b, c)
}

/// The exact sign of (a − c) × (b − c) from expansions: each difference is exactly the sum of
/// two floats, so the determinant is exactly a sum of 16 products, each exactly the sum of two
/// floats; their exact sum's sign is that of its most significant non-zero component.
fn orient2d_exact(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let (acx, acxt) = two_diff(a[0], c[0]);
    let (bcy, bcyt) = two_diff(b[1], c[1]);
    let (acy, acyt) = two_diff(a[1], c[1]);
    let (bcx, bcxt) = two_diff(b[0], c[0]);
    let mut e: Vec<f64> = Vec::with_capacity(32);
    for (u, v, s) in [
        (acx, bcy, 1.0),
        (acx, bcyt, 1.0),
        (acxt, bcy, 1.0),
        (acxt, bcyt, 1.0),
        (acy, bcx, -1.0),
        (acy, bcxt, -1.0),
        (acyt, bcx, -1.0),
        (acyt, bcxt, -1.0),
    ] {
        let (p, q) = two_product(u, v);
        grow_expansion(&mut e, s * q);
        grow_expansion(&mut e, s * p);
    }
    e.iter().rev().find(|&&v| v != 0.0).map_or(0, |&v| sign(v))
}

/// Adds `b` to the non-overlapping expansion `e` (components in increasing magnitude),
/// exactly (Shewchuk's Grow-Expansion, zero components dropped).
fn grow_expansion(e: &mut Vec<f64>, b: f64) {
    let mut q = b;
    let mut out = 0;
    for i in 0..e.len() {
        let (s, h) = two_sum(q, e[i]);
        q = s;
        if h != 0.0 {
            e[out] = h;
            out += 1;
        }
    }
    e.truncate(out);
    if q != 0.0 {
        e.push(q);
    }
}

/// a + b as (rounded sum, exact error).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let x = a + b;
    let bv = x - a;
    let av = x - bv;
    (x, (a - av) + (b - bv))
}

/// a − b as (rounded difference, exact error).
fn two_diff(a: f64, b: f64) -> (f64, f64) {
    let x = a - b;
    let bv = a - x;
    let av = x + bv;
    (x, (a - av) + (bv - b))
}

/// Dekker's split of a into high and low halves of 26 bits each.
fn split(a: f64) -> (f64, f64) {
    const SPLITTER: f64 = 134_217_729.0; // 2^27 + 1
    let c = SPLITTER * a;
    let big = c - a;
    let hi = c - big;
    (hi, a - hi)
}

/// a·b as (rounded product, exact error), without a fused multiply-add.
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let x = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let err = ((x - ah * bh) - al * bh) - ah * bl;
    (x, al * bl - err)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact sign for points on a fine dyadic grid, against integer arithmetic (exact in
    /// i128): nearly collinear triples, where the floating-point value is rounding noise.
    #[test]
    fn orientation_is_exact() {
        let scale = 2f64.powi(-40);
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut hard = 0;
        for _ in 0..20_000 {
            // Three points near one line, with differences of 2^30 grid steps, so that the
            // products round: a + t·(b − a) + a step or none across it.
            let base = [(next() % (1 << 50)) as i64, (next() % (1 << 50)) as i64];
            let dir = [(next() % (1 << 27)) as i64 + 1, (next() % (1 << 27)) as i64 - (1 << 26)];
            let pick = |t: i64, w: i64| [base[0] + t * dir[0] + w, base[1] + t * dir[1] - w];
            let a = pick(0, 0);
            let b = pick(3 + (next() % 5) as i64, 0);
            let c = pick((next() % 7) as i64 - 3, (next() % 3) as i64 - 1);
            let exact = {
                let (ax, ay, bx, by, cx, cy) =
                    (a[0] as i128, a[1] as i128, b[0] as i128, b[1] as i128, c[0] as i128, c[1] as i128);
                ((ax - cx) * (by - cy) - (ay - cy) * (bx - cx)).signum() as i8
            };
            let f = |p: [i64; 2]| [p[0] as f64 * scale, p[1] as f64 * scale];
            let (fa, fb, fc) = (f(a), f(b), f(c));
            // The floating-point filter cannot decide: the exact path is taken.
            let left = (fa[0] - fc[0]) * (fb[1] - fc[1]);
            let right = (fa[1] - fc[1]) * (fb[0] - fc[0]);
            if (left - right).abs() < CCW_ERROR_BOUND * (left.abs() + right.abs()) {
                hard += 1;
            }
            assert_eq!(orient2d(fa, fb, fc), exact, "{a:?} {b:?} {c:?}");
        }
        assert!(hard > 1000, "only {hard} near-collinear cases");
    }

    /// The perturbed orientation is antisymmetric in the line's direction and never zero.
    #[test]
    fn perturbation_breaks_every_tie() {
        let pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.5, 0.5], [0.5, 0.0], [2.0, 2.0]];
        for a in pts {
            for b in pts {
                if a == b {
                    continue;
                }
                for c in pts {
                    let s = orient2d_perturbed(a, b, c);
                    assert_ne!(s, 0);
                    assert_eq!(orient2d_perturbed(b, a, c), -s);
                }
            }
        }
    }
}
