//! The geometry of triangle-mesh walls: sphere–mesh contacts on flat floors (two triangles, a
//! grid, a random conforming floor with slivers), at convex edges and corners and in concave
//! corners; closest points on slivers; file input (STL ASCII and binary, OBJ), the load-time
//! transform, and every validation message.
//!
//! ## Tolerances
//! On a floor in the plane z = 0 the engine's contact is exact but for one rounding: the
//! normals of triangles in a coordinate plane are exactly the axis, and the plane's distance
//! (c − a)·n is then c_z itself, so the overlap is r − |c_z| rounded once. The comparisons
//! allow 1e-12 relative, some 5 000 ulps, so that they test the geometry rather than the last
//! bit. Elsewhere (ridges, corners, tilted planes) the expected values are formed from the same
//! coordinates by another route (ρ·(sin θ, 0, cos θ) against c − q), whose rounding is a few ε
//! of the coordinates (≤ 2): 1e-12 again, relative to the coordinates' magnitude.

use grainflow::Vec3;
use grainflow::mesh::{
    EdgeKind, Mesh, MeshContact, MeshError, MeshTransform, Primitive, Region, closest_point_on_triangle,
    sphere_contacts,
};
use proptest::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

const TOL: f64 = 1e-12;

fn mesh(name: &str, vertices: &[Vec3], triangles: &[[u32; 3]]) -> Mesh {
    match Mesh::from_indexed(name, vertices, triangles, &MeshTransform::default()) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    }
}

fn all(mesh: &Mesh) -> Vec<u32> {
    (0..mesh.triangle_count() as u32).collect()
}

fn contacts(mesh: &Mesh, centre: Vec3, radius: f64) -> Vec<MeshContact> {
    let mut out = Vec::new();
    sphere_contacts(mesh, &all(mesh), centre, radius, &mut out);
    out
}

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

/// A small deterministic generator (SplitMix64), so the random floor is the same every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

// ---------------------------------------------------------------------------------------------
// Floors in the plane z = 0, over the unit square, normals +z.

/// The unit square as n × n squares of two triangles each.
fn grid_floor(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let h = 1.0 / n as f64;
    let mut vertices = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            vertices.push(v(i as f64 * h, j as f64 * h, 0.0));
        }
    }
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (vertices, triangles)
}

/// Area over longest edge squared: the shape measure the degenerate test uses.
fn shape([a, b, c]: [Vec3; 3]) -> f64 {
    let l2 = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
    0.5 * (b - a).cross(c - a).length() / l2
}

/// The unit square split again and again at random points of random edges, both triangles
/// on an edge at once so that the mesh stays conforming (no vertex in the middle of another
/// triangle's side): no Delaunay or shape criterion, so slivers form. A split that would make a
/// triangle thinner than `thinnest` (area over longest edge squared) is skipped (1e-8 stays
/// clear of the degenerate limit, 1e-12).
fn random_floor(seed: u64, target: usize, thinnest: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut rng = Rng(seed);
    let mut vertices = vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(0.0, 1.0, 0.0)];
    let mut triangles: Vec<[u32; 3]> = vec![[0, 1, 2], [0, 2, 3]];
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut on_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            on_edge.entry(key(tri[k], tri[(k + 1) % 3])).or_default().push(t);
        }
    }
    while triangles.len() < target {
        let t = rng.below(triangles.len());
        let k = rng.below(3);
        let (a, b) = (triangles[t][k], triangles[t][(k + 1) % 3]);
        // Mostly near the middle, sometimes near an end (which makes slivers faster).
        let s = if rng.below(4) == 0 { 0.01 + 0.05 * rng.uniform() } else { 0.2 + 0.6 * rng.uniform() };
        let m = vertices[a as usize] + s * (vertices[b as usize] - vertices[a as usize]);
        let tris = on_edge[&key(a, b)].clone();
        // The children of each triangle on the edge: (x, m, o) and (m, y, o) for x → y along it.
        let children: Vec<(usize, [u32; 3], [u32; 3])> = tris
            .iter()
            .map(|&u| {
                let tri = triangles[u];
                let j = (0..3).find(|&j| key(tri[j], tri[(j + 1) % 3]) == key(a, b)).unwrap();
                let (x, y, o) = (tri[j], tri[(j + 1) % 3], tri[(j + 2) % 3]);
                (u, [x, u32::MAX, o], [u32::MAX, y, o])
            })
            .collect();
        let at = |i: u32| if i == u32::MAX { m } else { vertices[i as usize] };
        if children.iter().any(|(_, c0, c1)| shape(c0.map(at)) < thinnest || shape(c1.map(at)) < thinnest) {
            continue;
        }
        let mi = vertices.len() as u32;
        vertices.push(m);
        on_edge.remove(&key(a, b));
        for (u, c0, c1) in children {
            let fix = |c: [u32; 3]| c.map(|i| if i == u32::MAX { mi } else { i });
            let (c0, c1) = (fix(c0), fix(c1));
            let old = triangles[u];
            for j in 0..3 {
                let e = key(old[j], old[(j + 1) % 3]);
                if let Some(list) = on_edge.get_mut(&e) {
                    list.retain(|&w| w != u);
                }
            }
            triangles[u] = c0;
            let w = triangles.len();
            triangles.push(c1);
            for (id, c) in [(u, c0), (w, c1)] {
                for j in 0..3 {
                    on_edge.entry(key(c[j], c[(j + 1) % 3])).or_default().push(id);
                }
            }
        }
    }
    (vertices, triangles)
}

/// The three floors: 2 triangles, a 10 × 10 × 2 grid, and a random one of 8 000 triangles.
fn floors() -> &'static [Mesh; 3] {
    static FLOORS: OnceLock<[Mesh; 3]> = OnceLock::new();
    FLOORS.get_or_init(|| {
        let square = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(0.0, 1.0, 0.0)];
        let two = mesh("two.stl", &square, &[[0, 1, 2], [0, 2, 3]]);
        let (gv, gt) = grid_floor(10);
        let (rv, rt) = random_floor(28, 8000, 1e-8);
        [two, mesh("grid.stl", &gv, &gt), mesh("random.stl", &rv, &rt)]
    })
}

