//! MFIX's grids where a deck's STL walls cut them, for the rules that depend on them:
//!
//! - the **fluid grid** (`IMAX`×`JMAX`×`KMAX` uniform cells over the box) with each cell's
//!   fluid fraction: the part of the cell on the particles' side of the STL walls. MFIX's cut
//!   cells hold that part's volume (`VOL(IJK)`), a cell wholly behind the walls is no fluid
//!   cell (`FLUID_AT` false), and `GENER_PART_CONFIG` counts only the fluid volume of its IC's
//!   cells (`GET_IC_VOLUME`); a cut cell whose fraction is below `TOL_SMALL_CELL` is a small
//!   cell, not counted. The fraction is measured here by sampling each cut cell on a regular
//!   8×8×8 grid of points, each on the side of its nearest facet (the side its normal points
//!   to is the fluid, as in MFIX); a cell no facet crosses is wholly on one side.
//! - the **DES grid** (`DESGRIDSEARCH_IMAX`…, by default cells of 3 largest diameters, or the
//!   fluid cell if smaller) with the facets binned in each cell as MFIX bins them
//!   (`BIN_FACETS_TO_DG`: a facet belongs to every cell, ghost layers included, whose box grown
//!   by 1.1 largest radii it overlaps), and MFIX's test of a seeded site against them
//!   (`CHECK_IF_PARTICLE_OVERLAPS_STL`): a site is skipped when it lies behind the plane of any
//!   facet binned in the DES cells that span its fluid cell, or within 1.05 largest radii of
//!   that plane. The planes are infinite: where walls meet at an edge that is convex seen from
//!   the fluid (the top of a hopper's outlet pipe), the sites near the edge lie behind the
//!   other wall's plane and stay empty, as in MFIX.

use grainflow::Vec3;
use grainflow::mesh::{Mesh, closest_point_on_triangle};
use std::collections::VecDeque;

/// A facet of the STL walls: its corners and its unit normal, toward the fluid.
pub(super) struct Facet {
    c: [Vec3; 3],
    n: Vec3,
    lo: Vec3,
    hi: Vec3,
}

impl Facet {
    pub(super) fn corners(&self) -> &[Vec3; 3] {
        &self.c
    }

    /// True if the facet reaches the plane x[axis] = at.
    pub(super) fn spans(&self, axis: usize, at: f64) -> bool {
        self.lo[axis] <= at && at <= self.hi[axis]
    }
}

/// The facets of the walls, as MFIX holds them after reading the STL files.
pub(super) fn facets(walls: &[Mesh]) -> Vec<Facet> {
    let mut out = Vec::new();
    for mesh in walls {
        let normals = mesh.normals();
        for t in 0..mesh.triangle_count() as u32 {
            let c = mesh.corners(t);
            out.push(Facet {
                c,
                n: normals[t as usize],
                lo: c[0].min(c[1]).min(c[2]),
                hi: c[0].max(c[1]).max(c[2]),
            });
        }
    }
    out
}

/// Sample points per cut cell and axis for its fluid fraction.
const SAMPLES: usize = 8;

/// A uniform grid of cells over a box.
#[derive(Debug, Clone, Copy)]
struct Cells {
    lo: Vec3,
    h: Vec3,
    n: [usize; 3],
}

impl Cells {
    fn new(lo: Vec3, hi: Vec3, n: [usize; 3]) -> Cells {
        let h =
            Vec3::new((hi.x - lo.x) / n[0] as f64, (hi.y - lo.y) / n[1] as f64, (hi.z - lo.z) / n[2] as f64);
        Cells { lo, h, n }
    }

