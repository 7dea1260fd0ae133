//! From a list of triangles to a [`Mesh`]: the load-time transform, welding, validation and
//! topology.
//!
//! ## Welding
//! Every corner is transformed first; corners whose transformed coordinates are equal, bit
//! for bit (with −0 equal to +0), become one vertex. STL repeats each vertex in every facet that
//! has it, and CAD exporters write the same numbers each time, so exact equality joins them
//! without a tolerance that could also join distinct vertices of a fine mesh. A file whose
//! repeated vertices differ in their last digits is not joined: its triangles then have open
//! edges between them (still a valid, open mesh, but one whose seams a sphere can feel as
//! edges).
//!
//! ## Validation
//! Checked in this order, the first problem found reported with the file, the triangle's index
//! and (for a text file) its line: the transform's values; an empty mesh; vertex indices; a
//! corner that is not finite after the transform; a degenerate triangle (area below
//! [`DEGENERATE_AREA`] times its longest edge squared, with coincident welded corners
//! included); a duplicate triangle (the same three vertices in any order); an edge with more
//! than two triangles; two triangles running along a shared edge in the same direction (their
//! windings, hence normals, disagree).
//!
//! A non-manifold edge (three or more triangles) is refused. Such an edge is in practice a bad
//! export (two solids touching along an edge, or internal faces left inside a solid, whose
//! hidden triangles would give spurious contacts); across it a triangle's neighbour, the
//! orientation check and the edge's [`EdgeKind`] are all undefined. Pieces that meet along
//! an edge on purpose (a baffle welded to a plate) load as separate meshes.

use super::{Edge, EdgeKind, FLAT_COS, Location, Mesh, MeshError, MeshTransform, NONE};
use crate::math::Vec3;
use glam::DMat3;
use std::collections::HashMap;
use std::collections::hash_map::Entry;

/// A triangle is degenerate when its area is below this times its longest edge squared (a
/// height below 2e-12 of its length): some 4 000 times the rounding of the cross product
/// that gives the area, so that rounding never decides it, and far below the slivers a mesher
/// makes on purpose.
pub const DEGENERATE_AREA: f64 = 1e-12;

/// The most triangles a mesh may have: its edges (at most three per triangle) must be
/// numbered in `u32` below the "none" marker.
pub const MAX_TRIANGLES: usize = (u32::MAX / 3 - 1) as usize;

impl Mesh {
    /// A mesh from indexed triangles (e.g. one generated in code): `triangles` index
    /// `vertices` (file units). The transform is applied, vertices welded and the mesh
    /// validated as for a file; `name` names it in messages.
    pub fn from_indexed(
        name: &str,
        vertices: &[Vec3],
        triangles: &[[u32; 3]],
        transform: &MeshTransform,
    ) -> Result<Mesh, MeshError> {
        build(name, vertices, triangles, None, transform)
    }
}