#[test]
fn the_random_floor_is_conforming_flat_and_has_slivers() {
    let floor = &floors()[2];
    assert!(floor.triangle_count() >= 8000);
    let thinnest = (0..floor.triangle_count() as u32).map(|t| shape(floor.corners(t))).fold(1.0, f64::min);
    // An equilateral triangle has 0.43; a sliver far less.
    assert!(thinnest < 1e-4, "thinnest triangle {thinnest}");
    // Conforming: only the square's rim is open, and every inner edge is flat.
    let open: Vec<_> = floor.edges().iter().filter(|e| e.kind == EdgeKind::Boundary).collect();
    for e in &open {
        let [a, b] = e.vertices.map(|i| floor.vertices()[i as usize]);
        let on_rim = |p: Vec3| p.x == 0.0 || p.x == 1.0 || p.y == 0.0 || p.y == 1.0;
        assert!(on_rim(a) && on_rim(b), "open edge inside the floor: {a} {b}");
    }
    assert!(floor.edges().iter().all(|e| matches!(e.kind, EdgeKind::Flat | EdgeKind::Boundary)));
    assert!(floor.normals().iter().all(|&n| n == Vec3::Z));
}

/// Where a sphere's centre is put over a floor: anywhere, over a vertex, or over a point of an
/// edge (exactly, as far as the coordinates go).
#[derive(Debug, Clone)]
enum Spot {
    Anywhere(f64, f64),
    OverVertex(usize),
    OverEdge(usize, f64),
}

fn spot() -> impl Strategy<Value = Spot> {
    prop_oneof![
        (0.0f64..=1.0, 0.0f64..=1.0).prop_map(|(x, y)| Spot::Anywhere(x, y)),
        any::<usize>().prop_map(Spot::OverVertex),
        (any::<usize>(), 0.0f64..1.0).prop_map(|(e, s)| Spot::OverEdge(e, s)),
    ]
}

/// The (x, y) of a spot over `floor`.
fn place(floor: &Mesh, spot: Spot) -> (f64, f64) {
    match spot {
        Spot::Anywhere(x, y) => (x, y),
        Spot::OverVertex(i) => {
            let p = floor.vertices()[i % floor.vertices().len()];
            (p.x, p.y)
        }
        Spot::OverEdge(e, s) => {
            let [a, b] =
                floor.edges()[e % floor.edges().len()].vertices.map(|i| floor.vertices()[i as usize]);
            let p = a + s * (b - a);
            (p.x, p.y)
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() })]

    /// A sphere anywhere over a flat floor, on either side, gets exactly one contact, the
    /// plane's: normal ±z, overlap r − |z|, the point below the centre.
    #[test]
    fn a_flat_floor_is_one_plane(
        which in 0usize..3,
        spot in spot(),
        radius in 0.001f64..0.3,
        height in prop_oneof![4 => -0.999f64..0.999, 1 => Just(0.0)],
    ) {
        let floor = &floors()[which];
        let (x, y) = place(floor, spot);
        let z = height * radius;
        let centre = v(x, y, z);
        let found = contacts(floor, centre, radius);
        prop_assert_eq!(found.len(), 1, "{:?}", found);
        let c = found[0];
        let n = if z >= 0.0 { Vec3::Z } else { -Vec3::Z };
        prop_assert!((c.normal - n).length() <= TOL, "{:?}", c);
        prop_assert!((c.overlap - (radius - z.abs())).abs() <= TOL * radius, "{:?}", c);
        prop_assert!((c.point - v(x, y, 0.0)).length() <= TOL, "{:?}", c);
        prop_assert!((c.distance - z.abs()).abs() <= TOL * radius);
    }

    /// The same contacts, to the bit, whatever the order of the candidate triangles and
    /// however often one is repeated.
    #[test]
    fn contacts_do_not_depend_on_the_candidates_order(
        seed in any::<u64>(),
        x in -0.1f64..1.1,
        y in -0.1f64..1.1,
        z in -0.2f64..0.2,
        radius in 0.01f64..0.3,
    ) {
        let floor = &floors()[2];
        let centre = v(x, y, z);
        let mut reference = Vec::new();
        sphere_contacts(floor, &all(floor), centre, radius, &mut reference);
        let mut shuffled = all(floor);
        let mut rng = Rng(seed);
        for i in (1..shuffled.len()).rev() {
            shuffled.swap(i, rng.below(i + 1));
        }
        shuffled.extend_from_slice(&all(floor)[..100]);
        let mut out = Vec::new();
        sphere_contacts(floor, &shuffled, centre, radius, &mut out);
        prop_assert_eq!(reference, out);
    }
}

/// The transform of the tilted floors: turned by 30°, 20° and 10° about x, y and z, and moved.
const TILT: MeshTransform = MeshTransform {
    scale: 1.0,
    rotation_deg: [30.0, 20.0, 10.0],
    translation: Vec3::new(0.1, -0.2, 0.3),
    flip_normals: false,
    skip_degenerate: false,
};

/// Flat floors in no coordinate plane, whose triangles' normals are no longer exact: the random
/// floor, and one of 4 000 triangles no thinner than 1e-4; each with the height of its
/// thinnest triangle, m.
fn tilted_floors() -> &'static [(Mesh, f64); 2] {
    static TILTED: OnceLock<[(Mesh, f64); 2]> = OnceLock::new();
    TILTED.get_or_init(|| {
        [0, 1].map(|which| {
            let floor = floor_before_tilt(which);
            let tilted = Mesh::from_indexed("tilted", floor.vertices(), floor.triangles(), &TILT).unwrap();
            let heights = (0..tilted.triangle_count() as u32).map(|t| {
                let [a, b, c] = tilted.corners(t);
                let longest = (b - a).length().max((c - b).length()).max((a - c).length());
                (b - a).cross(c - a).length() / longest
            });
            let thinnest = heights.fold(f64::INFINITY, f64::min);
            (tilted, thinnest)
        })
    })
}