    fn len(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    fn index(&self, c: [usize; 3]) -> usize {
        c[0] + self.n[0] * (c[1] + self.n[1] * c[2])
    }

    fn corner(&self, c: [usize; 3]) -> Vec3 {
        self.lo + Vec3::new(c[0] as f64 * self.h.x, c[1] as f64 * self.h.y, c[2] as f64 * self.h.z)
    }

    /// The cells a box [a, b] touches, as index ranges (inclusive), clamped to the grid.
    fn range(&self, a: Vec3, b: Vec3) -> [[usize; 2]; 3] {
        let mut r = [[0; 2]; 3];
        for k in 0..3 {
            let f = |x: f64| (((x - self.lo[k]) / self.h[k]).floor().max(0.0) as usize).min(self.n[k] - 1);
            r[k] = [f(a[k]), f(b[k])];
        }
        r
    }
}

/// MFIX's fluid grid with each cell's fluid fraction.
pub(super) struct FluidGrid {
    cells: Cells,
    frac: Vec<f32>,
    /// The facets crossing each cell.
    bins: Vec<Vec<u32>>,
}

impl FluidGrid {
    /// The fluid fractions of the `n` cells over [lo, hi] cut by `facets`.
    pub(super) fn new(lo: Vec3, hi: Vec3, n: [usize; 3], facets: &[Facet]) -> FluidGrid {
        let cells = Cells::new(lo, hi, n);
        let mut bins: Vec<Vec<u32>> = vec![Vec::new(); cells.len()];
        for (id, f) in facets.iter().enumerate() {
            let r = cells.range(f.lo, f.hi);
            for k in r[2][0]..=r[2][1] {
                for j in r[1][0]..=r[1][1] {
                    for i in r[0][0]..=r[0][1] {
                        let c = [i, j, k];
                        let centre = cells.corner(c) + 0.5 * cells.h;
                        if tri_box_overlap(centre, 0.5 * cells.h * (1.0 + 1e-9), &f.c) {
                            bins[cells.index(c)].push(id as u32);
                        }
                    }
                }
            }
        }
        let all: Vec<u32> = (0..facets.len() as u32).collect();
        let mut frac = vec![f32::NAN; cells.len()];
        // Cells no facet crosses: each connected run of them lies on one side; one centre
        // tells which.
        for start in 0..cells.len() {
            if !frac[start].is_nan() || !bins[start].is_empty() {
                continue;
            }
            let c = unindex(&cells, start);
            let centre = cells.corner(c) + 0.5 * cells.h;
            let side = if nearest_side(centre, &all, facets).1 { 1.0 } else { 0.0 };
            let mut queue = VecDeque::from([start]);
            frac[start] = side;
            while let Some(at) = queue.pop_front() {
                let c = unindex(&cells, at);
                for (k, d) in [(0, -1i64), (0, 1), (1, -1), (1, 1), (2, -1), (2, 1)] {
                    let x = c[k] as i64 + d;
                    if x < 0 || x >= cells.n[k] as i64 {
                        continue;
                    }
                    let mut m = c;
                    m[k] = x as usize;
                    let next = cells.index(m);
                    if frac[next].is_nan() && bins[next].is_empty() {
                        frac[next] = side;
                        queue.push_back(next);
                    }
                }
            }
        }
        // Cut cells: the share of sample points in front of their nearest facet.
        let reach = cells.h.x.min(cells.h.y).min(cells.h.z);
        for at in 0..cells.len() {
            if !frac[at].is_nan() {
                continue;
            }
            let c = unindex(&cells, at);
            let near = near_facets(&cells, &bins, c);
            let base = cells.corner(c);
            let mut inside = 0usize;
            for s in 0..SAMPLES * SAMPLES * SAMPLES {
                let q = [s % SAMPLES, (s / SAMPLES) % SAMPLES, s / (SAMPLES * SAMPLES)];
                let p = base
                    + Vec3::new(
                        (q[0] as f64 + 0.5) / SAMPLES as f64 * cells.h.x,
                        (q[1] as f64 + 0.5) / SAMPLES as f64 * cells.h.y,
                        (q[2] as f64 + 0.5) / SAMPLES as f64 * cells.h.z,
                    );
                // A facet nearer than `reach` crosses the cells around this one, so the
                // nearest facet is among theirs; farther, it may be anywhere.
                let (d, front) = nearest_side(p, &near, facets);
                let front = if d <= reach { front } else { nearest_side(p, &all, facets).1 };
                inside += usize::from(front);
            }
            frac[at] = (inside as f64 / (SAMPLES * SAMPLES * SAMPLES) as f64) as f32;
        }
        FluidGrid { cells, frac, bins }
    }

