//! Sphere–mesh contact geometry: the closest point of a point on a triangle, and every contact
//! of one sphere with a mesh, each particle–surface contact counted once.
//!
//! ## One contact per touching surface
//! A sphere near a mesh is within reach of several triangles at once, and the closest points
//! of neighbouring triangles often lie on the edge or vertex they share. Counting every
//! triangle in reach would multiply the force at every seam of a flat floor. So a contact is
//! made with a *primitive* of the mesh — a face (a triangle's interior), an edge or a vertex —
//! and [`sphere_contacts`] keeps one contact per primitive and only the primitives that are
//! really touched:
//!
//! 1. Each candidate triangle gives its closest point to the centre and its region
//!    ([`closest_point_on_triangle`]), i.e. a primitive; one no farther than the radius is a
//!    candidate contact (a sphere exactly touching, at overlap 0, is in contact, as with a
//!    plane wall). A primitive reported by several triangles counts once; its geometry
//!    is computed from the primitive itself, not from the triangle that reported it.
//! 2. Face contacts are kept. An edge contact is kept only if no triangle on that edge has a
//!    face contact; a vertex contact only if no triangle around the vertex has a face contact
//!    and no edge of the vertex an edge contact (the rule of Kremmer & Favier 2001 and of Hu
//!    et al.).
//! 3. An edge or vertex contact is kept only if the centre lies in the primitive's normal cone
//!    ([`CONE_TOLERANCE`]): its closest point is then a local minimum of the distance over the
//!    whole surface, not only over the triangle that reported it. For an edge that is
//!    (c − q)·u ≤ 0 for the in-plane direction u into each triangle on the edge, for a vertex
//!    v it is (c − v)·(w − v) ≤ 0 for each edge v–w. Rule 2 alone is not enough: a sphere
//!    over the ridge of a roof whose slopes are two triangles each also touches the slopes'
//!    diagonals (each the closest part of the triangle beyond it, whose neighbour reports the
//!    ridge, not a face), and a sphere larger than the triangles of a fine floor touches every
//!    edge and vertex in its reach.
//! 4. Contacts that coincide (contact points and normals equal within [`MERGE_TOLERANCE`])
//!    are one: the first in the output order (below) is kept. On a flat patch a centre exactly
//!    over an edge or a vertex is, by rounding, in the face region of two triangles, or of one
//!    and in an edge or vertex region of another; their plane contacts are the same but for
//!    the rounding of their normals.
//!
//! An edge between coplanar triangles ([`EdgeKind::Flat`]), or a vertex all of whose edges are
//! flat, is touched as the plane of its lowest-index triangle: on a flat floor every contact
//! then has the plane's normal and overlap, to the rounding of one subtraction.
//!
//! ## Sides, and a centre on the surface
//! The contact normal points from the contact point to the centre, on whichever side of the
//! surface the centre is: a sphere may touch an open sheet from its back. As with any thin
//! wall, a sphere whose centre crosses a sheet (a step too long, an overlap beyond its radius)
//! is then pushed out on the far side. A centre exactly on the surface (distance 0) takes the
//! normal of the primitive's triangle ([`MeshContact::triangle`]) on its normal side, so that
//! no direction is 0/0; so does a centre on an edge or at a vertex but for the rounding of the
//! coordinates ([`ROUNDING`] of their magnitude), where c − q is rounding noise.
//!
//! ## Order
//! The contacts of one call are sorted by [`Primitive`] (faces, then edges, then vertices, each
//! by id): a function of the mesh, the centre and the radius and of the *set* of candidate
//! triangles, not of their order or repetitions. Contacts are computed in `f64` with no
//! order-dependent sums, so the same inputs give the same bits.

use super::build::unit_normal;
use super::{EdgeKind, Mesh};
use crate::math::Vec3;

/// Where on a triangle its closest point to a point lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Region {
    /// Inside the triangle: the projection onto its plane.
    Face,
    /// On side k (0..3), joining corners k and (k + 1) mod 3.
    Edge(u8),
    /// At corner k (0..3).
    Vertex(u8),
}

/// The closest point of a triangle to a point, and the region it lies in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint {
    /// The point on the triangle, m.
    pub point: Vec3,
    /// Where it lies.
    pub region: Region,
}