/// The floor that `tilted_floors()[which]` is the tilted form of (the same numbering).
fn floor_before_tilt(which: usize) -> &'static Mesh {
    static MODERATE: OnceLock<Mesh> = OnceLock::new();
    if which == 0 {
        &floors()[2]
    } else {
        MODERATE.get_or_init(|| {
            let (mv, mt) = random_floor(29, 4000, 1e-4);
            mesh("moderate", &mv, &mt)
        })
    }
}

/// The transform's rotation, formed here by quaternions (another route than the engine's).
fn rotation_of(t: &MeshTransform) -> glam::DQuat {
    let [x, y, z] = t.rotation_deg.map(f64::to_radians);
    glam::DQuat::from_rotation_z(z) * glam::DQuat::from_rotation_y(y) * glam::DQuat::from_rotation_x(x)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() })]

    /// Tilted, a random floor is still one plane to a sphere: one contact, the plane's. The
    /// plane of a triangle of height h is fixed by its rounded corners only to an angle of
    /// about ε·|x|max/h (a corner moved by its rounding, across a height h), and its offset at
    /// the centre to that angle times the centre's distance from the corners (< 2 m): so the
    /// normal and the overlap are compared to 64·ε·|x|max/h for the floor's thinnest triangle:
    /// 5e-7 for the floor of triangles no thinner than 1e-4 (the thinnest 3e-8 m high), 7e-4
    /// for the random floor (2e-11 m high: such a sliver's plane is poor), against an O(r)
    /// error of a wrong or second contact.
    #[test]
    fn a_tilted_flat_floor_is_one_plane(
        which in 0usize..2,
        spot in spot(),
        radius in 0.001f64..0.3,
        height in -0.999f64..0.999,
    ) {
        let (floor, thinnest) = &tilted_floors()[which];
        let (x, y) = place(floor_before_tilt(which), spot);
        let rotation = rotation_of(&TILT);
        let z = height * radius;
        let centre = rotation * v(x, y, z) + TILT.translation;
        let (lo, hi) = floor.bounds();
        let tol = 64.0 * f64::EPSILON * lo.abs().max(hi.abs()).max_element() / thinnest;
        let found = contacts(floor, centre, radius);
        prop_assert_eq!(found.len(), 1, "{:?}", found);
        let n = rotation * if z >= 0.0 { Vec3::Z } else { -Vec3::Z };
        prop_assert!((found[0].normal - n).length() <= tol, "{:?}", found);
        prop_assert!((found[0].overlap - (radius - z.abs())).abs() <= tol, "{:?}", found);
    }
}

#[test]
fn a_sphere_beside_the_rim_of_an_open_floor_touches_its_edge() {
    let floor = &floors()[1];
    // Level with the floor, 0.05 beyond its x = 0 rim: the rim is the nearest point.
    let found = contacts(floor, v(-0.05, 0.55, 0.0), 0.1);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(matches!(found[0].primitive, Primitive::Edge(_)));
    assert!((found[0].normal - v(-1.0, 0.0, 0.0)).length() <= TOL);
    assert!((found[0].overlap - 0.05).abs() <= TOL);
    // Beyond a corner of the square: its vertex.
    let found = contacts(floor, v(-0.03, -0.04, 0.0), 0.1);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].primitive, Primitive::Vertex(0));
    assert!((found[0].normal - v(-0.6, -0.8, 0.0)).length() <= TOL);
    assert!((found[0].overlap - 0.05).abs() <= TOL);
}

#[test]
fn appended_contacts_leave_the_earlier_ones_alone() {
    let floor = &floors()[0];
    let mut out = Vec::new();
    sphere_contacts(floor, &all(floor), v(0.5, 0.5, 0.05), 0.1, &mut out);
    let first = out.clone();
    sphere_contacts(floor, &all(floor), v(0.2, 0.7, -0.02), 0.1, &mut out);
    assert_eq!(out.len(), 2);
    assert_eq!(out[0], first[0]);
    assert_eq!(out[1].normal, -Vec3::Z);
}

// ---------------------------------------------------------------------------------------------
// Convex and concave edges and corners.

/// A roof: two slopes of two triangles each, folded at 90° along the ridge x = 0, z = 1
/// (y from 0 to 1), normals (∓1, 0, 1)/√2.
fn roof() -> Mesh {
    let p = [
        v(-1.0, 0.0, 0.0),
        v(0.0, 0.0, 1.0),
        v(0.0, 1.0, 1.0),
        v(-1.0, 1.0, 0.0),
        v(1.0, 0.0, 0.0),
        v(1.0, 1.0, 0.0),
    ];
    mesh("roof", &p, &[[0, 1, 2], [0, 2, 3], [4, 5, 2], [4, 2, 1]])
}

/// The unit cube [0, 1]³, twelve triangles, normals outward.
fn cube() -> Mesh {
    let p: Vec<Vec3> = (0..8).map(|i| v((i & 1) as f64, ((i >> 1) & 1) as f64, (i >> 2) as f64)).collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let tris: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    mesh("cube", &p, &tris)
}

/// A floor z = 0 (x, y in [0, 1], normal +z) and a wall x = 0 (y, z in [0, 1], normal +x)
/// meeting at a concave crease along the y axis.
fn corner() -> Mesh {
    let p = [
        v(0.0, 0.0, 0.0),
        v(1.0, 0.0, 0.0),
        v(1.0, 1.0, 0.0),
        v(0.0, 1.0, 0.0),
        v(0.0, 0.0, 1.0),
        v(0.0, 1.0, 1.0),
    ];
    mesh("corner", &p, &[[0, 1, 2], [0, 2, 3], [0, 3, 5], [0, 5, 4]])
}