    /// The fluid area of the face x[axis] = `at` over the rectangle [lo, hi] (MFIX's
    /// `BC_AREA` of a flow boundary on it): the cells of the layer on its `inward` side, each
    /// wholly fluid or not, or for a cut cell the share of an 8×8 grid of points on the face
    /// in front of their nearest facet.
    pub(super) fn face_area(
        &self,
        axis: usize,
        at: f64,
        inward: f64,
        lo: Vec3,
        hi: Vec3,
        facets: &[Facet],
    ) -> f64 {
        let c = &self.cells;
        let (p, q) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let layer = (((at - c.lo[axis]) / c.h[axis]).round() + if inward > 0.0 { 0.0 } else { -1.0 })
            .clamp(0.0, (c.n[axis] - 1) as f64) as usize;
        let r = c.range(lo, hi);
        let mut area = 0.0;
        for a in r[p][0]..=r[p][1] {
            for b in r[q][0]..=r[q][1] {
                let mut cell = [0; 3];
                cell[axis] = layer;
                cell[p] = a;
                cell[q] = b;
                let base = c.corner(cell);
                // The part of the cell's face inside [lo, hi].
                let (p0, p1) = (base[p].max(lo[p]), (base[p] + c.h[p]).min(hi[p]));
                let (q0, q1) = (base[q].max(lo[q]), (base[q] + c.h[q]).min(hi[q]));
                if p1 <= p0 || q1 <= q0 {
                    continue;
                }
                let at_cell = self.index_of(cell);
                let whole = (p1 - p0) * (q1 - q0);
                if self.bins[at_cell].is_empty() {
                    area += whole * f64::from(self.frac[at_cell]);
                    continue;
                }
                let near = self.near(cell);
                let mut inside = 0usize;
                for s in 0..SAMPLES * SAMPLES {
                    let mut x = Vec3::ZERO;
                    x[axis] = at + inward * 1e-9 * c.h[axis];
                    x[p] = p0 + ((s % SAMPLES) as f64 + 0.5) / SAMPLES as f64 * (p1 - p0);
                    x[q] = q0 + ((s / SAMPLES) as f64 + 0.5) / SAMPLES as f64 * (q1 - q0);
                    inside += usize::from(self.side(x, &near, facets));
                }
                area += whole * inside as f64 / (SAMPLES * SAMPLES) as f64;
            }
        }
        area
    }

    fn index_of(&self, c: [usize; 3]) -> usize {
        self.cells.index(c)
    }

    /// The facets crossing the cell `c` and its neighbours.
    fn near(&self, c: [usize; 3]) -> Vec<u32> {
        near_facets(&self.cells, &self.bins, c)
    }

    /// True if `x` (in the cell whose neighbours' facets are `near`) is on the fluid side.
    fn side(&self, x: Vec3, near: &[u32], facets: &[Facet]) -> bool {
        let reach = self.cells.h.x.min(self.cells.h.y).min(self.cells.h.z);
        let (d, front) = nearest_side(x, near, facets);
        if d <= reach {
            front
        } else {
            let all: Vec<u32> = (0..facets.len() as u32).collect();
            nearest_side(x, &all, facets).1
        }
    }

    /// The fluid volume of the cells [r[k][0], r[k][1]) on each axis, leaving out the small
    /// cells (fraction below `tol_small`), as MFIX's `GET_IC_VOLUME` counts it.
    pub(super) fn fluid_volume(&self, r: [[usize; 2]; 3], tol_small: f64) -> f64 {
        let v = self.cells.h.x * self.cells.h.y * self.cells.h.z;
        let mut total = 0.0;
        for k in r[2][0]..r[2][1].min(self.cells.n[2]) {
            for j in r[1][0]..r[1][1].min(self.cells.n[1]) {
                for i in r[0][0]..r[0][1].min(self.cells.n[0]) {
                    let f = f64::from(self.frac[self.cells.index([i, j, k])]);
                    if f > 0.0 && f >= tol_small {
                        total += f * v;
                    }
                }
            }
        }
        total
    }

    /// The cell holding `p` (MFIX's `PIC_SEARCH`: x in [west face, east face)), if inside.
    fn cell_of(&self, p: Vec3) -> Option<[usize; 3]> {
        let mut c = [0; 3];
        for k in 0..3 {
            let f = ((p[k] - self.cells.lo[k]) / self.cells.h[k]).floor();
            if !(f >= 0.0 && f < self.cells.n[k] as f64) {
                return None;
            }
            c[k] = f as usize;
        }
        Some(c)
    }

    /// True if `p` lies in a cell with fluid in it (a fluid, cut or small cell).
    pub(super) fn wet(&self, p: Vec3) -> bool {
        self.cell_of(p).is_some_and(|c| self.frac[self.cells.index(c)] > 0.0)
    }

