//! Triangles binned in a uniform grid, so that the triangles near a particle are found in time
//! that depends on the triangles near it, not on the mesh's size.

use super::Mesh;
use super::contact::closest_point_with_normal;
use crate::math::Vec3;

/// At most this many cells a triangle (on average), or [`MIN_CELL_BUDGET`] cells: coarser
/// cells where the mesh's bounding box holds few triangles (a large plate of two triangles),
/// so the grid's memory stays proportional to the mesh, but never coarser than a small fixed
/// budget needs (a coarse cell hands every query the triangles of a large region).
const CELLS_PER_TRIANGLE: usize = 8;
/// The cells a grid may always have (256 KB of cell starts).
const MIN_CELL_BUDGET: usize = 1 << 16;

/// Which triangles a query of [`TriangleGrid::near_with_distances`] has met: a mark per
/// triangle, the query's number, so that a triangle listed in several cells is tested once
/// without sorting.
#[derive(Debug, Clone, Default)]
pub struct NearScratch {
    seen: Vec<u32>,
    epoch: u32,
}

impl NearScratch {
    /// Heap bytes.
    pub fn heap_bytes(&self) -> usize {
        self.seen.capacity() * 4
    }

    /// The next query's mark, for a mesh of `n` triangles.
    fn next(&mut self, n: usize) -> u32 {
        if self.seen.len() != n || self.epoch == u32::MAX {
            self.seen.clear();
            self.seen.resize(n, 0);
            self.epoch = 0;
        }
        self.epoch += 1;
        self.epoch
    }
}

/// A mesh's triangles binned in cubic cells: each cell lists the triangles whose bounding
/// boxes meet it.
#[derive(Debug, Clone)]
pub struct TriangleGrid {
    lo: Vec3,
    cell: f64,
    dims: [usize; 3],
    /// Triangles of cell c: `triangles[start[c]..start[c + 1]]`, ascending.
    start: Vec<u32>,
    triangles: Vec<u32>,
}

impl TriangleGrid {
    /// Bins `mesh`'s triangles in cells of side at least `cell` (m; the neighbour cut-off),
    /// coarser where the mesh is large and has few triangles.
    pub fn new(mesh: &Mesh, cell: f64) -> TriangleGrid {
        let all: Vec<u32> = (0..mesh.triangle_count() as u32).collect();
        TriangleGrid::of(mesh, cell, &all, mesh.bounds())
    }