#[test]
fn edges_are_classified_seen_from_the_normal_side() {
    let count = |m: &Mesh, kind| m.edges().iter().filter(|e| e.kind == kind).count();
    let cube = cube();
    assert_eq!(cube.edges().len(), 18);
    assert_eq!((count(&cube, EdgeKind::Convex), count(&cube, EdgeKind::Flat)), (12, 6));
    let roof = roof();
    let ridge = roof.edges().iter().find(|e| e.kind == EdgeKind::Convex).unwrap();
    let ends = ridge.vertices.map(|i| roof.vertices()[i as usize]);
    assert!(ends.contains(&v(0.0, 0.0, 1.0)) && ends.contains(&v(0.0, 1.0, 1.0)));
    assert_eq!((count(&roof, EdgeKind::Convex), count(&roof, EdgeKind::Flat)), (1, 2));
    assert_eq!(count(&corner(), EdgeKind::Concave), 1);
    // Turning the normals round turns ridges into valleys.
    let flipped = Mesh::from_indexed(
        "cube",
        cube.vertices(),
        cube.triangles(),
        &MeshTransform { flip_normals: true, ..MeshTransform::default() },
    )
    .unwrap();
    assert_eq!(count(&flipped, EdgeKind::Concave), 12);
}

#[test]
fn topology_links_triangles_edges_and_vertices() {
    let floor = &floors()[0];
    // Triangle 0 = (0, 1, 2) and 1 = (0, 2, 3) share the diagonal 0–2: side 2 of 0 and side 0
    // of 1.
    assert_eq!(floor.neighbour(0, 2), Some(1));
    assert_eq!(floor.neighbour(1, 0), Some(0));
    assert_eq!(floor.neighbour(0, 0), None);
    let diagonal = floor.triangle_edges()[0][2];
    assert_eq!(floor.triangle_edges()[1][0], diagonal);
    assert_eq!(floor.edges()[diagonal as usize].triangles(), &[0, 1]);
    assert_eq!(floor.edges()[diagonal as usize].vertices, [2, 0]);
    assert_eq!(floor.vertex_triangles(0), &[0, 1]);
    assert_eq!(floor.vertex_triangles(1), &[0]);
    assert_eq!(floor.bounds(), (v(0.0, 0.0, 0.0), v(1.0, 1.0, 0.0)));
    assert!(floor.outside_box(v(0.0, 0.0, 0.1), v(1.0, 1.0, 1.0)));
    assert!(!floor.outside_box(v(0.5, 0.5, -1.0), v(2.0, 2.0, 0.0)));
    assert!(floor.outside_box(v(1.5, -1.0, -1.0), v(2.0, 2.0, 1.0)));
    let cube = cube();
    for t in 0..12 {
        assert!((0..3).all(|k| cube.neighbour(t, k).is_some()), "a closed mesh has no open side");
    }
}

#[test]
fn a_sphere_over_a_ridge_touches_the_ridge_once() {
    let roof = roof();
    let ridge = roof.edges().iter().position(|e| e.kind == EdgeKind::Convex).unwrap() as u32;
    let r = 0.2;
    for (y, theta, rho) in [(0.5, 0.0, 0.1), (0.3, 30.0, 0.15), (0.71, -44.0, 0.05), (0.2, 10.0, 0.199)] {
        let (s, c) = f64::to_radians(theta).sin_cos();
        let q = v(0.0, y, 1.0);
        let centre = q + rho * v(s, 0.0, c);
        let found = contacts(&roof, centre, r);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].primitive, Primitive::Edge(ridge));
        assert!((found[0].normal - v(s, 0.0, c)).length() <= TOL, "{found:?}");
        assert!((found[0].overlap - (r - rho)).abs() <= TOL);
        assert!((found[0].point - q).length() <= TOL);
        // The lowest triangle on the ridge owns it.
        assert_eq!(found[0].triangle, 0);
    }
    // Past 45° from the vertical the centre is over the right slope: its plane alone.
    let n = v(1.0, 0.0, 1.0) / 2f64.sqrt();
    for (y, theta, rho) in [(0.5, 50.0, 0.1), (0.4, 80.0, 0.15)] {
        let (s, c) = f64::to_radians(theta).sin_cos();
        let centre = v(0.0, y, 1.0) + rho * v(s, 0.0, c);
        let found = contacts(&roof, centre, r);
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(matches!(found[0].primitive, Primitive::Face(2 | 3)));
        assert!((found[0].normal - n).length() <= TOL);
        let distance = (centre - v(1.0, 0.0, 0.0)).dot(n);
        assert!((found[0].overlap - (r - distance)).abs() <= TOL);
    }
}

#[test]
fn a_sphere_off_a_cube_corner_touches_its_vertex_once() {
    let cube = cube();
    let corner = cube.vertices().iter().position(|&p| p == v(1.0, 1.0, 1.0)).unwrap() as u32;
    for dir in [v(1.0, 1.0, 1.0), v(0.2, 1.0, 0.5), v(1.0, 0.01, 0.01)] {
        let n = dir.normalize();
        let centre = v(1.0, 1.0, 1.0) + 0.07 * n;
        let found = contacts(&cube, centre, 0.1);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].primitive, Primitive::Vertex(corner));
        assert!((found[0].normal - n).length() <= TOL);
        assert!((found[0].overlap - 0.03).abs() <= TOL);
        assert_eq!(found[0].triangle, cube.vertex_triangles(corner)[0]);
    }
    // Off the edge x = y = 1: one edge contact; over the top face: one face contact.
    let found = contacts(&cube, v(1.05, 1.05, 0.4), 0.1);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(matches!(found[0].primitive, Primitive::Edge(_)));
    assert!((found[0].normal - v(1.0, 1.0, 0.0).normalize()).length() <= TOL);
    let found = contacts(&cube, v(0.3, 0.6, 1.04), 0.1);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!((found[0].normal - Vec3::Z).length() <= TOL && (found[0].overlap - 0.06).abs() <= TOL);
}

#[test]
fn a_sphere_in_a_concave_corner_touches_both_planes() {
    let corner = corner();
    let r = 0.1;
    for (x, y, z) in [(0.05, 0.5, 0.07), (0.09, 0.2, 0.01), (0.001, 0.8, 0.099), (0.03, 0.03, 0.03)] {
        let found = contacts(&corner, v(x, y, z), r);
        assert_eq!(found.len(), 2, "{found:?}");
        let floor = found.iter().find(|c| c.normal == Vec3::Z).expect("a floor contact");
        let wall = found.iter().find(|c| c.normal == Vec3::X).expect("a wall contact");
        assert!((floor.overlap - (r - z)).abs() <= TOL && (wall.overlap - (r - x)).abs() <= TOL);
        // Over a floor or wall diagonal (the last case) the contact may be the flat edge's,
        // owned by the lower triangle: the geometry is the plane's all the same.
        assert!(matches!((floor.triangle, wall.triangle), (0 | 1, 2 | 3)), "{found:?}");
    }
}