    /// The fluid fraction of the cell holding `p` (0 outside the grid).
    #[cfg(test)]
    fn fraction_at(&self, p: Vec3) -> f64 {
        self.cell_of(p).map_or(0.0, |c| f64::from(self.frac[self.cells.index(c)]))
    }
}

/// The facets crossing the cell `c` and its neighbours.
fn near_facets(cells: &Cells, bins: &[Vec<u32>], c: [usize; 3]) -> Vec<u32> {
    let n = cells.n;
    let mut near: Vec<u32> = Vec::new();
    for k in c[2].saturating_sub(1)..=(c[2] + 1).min(n[2] - 1) {
        for j in c[1].saturating_sub(1)..=(c[1] + 1).min(n[1] - 1) {
            for i in c[0].saturating_sub(1)..=(c[0] + 1).min(n[0] - 1) {
                near.extend_from_slice(&bins[cells.index([i, j, k])]);
            }
        }
    }
    near.sort_unstable();
    near.dedup();
    near
}

fn unindex(cells: &Cells, at: usize) -> [usize; 3] {
    [at % cells.n[0], (at / cells.n[0]) % cells.n[1], at / (cells.n[0] * cells.n[1])]
}

/// The distance from `p` to the nearest of the facets `ids`, and whether `p` is in front of it
/// (on the side its normal points to). Of facets equally near (at an edge or a corner), the
/// one facing `p` most squarely tells the side.
fn nearest_side(p: Vec3, ids: &[u32], facets: &[Facet]) -> (f64, bool) {
    let mut best = f64::INFINITY;
    let mut squareness = 0.0;
    let mut front = true;
    for &id in ids {
        let f = &facets[id as usize];
        let outside = (f.lo - p).max(p - f.hi).max(Vec3::ZERO);
        if outside.length() > best * (1.0 + 1e-9) {
            continue;
        }
        let q = closest_point_on_triangle(p, f.c).point;
        let dist = (p - q).length();
        let side = (p - q).dot(f.n);
        let square = if dist > 0.0 { side.abs() / dist } else { 1.0 };
        if dist < best * (1.0 - 1e-9) || (dist <= best * (1.0 + 1e-9) && square > squareness) {
            best = dist;
            squareness = square;
            front = side >= 0.0;
        }
    }
    (best, front)
}

/// MFIX's DES grid with the facets binned in each cell, ghost layers included.
pub(super) struct DesGrid {
    cells: Cells,
    /// Cells by index with one ghost layer each side: (n + 2) per axis.
    bins: Vec<Vec<u32>>,
    /// 1.05 largest radii, squared: the clearance of a seeded site from a facet's plane.
    clearance_sq: f64,
}

impl DesGrid {
    /// The `n` DES cells over [lo, hi], `max_radius` MFIX's `MAX_RADIUS`.
    pub(super) fn new(lo: Vec3, hi: Vec3, n: [usize; 3], facets: &[Facet], max_radius: f64) -> DesGrid {
        let cells = Cells::new(lo, hi, n);
        let g = [n[0] + 2, n[1] + 2, n[2] + 2];
        let mut bins: Vec<Vec<u32>> = vec![Vec::new(); g[0] * g[1] * g[2]];
        let buffer = 1.1 * max_radius;
        for (id, f) in facets.iter().enumerate() {
            // MFIX looks one cell beyond the facet's extent, within the ghost layers.
            let mut r = [[0usize; 2]; 3];
            for k in 0..3 {
                let at = |x: f64| ((x - lo[k]) / cells.h[k]).floor() + 1.0;
                r[k] = [
                    (at(f.lo[k]) - 1.0).clamp(0.0, (g[k] - 1) as f64) as usize,
                    (at(f.hi[k]) + 1.0).clamp(0.0, (g[k] - 1) as f64) as usize,
                ];
            }
            for k in r[2][0]..=r[2][1] {
                for j in r[1][0]..=r[1][1] {
                    for i in r[0][0]..=r[0][1] {
                        let centre = lo
                            + Vec3::new(
                                (i as f64 - 0.5) * cells.h.x,
                                (j as f64 - 0.5) * cells.h.y,
                                (k as f64 - 0.5) * cells.h.z,
                            );
                        if tri_box_overlap(centre, 0.5 * cells.h + Vec3::splat(buffer), &f.c) {
                            bins[i + g[0] * (j + g[1] * k)].push(id as u32);
                        }
                    }
                }
            }
        }
        DesGrid { cells, bins, clearance_sq: (1.05 * max_radius).powi(2) }
    }