/// The mesh of `triangles` over `positions` (file units), `lines[t]` the line triangle t came
/// from, if from a text file.
pub(crate) fn build(
    name: &str,
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    lines: Option<&[u32]>,
    transform: &MeshTransform,
) -> Result<Mesh, MeshError> {
    let file = || name.to_string();
    let at = |t: u32| Location { triangle: t, line: lines.map(|l| l[t as usize]) };
    let rotation = rotation(transform).map_err(|reason| MeshError::Transform { file: file(), reason })?;
    if triangles.is_empty() {
        return Err(MeshError::Empty { file: file() });
    }
    check_count(name, triangles.len())?;
    for (t, tri) in (0u32..).zip(triangles) {
        if let Some(&v) = tri.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(MeshError::BadIndex {
                file: file(),
                at: at(t),
                index: v.into(),
                count: positions.len(),
            });
        }
    }

    // Transform and weld.
    let mut vertices: Vec<Vec3> = Vec::new();
    let mut index_of: HashMap<[u64; 3], u32> = HashMap::new();
    let mut welded = Vec::with_capacity(triangles.len());
    for (t, tri) in (0u32..).zip(triangles) {
        let mut w = [0u32; 3];
        for k in 0..3 {
            let p = rotation * (transform.scale * positions[tri[k] as usize]) + transform.translation;
            if !p.is_finite() {
                return Err(MeshError::NonFinite { file: file(), at: at(t), corner: k, position: p });
            }
            // Adding +0 turns −0 into +0, so that the two weld.
            let key = (p + Vec3::ZERO).to_array().map(f64::to_bits);
            w[k] = *index_of.entry(key).or_insert_with(|| {
                vertices.push(p);
                (vertices.len() - 1) as u32
            });
        }
        if transform.flip_normals {
            w.swap(1, 2);
        }
        welded.push(w);
    }

    // Each kept triangle's index in the file.
    let mut orig: Vec<u32> = Vec::with_capacity(welded.len());
    let mut kept = Vec::with_capacity(welded.len());
    for (t, w) in (0u32..).zip(&welded) {
        let c = w.map(|v| vertices[v as usize]);
        let (m, longest2) = area_vector(c);
        let area = 0.5 * m.length();
        // (NaN only if the coordinates are so large that their squares overflow.)
        if area <= DEGENERATE_AREA * longest2 || area.is_nan() {
            if transform.skip_degenerate && !area.is_nan() {
                continue;
            }
            return Err(MeshError::Degenerate { file: file(), at: at(t), area, longest: longest2.sqrt() });
        }
        orig.push(t);
        kept.push(*w);
    }
    let skipped = welded.len() - kept.len();
    if kept.is_empty() {
        return Err(MeshError::Empty { file: file() });
    }
    let welded = kept;
    let at = |t: u32| {
        let o = orig[t as usize];
        Location { triangle: o, line: lines.map(|l| l[o as usize]) }
    };

    let mut first_with: HashMap<[u32; 3], u32> = HashMap::with_capacity(welded.len());
    for (t, w) in (0u32..).zip(&welded) {
        let mut key = *w;
        key.sort_unstable();
        if let Some(&first) = first_with.get(&key) {
            return Err(MeshError::Duplicate { file: file(), at: at(t), first: at(first) });
        }
        first_with.insert(key, t);
    }

    // Edges, each with the triangles on it.
    let mut edges: Vec<Edge> = Vec::new();
    let mut edge_of: HashMap<(u32, u32), u32> = HashMap::with_capacity(welded.len() * 3 / 2 + 3);
    let mut triangle_edges = Vec::with_capacity(welded.len());
    for (t, w) in (0u32..).zip(&welded) {
        let mut ids = [0u32; 3];
        for k in 0..3 {
            let (a, b) = (w[k], w[(k + 1) % 3]);
            ids[k] = match edge_of.entry((a.min(b), a.max(b))) {
                Entry::Vacant(slot) => {
                    let id = edges.len() as u32;
                    edges.push(Edge { vertices: [a, b], triangles: [t, NONE], kind: EdgeKind::Boundary });
                    *slot.insert(id)
                }
                Entry::Occupied(slot) => {
                    let id = *slot.get();
                    let e = &mut edges[id as usize];
                    let (from, to) = (vertices[a as usize], vertices[b as usize]);
                    if e.triangles[1] != NONE {
                        return Err(MeshError::NonManifold {
                            file: file(),
                            at: at(t),
                            first: at(e.triangles[0]),
                            second: at(e.triangles[1]),
                            from,
                            to,
                        });
                    }
                    if e.vertices == [a, b] {
                        return Err(MeshError::Orientation {
                            file: file(),
                            at: at(t),
                            other: at(e.triangles[0]),
                            from,
                            to,
                        });
                    }
                    e.triangles[1] = t;
                    id
                }
            };
        }
        triangle_edges.push(ids);
    }

    let normals: Vec<Vec3> = welded.iter().map(|w| unit_normal(w.map(|v| vertices[v as usize]))).collect();
    let neighbours = (0u32..)
        .zip(&triangle_edges)
        .map(|(t, ids)| {
            ids.map(|e| {
                let tris = edges[e as usize].triangles;
                if tris[0] == t { tris[1] } else { tris[0] }
            })
        })
        .collect();
    for e in &mut edges {
        if e.triangles[1] == NONE {
            continue;
        }
        let (na, nb) = (normals[e.triangles[0] as usize], normals[e.triangles[1] as usize]);
        e.kind = if na.dot(nb) > FLAT_COS {
            EdgeKind::Flat
        } else {
            // The first triangle runs a → b: the surface turns down past the edge (a ridge)
            // when n_a × n_b points along a → b.
            let along = vertices[e.vertices[1] as usize] - vertices[e.vertices[0] as usize];
            if na.cross(nb).dot(along) > 0.0 { EdgeKind::Convex } else { EdgeKind::Concave }
        };
    }

    // Each vertex's triangles, in compressed rows (ascending, as the triangles are walked in
    // order).
    let mut vertex_offsets = vec![0u32; vertices.len() + 1];
    for w in &welded {
        for &v in w {
            vertex_offsets[v as usize + 1] += 1;
        }
    }
    for v in 0..vertices.len() {
        vertex_offsets[v + 1] += vertex_offsets[v];
    }
    let mut fill = vertex_offsets.clone();
    let mut vertex_triangles = vec![0u32; welded.len() * 3];
    for (t, w) in (0u32..).zip(&welded) {
        for &v in w {
            vertex_triangles[fill[v as usize] as usize] = t;
            fill[v as usize] += 1;
        }
    }
    let mut flat_vertices = vec![true; vertices.len()];
    for e in edges.iter().filter(|e| e.kind != EdgeKind::Flat) {
        flat_vertices[e.vertices[0] as usize] = false;
        flat_vertices[e.vertices[1] as usize] = false;
    }

    let lo = vertices.iter().fold(Vec3::INFINITY, |m, &p| m.min(p));
    let hi = vertices.iter().fold(Vec3::NEG_INFINITY, |m, &p| m.max(p));
    let extent = lo.abs().max(hi.abs()).max_element();
    let corner_table = welded.iter().map(|w| w.map(|v| vertices[v as usize])).collect();
    Ok(Mesh {
        name: name.to_string(),
        vertices,
        corner_table,
        triangles: welded,
        normals,
        triangle_edges,
        neighbours,
        edges,
        vertex_offsets,
        vertex_triangles,
        flat_vertices,
        lo,
        hi,
        extent,
        skipped: skipped as u32,
    })
}