#[test]
fn a_centre_on_the_surface_takes_its_triangles_normal() {
    let floor = &floors()[1];
    let found = contacts(floor, v(0.37, 0.52, 0.0), 0.1);
    assert_eq!(found.len(), 1);
    assert_eq!((found[0].normal, found[0].overlap), (Vec3::Z, 0.1));
    let roof = roof();
    let found = contacts(&roof, v(0.0, 0.5, 1.0), 0.1);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!((found[0].normal, found[0].overlap, found[0].triangle), (roof.normals()[0], 0.1, 0));
    let cube = cube();
    let found = contacts(&cube, v(1.0, 1.0, 1.0), 0.1);
    assert_eq!(found.len(), 1, "{found:?}");
    let owner = found[0].triangle;
    assert_eq!((found[0].normal, found[0].overlap), (cube.normals()[owner as usize], 0.1));
    assert!(found[0].normal.is_finite());
}

#[test]
fn a_sphere_under_an_open_sheet_touches_its_back() {
    let roof = roof();
    // Under the left slope, 0.05 from it.
    let n = v(-1.0, 0.0, 1.0) / 2f64.sqrt();
    let centre = v(-0.5, 0.5, 0.5) - 0.05 * n;
    let found = contacts(&roof, centre, 0.1);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!((found[0].normal + n).length() <= TOL && (found[0].overlap - 0.05).abs() <= TOL);
}

// ---------------------------------------------------------------------------------------------
// Closest points on slivers.

/// The closest point by another route: the nearest of the three sides' closest points and,
/// when it falls inside, the projection onto the plane.
fn reference_closest(p: Vec3, [a, b, c]: [Vec3; 3]) -> f64 {
    let segment = |a: Vec3, b: Vec3| {
        let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
        (p - (a + t * (b - a))).length()
    };
    let mut best = segment(a, b).min(segment(b, c)).min(segment(c, a));
    let n = (b - a).cross(c - a).normalize();
    let q = p - (p - a).dot(n) * n;
    let inside = [(a, b), (b, c), (c, a)].iter().all(|&(u, w)| (w - u).cross(q - u).dot(n) >= 0.0);
    if inside {
        best = best.min((p - q).length());
    }
    best
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    /// On slivers (height h down to 1e-7 of the length L = 1) in any orientation, the closest
    /// point lies on the triangle and is as close as the reference's. A sliver's plane is fixed
    /// by its rounded corners only to an angle of about ε·L/h (the rounding of the cross
    /// product of its sides, of order ε·L², against its size L·h), so a point P from the
    /// triangle is placed to about ε·P·L/h by either route: the distances are compared to
    /// 64·ε·(L + P)·L/h (6e-7 at h = 1e-7, 3e-14 for a fat triangle).
    #[test]
    fn closest_points_on_slivers_are_the_nearest(
        along in 1e-3f64..1.0,
        height_exp in -7.0f64..0.0,
        axis in prop::array::uniform3(-1.0f64..1.0),
        angle in 0.0f64..6.3,
        offset in prop::array::uniform3(-2.0f64..2.0),
    ) {
        let axis = Vec3::from_array(axis);
        prop_assume!(axis.length() > 0.1);
        let rot = glam::DQuat::from_axis_angle(axis.normalize(), angle);
        let h = 10f64.powf(height_exp);
        let corners = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(along, h, 0.0)].map(|p| rot * p + v(0.3, -0.2, 0.1));
        let p = Vec3::from_array(offset);
        let found = closest_point_on_triangle(p, corners);
        let got = (p - found.point).length();
        let want = reference_closest(p, corners);
        let tol = 64.0 * f64::EPSILON * (1.0 + want) / h;
        prop_assert!((got - want).abs() <= tol, "got {} want {} at {:?}", got, want, found);
        // On the triangle: within its bounding box, give or take the same.
        let lo = corners[0].min(corners[1]).min(corners[2]) - Vec3::splat(tol);
        let hi = corners[0].max(corners[1]).max(corners[2]) + Vec3::splat(tol);
        prop_assert!(found.point.cmpge(lo).all() && found.point.cmple(hi).all(), "{:?}", found);
    }
}

#[test]
fn closest_point_regions() {
    let t = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
    let cases = [
        (v(0.2, 0.3, 0.5), Region::Face, v(0.2, 0.3, 0.0)),
        (v(0.5, -1.0, 0.5), Region::Edge(0), v(0.5, 0.0, 0.0)),
        (v(1.0, 1.0, -0.5), Region::Edge(1), v(0.5, 0.5, 0.0)),
        (v(-1.0, 0.5, 0.0), Region::Edge(2), v(0.0, 0.5, 0.0)),
        (v(-1.0, -1.0, 1.0), Region::Vertex(0), t[0]),
        (v(2.0, -0.5, 0.0), Region::Vertex(1), t[1]),
        (v(-0.1, 3.0, 0.0), Region::Vertex(2), t[2]),
    ];
    for (p, region, point) in cases {
        let found = closest_point_on_triangle(p, t);
        assert_eq!(found.region, region, "{p}");
        assert!((found.point - point).length() <= 1e-15, "{p}: {found:?}");
    }
    // Over the face, the projection keeps x and y to the bit.
    let p = v(0.123456789, 0.3210987, 7.5);
    assert_eq!(closest_point_on_triangle(p, t).point, v(p.x, p.y, 0.0));
}

// ---------------------------------------------------------------------------------------------
// Files and the transform.

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes").join(name)
}

/// The triangles of a mesh as corner coordinates.
fn soup(mesh: &Mesh) -> Vec<[Vec3; 3]> {
    (0..mesh.triangle_count() as u32).map(|t| mesh.corners(t)).collect()
}