    /// MFIX's test of a seeded site `p` whose fluid cell spans [west, east] (its faces on each
    /// axis): true if it is in front of the plane of every facet binned in the DES cells that
    /// hold those faces, and farther than 1.05 largest radii from each plane.
    pub(super) fn clear(&self, p: Vec3, west: Vec3, east: Vec3, facets: &[Facet]) -> bool {
        let g = [self.cells.n[0] + 2, self.cells.n[1] + 2, self.cells.n[2] + 2];
        let at = |x: f64, k: usize| {
            (((x - self.cells.lo[k]) / self.cells.h[k]).floor() + 1.0).clamp(0.0, (g[k] - 1) as f64) as usize
        };
        for k in at(west.z, 2)..=at(east.z, 2) {
            for j in at(west.y, 1)..=at(east.y, 1) {
                for i in at(west.x, 0)..=at(east.x, 0) {
                    for &id in &self.bins[i + g[0] * (j + g[1] * k)] {
                        let f = &facets[id as usize];
                        // Where the line from p along the normal meets the facet's plane.
                        let t = (f.c[0] - p).dot(f.n);
                        if t > 0.0 || t * t <= self.clearance_sq {
                            return false;
                        }
                    }
                }
            }
        }
        true
    }
}

impl FluidGrid {
    /// The faces of the fluid cell holding `p`: its west-south-bottom and east-north-top
    /// corners.
    pub(super) fn faces_of(&self, p: Vec3) -> Option<(Vec3, Vec3)> {
        let c = self.cell_of(p)?;
        let a = self.cells.corner(c);
        Some((a, a + self.cells.h))
    }
}

/// True if the triangle `t` and the box of centre `centre` and half-sizes `half` overlap, by
/// the separating-axis theorem: the box's three axes, the triangle's normal and the nine
/// cross products of their edges.
pub(super) fn tri_box_overlap(centre: Vec3, half: Vec3, t: &[Vec3; 3]) -> bool {
    let v = [t[0] - centre, t[1] - centre, t[2] - centre];
    let separated = |axis: Vec3| -> bool {
        let p = [v[0].dot(axis), v[1].dot(axis), v[2].dot(axis)];
        let r = half.x * axis.x.abs() + half.y * axis.y.abs() + half.z * axis.z.abs();
        p[0].min(p[1]).min(p[2]) > r || p[0].max(p[1]).max(p[2]) < -r
    };
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        if separated(axis) {
            return false;
        }
    }
    let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let normal = e[0].cross(e[1]);
    if normal.length_squared() > 0.0 && separated(normal) {
        return false;
    }
    for edge in e {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            let a = edge.cross(axis);
            if a.length_squared() > 0.0 && separated(a) {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plane y = 0.3 (fluid above) crossing a 1 m box of 4×4×4 cells: the cells of the layer
    /// [0.25, 0.5) hold 6 of their 8 layers of sample points above the plane (0.8 of their
    /// volume is), those below none, those above all.
    #[test]
    fn a_plane_cuts_the_cells_by_its_height() {
        let l = 1.0;
        let tri = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
            let c = [Vec3::from_array(a), Vec3::from_array(b), Vec3::from_array(c)];
            let n = (c[1] - c[0]).cross(c[2] - c[0]).normalize();
            Facet { c, n, lo: c[0].min(c[1]).min(c[2]), hi: c[0].max(c[1]).max(c[2]) }
        };
        let y = 0.3;
        let facets =
            vec![tri([0.0, y, 0.0], [0.0, y, l], [l, y, l]), tri([0.0, y, 0.0], [l, y, l], [l, y, 0.0])];
        assert!(facets[0].n.y > 0.0);
        let grid = FluidGrid::new(Vec3::ZERO, Vec3::splat(l), [4, 4, 4], &facets);
        assert_eq!(grid.fraction_at(Vec3::new(0.5, 0.1, 0.5)), 0.0);
        // 0.3 is 0.2 of the way up the cell [0.25, 0.5]: 8 samples at (s + ½)/8, of which
        // the ones above 0.2 (s ≥ 2) are fluid: 6/8 = 0.75 of the samples.
        assert_eq!(grid.fraction_at(Vec3::new(0.5, 0.3, 0.5)), 0.75);
        assert_eq!(grid.fraction_at(Vec3::new(0.5, 0.9, 0.5)), 1.0);
        let v = grid.fluid_volume([[0, 4], [0, 4], [0, 4]], 0.0);
        assert!((v - (0.5 + 0.25 * 0.75)).abs() < 1e-12, "{v}");
        assert!(!grid.wet(Vec3::new(0.5, 0.1, 0.5)) && grid.wet(Vec3::new(0.5, 0.26, 0.5)));
    }

    #[test]
    fn triangles_and_boxes_overlap_as_the_separating_axes_say() {
        let t = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        assert!(tri_box_overlap(Vec3::new(0.2, 0.2, 0.0), Vec3::splat(0.1), &t));
        // Beyond the hypotenuse x + y = 1: the box [0.6, 0.8]² is clear of it.
        assert!(!tri_box_overlap(Vec3::new(0.7, 0.7, 0.0), Vec3::splat(0.1), &t));
        assert!(tri_box_overlap(Vec3::new(0.55, 0.55, 0.0), Vec3::splat(0.1), &t));
        // Above the plane z = 0.
        assert!(!tri_box_overlap(Vec3::new(0.2, 0.2, 0.2), Vec3::splat(0.1), &t));
    }
}