/// A part of the mesh a sphere touches. The derived order (faces, edges, vertices, each by
/// id) is the order of [`sphere_contacts`]'s output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Primitive {
    /// The interior of a triangle.
    Face(u32),
    /// An edge, by id.
    Edge(u32),
    /// A vertex, by id.
    Vertex(u32),
}

/// One contact of a sphere with a mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshContact {
    /// Unit normal from the contact point towards the sphere's centre.
    pub normal: Vec3,
    /// Overlap δ = R − distance, m (≥ 0).
    pub overlap: f64,
    /// The contact point on the mesh, m.
    pub point: Vec3,
    /// Distance from the contact point to the centre, m.
    pub distance: f64,
    /// The primitive touched.
    pub primitive: Primitive,
    /// The triangle that owns the contact, e.g. to key its tangential history: the face's own,
    /// or the lowest-index triangle on the edge or around the vertex.
    pub triangle: u32,
}

/// The tolerance of the normal-cone test (rule 3 of the [module doc](self)), as a fraction of
/// the centre's distance, plus [`ROUNDING`] times the mesh's coordinate magnitude: an edge or
/// vertex is kept while (c − q)·û ≤ `CONE_TOLERANCE`·|c − q| + `ROUNDING`·|x|max. Well above
/// the rounding of the test itself (its directions are good to about ε·L/h for a triangle of
/// length L and height h, 2e-10 for a 1e-6 sliver), so that a centre exactly over a seam is not
/// refused by every triangle at it.
pub const CONE_TOLERANCE: f64 = 1e-9;

/// Two contacts coincide (rule 4 of the [module doc](self)) when their normals are within
/// `MERGE_TOLERANCE` and their points within `MERGE_TOLERANCE` times the larger distance plus
/// 10·[`ROUNDING`]·|x|max. Above the angle within which the mesh calls two triangles coplanar
/// ([`FLAT_COS`](super::FLAT_COS), 1.4e-5 rad), by which the plane contacts of neighbours on a
/// flat patch may differ (on a tilted floor of slivers their normals differ by 1e-8 and more),
/// and far above what the cone test lets through on either side of a region's border. Two
/// contacts that close are one place on one surface.
pub const MERGE_TOLERANCE: f64 = 2e-5;

/// The rounding of coordinates, relative to their magnitude, that the tolerances allow for:
/// some 5 000 times ε.
pub const ROUNDING: f64 = 1e-12;

/// The point of triangle `corners` closest to `p`, and its region (Ericson, *Real-Time
/// Collision Detection*, §5.1.5: the Voronoi regions of the corners, then of the sides, are
/// tested; a point in none of them projects into the face). `corners` must not be degenerate.
///
/// Two changes make it robust for slivers. The side tests use the barycentric numerators as
/// triple products with the unit normal n, e.g. n·((b − a) × (p − a)) for side ab (the signed
/// in-plane distance of p from the side, times the side's length), where Ericson forms them
/// as differences of products of dot products, (ab·ap)(ac·bp) − (ab·bp)(ac·ap): equal up to
/// the factor |(b − a) × (c − a)|, but the latter loses about ε·|p − a|² to cancellation,
/// which misplaces points up to ε·|p − a|²/h from a side of a triangle of height h; the triple
/// product misplaces them by a few ε·|p − a| only. And in the face region the point is the
/// projection p − ((p − a)·n)·n, free of the division by the squared area of the barycentric
/// form. The normal is taken from the triangle's two shorter sides (as the mesh's normals
/// are), and is exact for a triangle in a coordinate plane: there the projection keeps p's
/// other two coordinates bit for bit and puts the third on the plane exactly.
pub fn closest_point_on_triangle(p: Vec3, corners: [Vec3; 3]) -> ClosestPoint {
    closest_point_with_normal(p, corners, unit_normal(corners))
}

/// [`closest_point_on_triangle`] with the triangle's unit normal `n` given (the mesh's own).
pub(crate) fn closest_point_with_normal(p: Vec3, [a, b, c]: [Vec3; 3], n: Vec3) -> ClosestPoint {
    let at = |point, region| ClosestPoint { point, region };
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return at(a, Region::Vertex(0));
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return at(b, Region::Vertex(1));
    }
    // The barycentric numerators of c, b and a (see above), each zero on the opposite side.
    let vc = n.dot(ab.cross(ap));
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return at(a + (d1 / (d1 - d3)) * ab, Region::Edge(0));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return at(c, Region::Vertex(2));
    }
    let vb = n.dot((a - c).cross(cp));
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return at(a + (d2 / (d2 - d6)) * ac, Region::Edge(2));
    }
    let va = n.dot((c - b).cross(bp));
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return at(b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b), Region::Edge(1));
    }
    at(p - ap.dot(n) * n, Region::Face)
}