fn ascii_stl(triangles: &[[Vec3; 3]]) -> String {
    let mut s = String::from("solid test\n");
    for t in triangles {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for p in t {
            // f64's shortest form reads back to the same f64.
            s += &format!("      vertex {} {} {}\n", p.x, p.y, p.z);
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid test\n"
}

fn binary_stl(triangles: &[[Vec3; 3]], header: &str) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b[..header.len()].copy_from_slice(header.as_bytes());
    b.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
    for t in triangles {
        b.extend_from_slice(&[0u8; 12]);
        for p in t {
            for x in p.to_array() {
                b.extend_from_slice(&(x as f32).to_le_bytes());
            }
        }
        b.extend_from_slice(&[0u8; 2]);
    }
    b
}

#[test]
fn ascii_and_binary_stl_of_the_same_geometry_give_the_same_mesh() {
    // A cube's coordinates, made f32 (as binary STL stores them) and not round in decimal.
    let f = |x: f64| (x * 0.0137 + 0.3) as f32 as f64;
    let triangles: Vec<[Vec3; 3]> = soup(&cube()).iter().map(|t| t.map(|p| p.map(f))).collect();
    let ascii =
        Mesh::from_stl("cube.stl", ascii_stl(&triangles).as_bytes(), &MeshTransform::default()).unwrap();
    // A binary header that starts with "solid", as some exporters write.
    let bytes = binary_stl(&triangles, "solid cube exported as binary");
    let binary = Mesh::from_stl("cube.stl", &bytes, &MeshTransform::default()).unwrap();
    assert_eq!(ascii, binary);
    // Welded: 8 vertices, the cube's topology.
    assert_eq!((ascii.vertices().len(), ascii.edges().len()), (8, 18));
    assert_eq!(soup(&ascii), triangles);
}

#[test]
fn the_vendored_files_load() {
    let roof = Mesh::load(&data("roof.stl"), &MeshTransform::default()).unwrap();
    assert_eq!(roof.vertices(), self::roof().vertices());
    assert_eq!(roof.triangles(), self::roof().triangles());
    let cube = Mesh::load(&data("cube_quads.obj"), &MeshTransform::default()).unwrap();
    assert_eq!((cube.triangle_count(), cube.vertices().len(), cube.edges().len()), (12, 8, 18));
    // Every normal points out of the cube, and every edge has two triangles.
    for t in 0..12 {
        let centre = cube.corners(t).iter().sum::<Vec3>() / 3.0;
        assert!(cube.normals()[t as usize].dot(centre - Vec3::splat(0.5)) > 0.0);
    }
    assert!(cube.edges().iter().all(|e| e.triangles().len() == 2));
}

#[test]
fn obj_negative_indices_and_quads_are_the_positive_triangles() {
    let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4/1/1 -3/2/1 -2/3/1 -1/4/1\nv 2 0 0\nf 2 5 3\n";
    let obj = Mesh::from_obj("quad.obj", text.as_bytes(), &MeshTransform::default()).unwrap();
    let square = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(0.0, 1.0, 0.0), v(2.0, 0.0, 0.0)];
    let indexed = Mesh::from_indexed(
        "quad.obj",
        &square,
        &[[0, 1, 2], [0, 2, 3], [1, 4, 2]],
        &MeshTransform::default(),
    );
    assert_eq!(obj, indexed.unwrap());
}

/// An L-shaped face, [0, 2]² without its notch (1, 2]², written from the corner (2, 1) next
/// to the reflex corner (1, 1): the fan from there covers the notch with a triangle wound the
/// other way. In the plane z = 0 and in a tilted plane (v along (0, 0.6, 0.8)).
#[test]
fn an_obj_face_with_a_reflex_corner_covers_the_polygon_and_not_its_notch() {
    let l = [(2.0, 1.0), (1.0, 1.0), (1.0, 2.0), (0.0, 2.0), (0.0, 0.0), (2.0, 0.0)];
    // Shoelace: the polygon's area.
    let shoelace: f64 =
        0.5 * (0..6).map(|i| l[i].0 * l[(i + 1) % 6].1 - l[(i + 1) % 6].0 * l[i].1).sum::<f64>();
    assert_eq!(shoelace, 3.0);
    let (c, s) = (0.6, 0.8);
    // Each plane by its two in-plane unit axes: (u, w) sits at u·e_u + w·e_w.
    let planes = [("flat", Vec3::X, Vec3::Y), ("tilted", Vec3::X, v(0.0, c, s))];
    for &(name, e_u, e_w) in &planes {
        let to_3d = |u: f64, w: f64| e_u * u + e_w * w;
        let to_2d = |p: Vec3| (p.dot(e_u), p.dot(e_w));
        let mut text = String::new();
        for &(u, w) in &l {
            let p = to_3d(u, w);
            text += &format!("v {} {} {}\n", p.x, p.y, p.z);
        }
        text += "f 1 2 3 4 5 6\n";
        let mesh = Mesh::from_obj("l.obj", text.as_bytes(), &MeshTransform::default()).unwrap();
        assert_eq!(mesh.triangle_count(), 4, "{name}");
        let plane_normal = (to_3d(1.0, 0.0) - to_3d(0.0, 0.0)).cross(to_3d(0.0, 1.0) - to_3d(0.0, 0.0));
        // The triangles' areas add up to the shoelace area: they do not overlap and leave no
        // gap (an overlap, as the fan's, adds area). The corners are exact in the plane z = 0
        // and rounded once (0.6, 0.8) in the tilted one: 1e-12 is far above that rounding.
        let mut area = 0.0;
        for t in 0..4 {
            let [a, b, q] = mesh.corners(t);
            area += 0.5 * (b - a).cross(q - a).length();
            // Each keeps the face's winding, so its normal is the plane's.
            assert!((mesh.normals()[t as usize] - plane_normal).length() < 1e-12, "{name}: triangle {t}");
        }
        assert!((area - shoelace).abs() < 1e-12, "{name}: area {area} against {shoelace}");
        // Where a point is: inside (or on) a triangle, in the face's own coordinates.
        let covering = |u: f64, w: f64| {
            (0..4u32)
                .filter(|&t| {
                    let k = mesh.corners(t).map(to_2d);
                    let side =
                        |a: (f64, f64), b: (f64, f64)| (b.0 - a.0) * (w - a.1) - (b.1 - a.1) * (u - a.0);
                    side(k[0], k[1]) >= -1e-12 && side(k[1], k[2]) >= -1e-12 && side(k[2], k[0]) >= -1e-12
                })
                .count()
        };
        // No point of the notch (a grid over the open square (1, 2)²) is covered; points of
        // the L away from the triangles' sides are covered once.
        for i in 1..10 {
            for j in 1..10 {
                let (u, w) = (1.0 + 0.1 * i as f64, 1.0 + 0.1 * j as f64);
                assert_eq!(covering(u, w), 0, "{name}: notch point ({u}, {w}) is covered");
            }
        }
        for (u, w) in [(0.31, 0.53), (1.71, 0.29), (0.23, 1.83), (0.93, 0.97), (1.87, 0.91)] {
            assert_eq!(covering(u, w), 1, "{name}: ({u}, {w}) of the L");
        }
    }
}