/// Refuses a mesh of more than [`MAX_TRIANGLES`] triangles.
pub(crate) fn check_count(name: &str, triangles: usize) -> Result<(), MeshError> {
    if triangles > MAX_TRIANGLES {
        return Err(MeshError::TooLarge { file: name.to_string(), triangles, limit: MAX_TRIANGLES });
    }
    Ok(())
}

/// The transform's rotation matrix, or what is wrong with its values.
fn rotation(t: &MeshTransform) -> Result<DMat3, String> {
    if !(t.scale.is_finite() && t.scale > 0.0) {
        return Err(format!("scale = {} must be finite and positive", t.scale));
    }
    if let Some(a) = t.rotation_deg.iter().find(|a| !a.is_finite()) {
        return Err(format!("rotation angle {a}° is not finite"));
    }
    if !t.translation.is_finite() {
        return Err(format!("translation {} is not finite", t.translation));
    }
    let [(sx, cx), (sy, cy), (sz, cz)] = t.rotation_deg.map(sin_cos_degrees);
    let rx = DMat3::from_cols(Vec3::X, Vec3::new(0.0, cx, sx), Vec3::new(0.0, -sx, cx));
    let ry = DMat3::from_cols(Vec3::new(cy, 0.0, -sy), Vec3::Y, Vec3::new(sy, 0.0, cy));
    let rz = DMat3::from_cols(Vec3::new(cz, sz, 0.0), Vec3::new(-sz, cz, 0.0), Vec3::Z);
    Ok(rz * ry * rx)
}

/// (sin, cos) of an angle in degrees, exact for multiples of 90°.
fn sin_cos_degrees(deg: f64) -> (f64, f64) {
    let r = deg.rem_euclid(360.0);
    if r == 0.0 {
        (0.0, 1.0)
    } else if r == 90.0 {
        (1.0, 0.0)
    } else if r == 180.0 {
        (0.0, -1.0)
    } else if r == 270.0 {
        (-1.0, 0.0)
    } else {
        r.to_radians().sin_cos()
    }
}

/// Twice the triangle's area vector, (b − a) × (c − a), and its longest edge squared. The
/// cross product is taken of the two shorter edges (those at the corner opposite the longest),
/// whose rounding error, of order ε times the product of their lengths, is the smallest of the
/// three choices: what keeps a sliver's normal as good as its coordinates allow.
pub(crate) fn area_vector([a, b, c]: [Vec3; 3]) -> (Vec3, f64) {
    let (e0, e1, e2) = (b - a, c - b, a - c);
    let (l0, l1, l2) = (e0.length_squared(), e1.length_squared(), e2.length_squared());
    // e0 × e1 = e1 × e2 = e2 × e0 = (b − a) × (c − a).
    if l0 >= l1 && l0 >= l2 {
        (e1.cross(e2), l0)
    } else if l1 >= l2 {
        (e2.cross(e0), l1)
    } else {
        (e0.cross(e1), l2)
    }
}

/// The unit normal of a non-degenerate triangle. For a triangle in a coordinate plane it is
/// exactly the axis (the cross product then has two exact zeros, and √(z²) = |z| in IEEE
/// arithmetic).
pub(crate) fn unit_normal(corners: [Vec3; 3]) -> Vec3 {
    let m = area_vector(corners).0;
    m / m.length()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_turns_are_exact() {
        for (deg, want) in [(0.0, (0.0, 1.0)), (90.0, (1.0, 0.0)), (-90.0, (-1.0, 0.0)), (540.0, (0.0, -1.0))]
        {
            assert_eq!(sin_cos_degrees(deg), want, "{deg}°");
        }
        let (s, c) = sin_cos_degrees(30.0);
        assert!((s - 0.5).abs() < 1e-15 && (c - 0.75f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn the_area_vector_is_the_same_from_any_corner() {
        let t = [Vec3::new(0.1, 0.2, 0.3), Vec3::new(1.7, -0.4, 0.9), Vec3::new(0.5, 2.0, -1.1)];
        let want = (t[1] - t[0]).cross(t[2] - t[0]);
        for k in 0..3 {
            let turned = [t[k], t[(k + 1) % 3], t[(k + 2) % 3]];
            // The same vector up to the rounding of a cross product of O(1) sides.
            assert!((area_vector(turned).0 - want).length() < 1e-14);
        }
        assert_eq!(area_vector(t).1, (t[2] - t[1]).length_squared());
    }
}