/// Appends to `out` every contact of the sphere (`centre`, `radius`, m) with `mesh`, of the
/// triangles `candidate_triangles` (e.g. those the broad phase found within reach; more,
/// repeated or in any order do no harm), each particle–surface contact once, sorted by
/// [`Primitive`] (see the [module doc](self) for the rule and the order). Contacts already in
/// `out` are left as they are.
///
/// # Panics
/// If a candidate is not a triangle of `mesh`.
pub fn sphere_contacts(
    mesh: &Mesh,
    candidate_triangles: &[u32],
    centre: Vec3,
    radius: f64,
    out: &mut Vec<MeshContact>,
) {
    let start = out.len();
    // Faces first: an edge or vertex of a triangle touched on its face is shadowed (rule 2),
    // so its contact need not be formed. The others wait here (beyond its size, formed at once).
    const WAIT: usize = 48;
    let mut waiting = [Primitive::Face(0); WAIT];
    let mut n_waiting = 0;
    for &t in candidate_triangles {
        let corners = mesh.corners(t);
        let n = mesh.normals[t as usize];
        // The distance to the triangle's plane bounds the distance to the triangle (the
        // margin covers the rounding of the two, so no triangle in reach is passed over).
        let s = (centre - corners[0]).dot(n);
        if s.abs() > radius * (1.0 + 1e-12) {
            continue;
        }
        let closest = closest_point_with_normal(centre, corners, n);
        // A triangle out of reach takes no part, so that the contacts are a function of the
        // triangles within reach, whatever other candidates come with them.
        if (centre - closest.point).length_squared() > radius * radius {
            continue;
        }
        let primitive = match closest.region {
            // The face's contact is its plane's, at the signed distance s.
            Region::Face => {
                out.extend(signed_plane_contact(t, n, s, Primitive::Face(t), centre, radius));
                continue;
            }
            Region::Edge(k) => Primitive::Edge(mesh.triangle_edges[t as usize][k as usize]),
            Region::Vertex(k) => Primitive::Vertex(mesh.triangles[t as usize][k as usize]),
        };
        if n_waiting == WAIT {
            if let Some(contact) = primitive_contact(mesh, primitive, centre, radius) {
                out.push(contact);
            }
        } else {
            waiting[n_waiting] = primitive;
            n_waiting += 1;
        }
    }
    for &primitive in &waiting[..n_waiting] {
        if out[start..].iter().any(|k| shadows(mesh, k.primitive, primitive)) {
            continue;
        }
        if let Some(contact) = primitive_contact(mesh, primitive, centre, radius) {
            out.push(contact);
        }
    }
    out[start..].sort_unstable_by_key(|c| c.primitive);
    // Keep, in order, what rules 2 and 4 leave: each decided against those kept before it,
    // which are all the faces before an edge, and all the faces and edges before a vertex.
    let mut kept = start;
    let mut previous = None;
    for i in start..out.len() {
        let contact = out[i];
        if previous.replace(contact.primitive) == Some(contact.primitive) {
            continue;
        }
        if accepted(mesh, &out[start..kept], &contact) {
            out[kept] = contact;
            kept += 1;
        }
    }
    out.truncate(kept);
}

/// Whether a contact with `kept` shadows one with `c` (rule 2): a face its edges and
/// vertices, an edge its vertices.
fn shadows(mesh: &Mesh, kept: Primitive, c: Primitive) -> bool {
    match (c, kept) {
        (Primitive::Edge(e), Primitive::Face(t)) => mesh.edges[e as usize].triangles().contains(&t),
        (Primitive::Vertex(v), Primitive::Face(t)) => mesh.triangles[t as usize].contains(&v),
        (Primitive::Vertex(v), Primitive::Edge(e)) => mesh.edges[e as usize].vertices.contains(&v),
        _ => false,
    }
}