#[test]
fn an_obj_face_whose_sides_cross_is_refused_with_its_line() {
    // A bow tie: its sides (1, 2) and (3, 4) cross at (0.5, 0.5).
    let e = obj_error("v 0 0 0\nv 1 1 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 3 5\nf 1 2 3 4\n");
    says(&e, &["bad.obj:7", "sides cross"]);
    // A one-stroke star, two of whose sides cross although every corner turns left.
    let mut text = String::new();
    for k in 0..5 {
        let a = std::f64::consts::TAU * (2 * k) as f64 / 5.0;
        text += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    says(
        &obj_error(&(text + "f 1 2 3 4 5\n")),
        &["bad.obj:6", "not a simple polygon", "side from corner 1 to 2"],
    );
}

#[test]
fn stl_and_obj_files_with_a_byte_order_mark_read_as_without() {
    let square = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0)];
    let stl = ascii_stl(&[square]);
    let plain = Mesh::from_stl("t.stl", stl.as_bytes(), &MeshTransform::default()).unwrap();
    let marked = Mesh::from_stl("t.stl", format!("\u{feff}{stl}").as_bytes(), &MeshTransform::default());
    assert_eq!(marked.unwrap(), plain);
    // In an OBJ file the mark would hide the first vertex (its line would not start with v).
    let obj = format!("{SQUARE}f 1 2 3 4\n");
    let plain = Mesh::from_obj("t.obj", obj.as_bytes(), &MeshTransform::default()).unwrap();
    let marked = Mesh::from_obj("t.obj", format!("\u{feff}{obj}").as_bytes(), &MeshTransform::default());
    assert_eq!(marked.unwrap(), plain);
}

#[test]
fn the_transform_scales_then_rotates_x_y_z_then_translates() {
    let one = [v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0), v(0.0, 0.0, 1.0)];
    let transform = MeshTransform {
        scale: 1e-3,
        rotation_deg: [90.0, 0.0, 90.0],
        translation: v(0.5, 0.0, -1.0),
        flip_normals: false,
        skip_degenerate: false,
    };
    let m = Mesh::from_indexed("t", &one, &[[0, 1, 2]], &transform).unwrap();
    // x about x stays x, then about z becomes y; y about x becomes z, then stays; z about x
    // becomes −y, then about z becomes x. Quarter turns are exact.
    let want = [v(0.0, 1e-3, 0.0), v(0.0, 0.0, 1e-3), v(1e-3, 0.0, 0.0)].map(|p| p + v(0.5, 0.0, -1.0));
    assert_eq!(m.vertices(), &want);
    // A floor turned by a quarter about x is exactly the plane y = 0, facing −y.
    let turned = Mesh::from_indexed(
        "floor",
        floors()[1].vertices(),
        floors()[1].triangles(),
        &MeshTransform { rotation_deg: [90.0, 0.0, 0.0], ..MeshTransform::default() },
    )
    .unwrap();
    assert!(turned.vertices().iter().all(|p| p.y == 0.0));
    assert!(turned.normals().iter().all(|&n| n == -Vec3::Y));
    // Other angles: a rotation about z by 30°.
    let t30 = MeshTransform { rotation_deg: [0.0, 0.0, 30.0], ..MeshTransform::default() };
    let m = Mesh::from_indexed("t", &one, &[[0, 1, 2]], &t30).unwrap();
    let (s, c) = 30f64.to_radians().sin_cos();
    assert!((m.vertices()[0] - v(c, s, 0.0)).length() <= 1e-15);
    // Flipping reverses the winding.
    let flipped = Mesh::from_indexed(
        "t",
        &one,
        &[[0, 1, 2]],
        &MeshTransform { flip_normals: true, ..MeshTransform::default() },
    )
    .unwrap();
    assert_eq!(flipped.triangles(), &[[0, 2, 1]]);
    assert!((flipped.normals()[0] + v(1.0, 1.0, 1.0).normalize()).length() <= 1e-15);
}

// ---------------------------------------------------------------------------------------------
// Validation messages.

fn obj_error(text: &str) -> MeshError {
    Mesh::from_obj("bad.obj", text.as_bytes(), &MeshTransform::default()).unwrap_err()
}

fn stl_error(text: &str) -> MeshError {
    Mesh::from_stl("bad.stl", text.as_bytes(), &MeshTransform::default()).unwrap_err()
}

fn says(e: &MeshError, parts: &[&str]) {
    let message = e.to_string();
    for part in parts {
        assert!(message.contains(part), "'{message}' does not say '{part}'");
    }
}

const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