    /// [`new`](Self::new) for the triangles whose bounding boxes meet the box `lo`–`hi` alone
    /// (a rank's part of the domain, widened by the reach of its particles): the others are
    /// never near.
    pub fn within(mesh: &Mesh, cell: f64, lo: Vec3, hi: Vec3) -> TriangleGrid {
        let meets = |t: u32| {
            let [a, b, c] = mesh.corners(t);
            (a.min(b).min(c)).cmple(hi).all() && (a.max(b).max(c)).cmpge(lo).all()
        };
        let kept: Vec<u32> = (0..mesh.triangle_count() as u32).filter(|&t| meets(t)).collect();
        let bounds =
            kept.iter().fold((Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)), |(l, h), &t| {
                let [a, b, c] = mesh.corners(t);
                (l.min(a.min(b).min(c)), h.max(a.max(b).max(c)))
            });
        let bounds = if kept.is_empty() { (Vec3::ZERO, Vec3::ZERO) } else { bounds };
        TriangleGrid::of(mesh, cell, &kept, bounds)
    }

    /// The triangles `kept` of `mesh`, which lie within `lo`–`hi`, binned.
    fn of(mesh: &Mesh, cell: f64, kept: &[u32], (lo, hi): (Vec3, Vec3)) -> TriangleGrid {
        let span = (hi - lo).max(Vec3::splat(0.0));
        let budget = (CELLS_PER_TRIANGLE * kept.len()).max(MIN_CELL_BUDGET) as f64;
        let mut cell = if cell.is_finite() && cell > 0.0 { cell } else { span.max_element().max(1.0) };
        let count = |c: f64| span.to_array().map(|s| (s / c).floor() as usize + 1);
        while count(cell).iter().map(|&n| n as f64).product::<f64>() > budget {
            cell *= 2.0;
        }
        let dims = count(cell);
        let n_cells = dims[0] * dims[1] * dims[2];
        let index = |c: [usize; 3]| (c[2] * dims[1] + c[1]) * dims[0] + c[0];
        let cell_of = |x: Vec3| {
            let r = ((x - lo) / cell).to_array();
            std::array::from_fn(|k| (r[k].floor().max(0.0) as usize).min(dims[k] - 1))
        };
        // Counting sort of (cell, triangle) pairs.
        let boxes: Vec<([usize; 3], [usize; 3])> = kept
            .iter()
            .map(|&t| {
                let [a, b, c] = mesh.corners(t);
                (cell_of(a.min(b).min(c)), cell_of(a.max(b).max(c)))
            })
            .collect();
        let each_cell = |(l, h): &([usize; 3], [usize; 3]), f: &mut dyn FnMut(usize)| {
            for z in l[2]..=h[2] {
                for y in l[1]..=h[1] {
                    for x in l[0]..=h[0] {
                        f(index([x, y, z]));
                    }
                }
            }
        };
        let mut start = vec![0u32; n_cells + 1];
        for b in &boxes {
            each_cell(b, &mut |c| start[c + 1] += 1);
        }
        for c in 0..n_cells {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut triangles = vec![0u32; start[n_cells] as usize];
        for (&t, b) in kept.iter().zip(&boxes) {
            each_cell(b, &mut |c| {
                triangles[fill[c] as usize] = t;
                fill[c] += 1;
            });
        }
        TriangleGrid { lo, cell, dims, start, triangles }
    }

    /// Appends to `out`, ascending and each once, the triangles of `mesh` (the mesh this grid
    /// was made of) closer to `centre` than `reach` (m). `out` is cleared first.
    pub fn near(&self, mesh: &Mesh, centre: Vec3, reach: f64, out: &mut Vec<u32>) {
        let mut with = Vec::new();
        // A triangle listed in several cells is tested each time: no marks to keep.
        self.scan(mesh, centre, reach, |_| true, &mut with);
        out.clear();
        out.extend(with.iter().map(|&(t, _)| t));
        out.sort_unstable();
        out.dedup();
    }

    /// As [`near`](Self::near), each triangle with its distance from `centre` (m), in no
    /// particular order; `scratch` marks the triangles already met (kept between calls).
    pub fn near_with_distances(
        &self,
        mesh: &Mesh,
        centre: Vec3,
        reach: f64,
        scratch: &mut NearScratch,
        out: &mut Vec<(u32, f64)>,
    ) {
        let epoch = scratch.next(mesh.triangle_count());
        let seen = &mut scratch.seen;
        let fresh = |t: u32| std::mem::replace(&mut seen[t as usize], epoch) != epoch;
        self.scan(mesh, centre, reach, fresh, out);
    }

    /// Fills `out` with the triangles of the cells within `reach` of `centre` that `fresh`
    /// lets through and that are closer than `reach`, each with its distance.
    fn scan(
        &self,
        mesh: &Mesh,
        centre: Vec3,
        reach: f64,
        mut fresh: impl FnMut(u32) -> bool,
        out: &mut Vec<(u32, f64)>,
    ) {
        out.clear();
        let lo = ((centre - Vec3::splat(reach) - self.lo) / self.cell).to_array();
        let hi = ((centre + Vec3::splat(reach) - self.lo) / self.cell).to_array();
        let mut range = [(0usize, 0usize); 3];
        for k in 0..3 {
            // Outside the grid on an axis (or not a number): no triangle is near.
            if !(hi[k] >= 0.0 && lo[k] < self.dims[k] as f64) {
                return;
            }
            range[k] = (lo[k].max(0.0) as usize, (hi[k] as usize).min(self.dims[k] - 1));
        }
        let normals = mesh.normals();
        for z in range[2].0..=range[2].1 {
            for y in range[1].0..=range[1].1 {
                for x in range[0].0..=range[0].1 {
                    let c = (z * self.dims[1] + y) * self.dims[0] + x;
                    for &t in &self.triangles[self.start[c] as usize..self.start[c + 1] as usize] {
                        if !fresh(t) {
                            continue;
                        }
                        let corners = mesh.corners(t);
                        let n = normals[t as usize];
                        // The distance to the triangle's plane bounds the distance to the
                        // triangle: most triangles of the cells are out of reach of their plane.
                        if (centre - corners[0]).dot(n).abs() >= reach {
                            continue;
                        }
                        let q = closest_point_with_normal(centre, corners, n).point;
                        let d2 = (centre - q).length_squared();
                        if d2 < reach * reach {
                            out.push((t, d2.sqrt()));
                        }
                    }
                }
            }
        }
    }

    /// The triangles binned (each once).
    pub fn triangle_count(&self) -> usize {
        let mut t = self.triangles.clone();
        t.sort_unstable();
        t.dedup();
        t.len()
    }

    /// Heap bytes of the grid.
    pub fn heap_bytes(&self) -> usize {
        (self.start.capacity() + self.triangles.capacity()) * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{MeshTransform, closest_point_on_triangle};

    /// A flat n×n grid of squares (two triangles each) on z = 0 over [0, 1]².
    fn floor(n: usize) -> Mesh {
        let mut v = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                v.push(Vec3::new(i as f64 / n as f64, j as f64 / n as f64, 0.0));
            }
        }
        let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                t.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                t.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        Mesh::from_indexed("floor", &v, &t, &MeshTransform::default()).expect("a valid floor")
    }

    /// The grid finds exactly the triangles a search over all of them finds.
    #[test]
    fn near_triangles_are_those_of_a_full_search() {
        let mesh = floor(20);
        for cell in [0.01, 0.05, 0.3, 5.0] {
            let grid = TriangleGrid::new(&mesh, cell);
            let mut got = Vec::new();
            for k in 0..200 {
                let f = |s: u64| ((k as u64 * 2654435761 + s * 40503) % 1000) as f64 / 1000.0;
                let c = Vec3::new(1.2 * f(1) - 0.1, 1.2 * f(2) - 0.1, 0.2 * f(3) - 0.1);
                let reach = 0.01 + 0.1 * f(4);
                grid.near(&mesh, c, reach, &mut got);
                let want: Vec<u32> = (0..mesh.triangle_count() as u32)
                    .filter(|&t| {
                        let q = closest_point_on_triangle(c, mesh.corners(t)).point;
                        (c - q).length_squared() < reach * reach
                    })
                    .collect();
                assert_eq!(got, want, "cell {cell}, centre {c}, reach {reach}");
            }
        }
    }

    /// A large plate of two triangles gets few cells, whatever the cell asked for.
    #[test]
    fn cells_stay_proportional_to_the_triangles() {
        let mesh = floor(1);
        let grid = TriangleGrid::new(&mesh, 1e-6);
        assert!(grid.dims.iter().product::<usize>() <= MIN_CELL_BUDGET);
    }
}