/// Whether `c` stands beside the contacts `kept` before it (rules 2 and 4).
fn accepted(mesh: &Mesh, kept: &[MeshContact], c: &MeshContact) -> bool {
    let shadowed = |k: &MeshContact| shadows(mesh, k.primitive, c.primitive);
    let same = |k: &MeshContact| {
        let reach = MERGE_TOLERANCE * k.distance.max(c.distance) + 10.0 * ROUNDING * mesh.extent;
        (k.point - c.point).length() <= reach && (k.normal - c.normal).length() <= MERGE_TOLERANCE
    };
    !kept.iter().any(|k| shadowed(k) || same(k))
}

/// The contact of the sphere with one primitive, if no farther than the radius and (for an edge or
/// a vertex) in its normal cone.
fn primitive_contact(mesh: &Mesh, primitive: Primitive, p: Vec3, r: f64) -> Option<MeshContact> {
    // (c − q)·w may exceed 0 by this much times |w| (rule 3).
    let slack = |d: f64| CONE_TOLERANCE * d + ROUNDING * mesh.extent;
    match primitive {
        Primitive::Face(t) => plane_contact(mesh, t, primitive, p, r),
        Primitive::Edge(e) => {
            let edge = &mesh.edges[e as usize];
            let [a, b] = edge.vertices.map(|v| mesh.vertices[v as usize]);
            let ab = b - a;
            let q = a + ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0) * ab;
            let d = p - q;
            let distance = d.length();
            for &t in edge.triangles() {
                // The in-plane direction from the edge into triangle t.
                let opposite = mesh.triangles[t as usize].into_iter().find(|v| !edge.vertices.contains(v));
                let ao = opposite.map_or(Vec3::ZERO, |o| mesh.vertices[o as usize] - a);
                let u = ao - (ao.dot(ab) / ab.length_squared()) * ab;
                if d.dot(u) > slack(distance) * u.length() {
                    return None;
                }
            }
            let owner = edge.triangles()[0];
            if edge.kind == EdgeKind::Flat {
                plane_contact(mesh, owner, primitive, p, r)
            } else {
                point_contact(mesh, owner, primitive, q, d, distance, r)
            }
        }
        Primitive::Vertex(v) => {
            let q = mesh.vertices[v as usize];
            let d = p - q;
            let distance = d.length();
            for &t in mesh.vertex_triangles(v) {
                for w in mesh.triangles[t as usize].into_iter().filter(|&w| w != v) {
                    let along = mesh.vertices[w as usize] - q;
                    if d.dot(along) > slack(distance) * along.length() {
                        return None;
                    }
                }
            }
            let owner = mesh.vertex_triangles(v)[0];
            if mesh.flat_vertices[v as usize] {
                plane_contact(mesh, owner, primitive, p, r)
            } else {
                point_contact(mesh, owner, primitive, q, d, distance, r)
            }
        }
    }
}

/// The contact with the plane of triangle `t`, on whichever side the centre `p` is (the
/// normal side at distance 0).
fn plane_contact(mesh: &Mesh, t: u32, primitive: Primitive, p: Vec3, r: f64) -> Option<MeshContact> {
    let n = mesh.normals[t as usize];
    let s = (p - mesh.corners(t)[0]).dot(n);
    signed_plane_contact(t, n, s, primitive, p, r)
}

/// [`plane_contact`] with the triangle's normal `n` and the centre's signed distance `s` from
/// its plane given.
fn signed_plane_contact(
    t: u32,
    n: Vec3,
    s: f64,
    primitive: Primitive,
    p: Vec3,
    r: f64,
) -> Option<MeshContact> {
    let distance = s.abs();
    (distance <= r).then(|| MeshContact {
        normal: if s >= 0.0 { n } else { -n },
        overlap: r - distance,
        point: p - s * n,
        distance,
        primitive,
        triangle: t,
    })
}

/// The contact with the point `q` of an edge or vertex, `d` = p − q, `distance` = |d|, owned by
/// triangle `t` (whose normal it takes at a distance within [`ROUNDING`] of the coordinates'
/// magnitude, i.e. 0 but for rounding).
fn point_contact(
    mesh: &Mesh,
    t: u32,
    primitive: Primitive,
    q: Vec3,
    d: Vec3,
    distance: f64,
    r: f64,
) -> Option<MeshContact> {
    (distance <= r).then(|| MeshContact {
        // Closer than the coordinates' rounding, the direction of d is noise.
        normal: if distance > ROUNDING * mesh.extent { d / distance } else { mesh.normals[t as usize] },
        overlap: r - distance,
        point: q,
        distance,
        primitive,
        triangle: t,
    })
}