#[test]
fn each_validation_error_names_the_file_and_the_triangle() {
    let e = obj_error(&format!("{SQUARE}v nan 0 1\nf 1 2 3\nf 1 3 5\n"));
    assert!(matches!(e, MeshError::NonFinite { corner: 2, .. }));
    says(&e, &["bad.obj", "triangle 1 (line 7)", "corner 2", "not finite"]);

    let e = obj_error(&format!("{SQUARE}v 0.5 0.5 0\nf 1 2 3\nf 1 3 5\n"));
    says(&e, &["bad.obj", "triangle 1 (line 7)", "degenerate"]);
    // Corners that weld into one make a degenerate triangle too.
    let e = obj_error(&format!("{SQUARE}v 1 0 0\nf 1 2 3\nf 1 2 5\n"));
    says(&e, &["triangle 1 (line 7)", "degenerate"]);
    // A sliver at the limit: height 1e-13 of its length.
    let e = obj_error("v 0 0 0\nv 1 0 0\nv 0.5 1e-13 0\nf 1 2 3\n");
    says(&e, &["triangle 0 (line 4)", "degenerate"]);

    let e = obj_error(&format!("{SQUARE}f 1 2 3\nf 1 3 4\nf 3 1 2\n"));
    says(&e, &["bad.obj", "triangle 2 (line 7) repeats triangle 0 (line 5)"]);

    let e = obj_error(&format!("{SQUARE}f 1 2 3\nf 1 4 3\n"));
    assert!(matches!(e, MeshError::Orientation { .. }));
    says(&e, &["bad.obj", "triangle 1 (line 6) and triangle 0 (line 5)", "same direction", "[1, 1, 0]"]);

    let e = obj_error(&format!("{SQUARE}v 0 0 1\nf 1 2 3\nf 1 3 4\nf 3 1 5\n"));
    assert!(matches!(e, MeshError::NonManifold { .. }));
    says(
        &e,
        &[
            "bad.obj",
            "triangle 2 (line 8) is a third triangle",
            "triangle 0 (line 6) and triangle 1 (line 7)",
        ],
    );

    says(&obj_error(SQUARE), &["bad.obj", "no triangles"]);
    says(&stl_error("solid empty\nendsolid empty\n"), &["bad.stl", "no triangles"]);
    // A binary STL names the facet by its index.
    let triangles = [
        [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)],
        [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(4.0, 0.0, 0.0)],
    ];
    let e = Mesh::from_stl("bad.stl", &binary_stl(&triangles, ""), &MeshTransform::default()).unwrap_err();
    says(&e, &["bad.stl: triangle 1 is degenerate"]);
    let e = Mesh::from_indexed("generated", &[v(0.0, 0.0, 0.0)], &[[0, 0, 3]], &MeshTransform::default())
        .unwrap_err();
    says(&e, &["generated: triangle 0: vertex index 3 is out of range (1 vertices)"]);
}

#[test]
fn syntax_and_file_errors_name_the_line() {
    says(&obj_error(&format!("{SQUARE}f 1 2 7\n")), &["bad.obj", "triangle 0 (line 5)", "vertex index 7"]);
    says(&obj_error(&format!("{SQUARE}f 1 -5 3\n")), &["line 5", "vertex index -5"]);
    says(&obj_error(&format!("{SQUARE}f 1 0 3\n")), &["bad.obj:5:", "index 0"]);
    says(&obj_error(&format!("{SQUARE}f 1 2\n")), &["bad.obj:5:", "three or more"]);
    says(&obj_error("v 0 0\n"), &["bad.obj:1:", "three coordinates"]);
    says(&obj_error("v 0 zero 0\n"), &["bad.obj:1:", "'zero' is not a number"]);
    says(&obj_error(&format!("{SQUARE}f 1 2 x/1\n")), &["bad.obj:5:", "'x/1'"]);
    let facet = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n";
    says(&stl_error(&format!("{facet}vertex 0 1\n")), &["bad.stl:6:", "three coordinates"]);
    says(&stl_error(&format!("{facet}endloop\n")), &["bad.stl:6:", "2 vertices"]);
    says(
        &stl_error(&format!("{facet}vertex 0 1 0\nendloop\nendfacet\n")),
        &["bad.stl:8:", "ends", "'endsolid'"],
    );
    says(&stl_error("solid s\nfacet 0 0 1\n"), &["bad.stl:2:", "'normal' must follow"]);
    says(&stl_error("solid s\nvertex 0 0 0\n"), &["bad.stl:2:", "unexpected 'vertex'"]);
    says(&stl_error("not an stl"), &["bad.stl", "fewer than a binary STL's 84-byte header"]);
    let mut truncated = binary_stl(&[[v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]], "");
    truncated.pop();
    let e = Mesh::from_stl("cut.stl", &truncated, &MeshTransform::default()).unwrap_err();
    says(&e, &["cut.stl", "1 triangles", "134 bytes, it has 133"]);
    let mut solid = binary_stl(&[[v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]], "solid");
    solid.push(0);
    let e = Mesh::from_stl("cut.stl", &solid, &MeshTransform::default()).unwrap_err();
    says(&e, &["cut.stl", "starts with 'solid'", "binary data"]);

    let e = Mesh::load(Path::new("hopper.ply"), &MeshTransform::default()).unwrap_err();
    assert_eq!(e, MeshError::Format { file: "hopper.ply".into() });
    let e = Mesh::load(&data("missing.stl"), &MeshTransform::default()).unwrap_err();
    says(&e, &["missing.stl: cannot read it"]);
    let bad = MeshTransform { scale: 0.0, ..MeshTransform::default() };
    let e = Mesh::load(&data("roof.stl"), &bad).unwrap_err();
    says(&e, &["roof.stl: transform: scale = 0 must be finite and positive"]);
    let bad = MeshTransform { rotation_deg: [0.0, f64::NAN, 0.0], ..MeshTransform::default() };
    says(&Mesh::load(&data("roof.stl"), &bad).unwrap_err(), &["rotation angle NaN° is not finite"]);
    // A transform that overflows is caught as a corner that is not finite.
    let huge = MeshTransform { scale: 1e10, ..MeshTransform::default() };
    let e = Mesh::from_obj("big.obj", format!("{SQUARE}v 1e300 0 0\nf 1 2 3\nf 5 3 4\n").as_bytes(), &huge);
    says(&e.unwrap_err(), &["big.obj: triangle 1 (line 7): corner 0 is not finite", "[inf, "]);
}
