//! Mesh walls through the whole time step, against the analytic plane walls they triangulate
//! (issue #28): impacts on a floor of 20 000 random triangles with slivers, anywhere and exactly
//! on edges and vertices; rolling and sliding across its seams; a closed box of triangles full
//! of particles against the box of six planes; concave corners of two and three faces against
//! two and three planes; and the one contact of a sphere on a convex edge.
//!
//! ## Why the mesh and the plane can agree to 1e-12
//! Every mesh here lies in coordinate planes (z = 0, x = 0, …) with coordinates that are
//! exact in binary. A triangle in a coordinate plane has exactly the axis as its normal, and its
//! plane distance (c − a)·n is then the one coordinate difference c_z − a_z, rounded once,
//! which is what the plane wall computes as (c − p)·n; an edge or vertex inside a flat patch is
//! touched as the plane of its triangle. So each contact has the plane's normal and overlap to
//! the bit or to one rounding, and the contact law then gives the same load. What is left is
//! the rounding of the loads to the order-free sums' quanta (2⁻⁴¹ of the peak load, the same in
//! both runs where the peaks agree) and the different routes of the plane and mesh stages (the
//! plane's vector lanes, the mesh's scalar law): a few ulps of a load. Over the short runs here,
//! a contact's dynamics do not amplify a few ulps beyond 1e-12 of the state's scale; where a
//! test is chaotic (many particles) its tolerance says why it still holds.

mod common;

use common::*;
use grainflow::contact::{ContactLaw, ContactParams, NormalModel};
use grainflow::mesh::{Mesh, MeshContact, MeshTransform, MeshWall, TriangleGrid, sphere_contacts};
use grainflow::state::ParticleInit;
use grainflow::{Integrator, Simulation, SimulationConfig, Vec3, Wall};
use std::sync::OnceLock;

/// The beads' radius, m (1 mm glass beads).
const R: f64 = 5e-4;
const DENSITY: f64 = 2500.0;
const GRAVITY: Vec3 = Vec3::new(0.0, 0.0, -9.81);

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

fn mesh(name: &str, vertices: &[Vec3], triangles: &[[u32; 3]]) -> Mesh {
    match Mesh::from_indexed(name, vertices, triangles, &MeshTransform::default()) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Laws.

/// The laws the tests run: MFIX's LSD and Hertz, LAMMPS's hooke/history and Hertz–Mindlin, and
/// JKR (LAMMPS's `granular jkr … damping tsuji`), each with its wall parameters.
fn laws() -> Vec<(&'static str, ContactLaw, ContactParams)> {
    let (hooke, hooke_params) = lammps_hooke();
    let (mindlin, mindlin_params) = lammps_mindlin();
    let jkr = ContactLaw { normal: NormalModel::Jkr, ..mindlin };
    // A surface energy whose pull-off force 3πγR (2.4e-5 N) is twice the bead's weight: the
    // contact holds past the touch and lets go at the pull-off distance, but the bead rebounds.
    let jkr_params = ContactParams { surface_energy: Some(5e-3), ..mindlin_params };
    vec![
        ("LSD", ContactLaw::mfix(NormalModel::LinearSpringDashpot), lsd_params(500.0, 0.8, 0.3)),
        ("Hertz", ContactLaw::mfix(NormalModel::Hertz), hertz_params(0.8, 0.9, 0.3)),
        ("LAMMPS hooke", hooke, hooke_params),
        ("LAMMPS Hertz-Mindlin", mindlin, mindlin_params),
        ("JKR", jkr, jkr_params),
    ]
}

/// A configuration of glass beads (E = 10 MPa, ν = 0.3) against steel-like walls of the same
/// stiffness, with `law` and `params` for pairs and walls, velocity Verlet with `dt`.
fn setup(
    law: ContactLaw,
    params: ContactParams,
    walls: Vec<Wall>,
    meshes: Vec<Mesh>,
    gravity: Vec3,
    dt: f64,
) -> SimulationConfig {
    let mut cfg = config(
        law,
        vec![elastic_phase("glass", 2.0 * R, DENSITY, 1e7, 0.3)],
        vec![wall_material("steel", Some(1e7), Some(0.3))],
        walls,
        vec![params],
        vec![params],
        Integrator::VelocityVerlet,
        dt,
    );
    cfg.meshes = meshes.into_iter().map(|mesh| MeshWall::fixed(mesh, 0)).collect();
    cfg.gravity = gravity;
    cfg
}

/// A bead at `x` with velocity `v0` and spin `w0`.
fn bead(x: Vec3, v0: Vec3, w0: Vec3) -> ParticleInit {
    let mut p = particle(1, 0, R, DENSITY, x, v0);
    p.omega = w0;
    p
}

/// The plane run and the mesh run of the same case: the same configuration with `planes`, or
/// with `meshes` instead.
#[allow(clippy::too_many_arguments)]
fn pair_of_runs(
    (law, params): (ContactLaw, ContactParams),
    planes: Vec<Wall>,
    meshes: Vec<Mesh>,
    gravity: Vec3,
    dt: f64,
    init: &[ParticleInit],
) -> (Simulation, Simulation) {
    let plane = simulation(setup(law, params, planes, vec![], gravity, dt), init);
    let mesh = simulation(setup(law, params, vec![], meshes, gravity, dt), init);
    (plane, mesh)
}

/// The largest difference of the two runs' particles' positions, velocities and spins,
/// relative to the scales `x` (m), `u` (m/s) and `u/R` (rad/s).
fn differ(a: &Simulation, b: &Simulation, x: f64, u: f64) -> f64 {
    let (p, q) = (a.particles(), b.particles());
    let mut worst = 0.0f64;
    for i in 0..p.len() {
        assert_eq!(p.id[i], q.id[i]);
        worst = worst
            .max((p.position[i] - q.position[i]).length() / x)
            .max((p.velocity[i] - q.velocity[i]).length() / u)
            .max((p.omega[i] - q.omega[i]).length() / (u / R));
    }
    worst
}

// ---------------------------------------------------------------------------------------------
// 1. Impacts on a floor of 20 000 random triangles with slivers.

/// Cells of the random floor per side, the floor's half width (m) and the rows of the cells
/// whose top line is doubled into a sliver strip.
const CELLS: usize = 100;
const HALF: f64 = 0.01;
const STRIPS: [usize; 3] = [31, 50, 68];
/// The height of a sliver strip, m: its triangles are up to 2·HALF = 0.02 m long, so their
/// area over their longest side squared goes down to about 3e-9 (1e-12 is degenerate).
const STRIP: f64 = 2e-8;

/// The floor z = 0 over [−HALF, HALF]²: a CELLS × CELLS grid whose inner vertices are jittered
/// by up to ±0.2 of a cell (each quad stays convex: a corner moves less than 0.29 of a cell,
/// its opposite diagonal as much, while 0.71 apart), each quad split along a random diagonal;
/// and three strips of height [`STRIP`] along rows of the grid, each triangulated as two fans
/// (every bottom side to the strip's top-left vertex, every top side to its bottom-right one),
/// so that their triangles are long thin slivers across the whole floor. Conforming, exactly
/// planar (every z is 0), normals +z. Returns the mesh and the strips' mid lines y.
fn random_floor() -> &'static (Mesh, Vec<f64>) {
    static FLOOR: OnceLock<(Mesh, Vec<f64>)> = OnceLock::new();
    FLOOR.get_or_init(|| {
        let mut rng = Rng::new(28);
        let h = 2.0 * HALF / CELLS as f64;
        let n = CELLS;
        // The horizontal lines: (y, whether it bounds a strip), bottom to top.
        let mut lines = Vec::new();
        for j in 0..=n {
            let y = -HALF + j as f64 * h;
            let strip = STRIPS.contains(&j);
            lines.push((y, strip || (j > 0 && STRIPS.contains(&(j - 1)))));
            if strip {
                lines.push((y + STRIP, true));
            }
        }
        let mut vertices = Vec::new();
        for (l, &(y, straight)) in lines.iter().enumerate() {
            let rim_y = l == 0 || l == lines.len() - 1;
            for i in 0..=n {
                let rim_x = i == 0 || i == n;
                let x = -HALF + i as f64 * h;
                let jx = if rim_x { 0.0 } else { rng.range(-0.2, 0.2) * h };
                let jy = if rim_y || straight { 0.0 } else { rng.range(-0.2, 0.2) * h };
                vertices.push(v(x + jx, y + jy, 0.0));
            }
        }
        let at = |l: usize, i: usize| (l * (n + 1) + i) as u32;
        let mut triangles = Vec::new();
        let mut mid_lines = Vec::new();
        for l in 0..lines.len() - 1 {
            if lines[l + 1].0 - lines[l].0 < h / 2.0 {
                // A strip: bottom line l, top line l + 1.
                for i in 0..n {
                    triangles.push([at(l, i), at(l, i + 1), at(l + 1, 0)]);
                }
                for i in 0..n {
                    triangles.push([at(l, n), at(l + 1, i + 1), at(l + 1, i)]);
                }
                mid_lines.push(lines[l].0 + 0.5 * STRIP);
                continue;
            }
            for i in 0..n {
                let (a, b, c, d) = (at(l, i), at(l, i + 1), at(l + 1, i + 1), at(l + 1, i));
                if rng.uniform() < 0.5 {
                    triangles.extend([[a, b, c], [a, c, d]]);
                } else {
                    triangles.extend([[a, b, d], [b, c, d]]);
                }
            }
        }
        (mesh("random floor", &vertices, &triangles), mid_lines)
    })
}

/// Area over longest side squared: 0.43 for an equilateral triangle, far less for a sliver.
fn shape([a, b, c]: [Vec3; 3]) -> f64 {
    let l2 = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
    0.5 * (b - a).cross(c - a).length() / l2
}

#[test]
fn the_random_floor_is_flat_conforming_and_has_long_slivers() {
    let (floor, _) = random_floor();
    assert!(floor.triangle_count() >= 20_000, "{} triangles", floor.triangle_count());
    assert!(floor.vertices().iter().all(|p| p.z == 0.0));
    assert!(floor.normals().iter().all(|&n| n == Vec3::Z));
    let thinnest = (0..floor.triangle_count() as u32).map(|t| shape(floor.corners(t))).fold(1.0, f64::min);
    let longest = (0..floor.triangle_count() as u32)
        .map(|t| {
            let [a, b, c] = floor.corners(t);
            (b - a).length().max((c - b).length()).max((a - c).length())
        })
        .fold(0.0, f64::max);
    assert!(thinnest < 1e-8 && longest > HALF, "thinnest {thinnest:e}, longest {longest:e} m");
    // Conforming: only the rim is open, and every inner edge is flat.
    use grainflow::mesh::EdgeKind;
    for e in floor.edges().iter().filter(|e| e.kind != EdgeKind::Flat) {
        assert_eq!(e.kind, EdgeKind::Boundary);
        let [a, b] = e.vertices.map(|i| floor.vertices()[i as usize]);
        let rim = |p: Vec3| p.x.abs() == HALF || p.y.abs() == HALF;
        assert!(rim(a) && rim(b), "an open edge inside the floor: {a} {b}");
    }
}

/// Where an impact starts: the (x, y) of the centre and what is under it.
#[derive(Debug, Clone, Copy)]
enum Spot {
    Anywhere(f64, f64),
    /// Exactly over a vertex.
    Vertex(Vec3),
    /// Exactly over a point of an edge (as far as a + s·(b − a) rounds).
    Edge(Vec3),
}

impl Spot {
    fn xy(self) -> (f64, f64) {
        match self {
            Spot::Anywhere(x, y) => (x, y),
            Spot::Vertex(p) | Spot::Edge(p) => (p.x, p.y),
        }
    }
}

/// Impact spots on the random floor, within its middle (the bead, 0.5 mm, and its travel
/// during the impact, < 0.1 mm, stay far from the rim): random points; random vertices,
/// among them vertices of the strips' fans; random points of random edges, among them the
/// long sliver edges of the strips; and the strips' mid lines.
fn spots() -> Vec<Spot> {
    let (floor, mid_lines) = random_floor();
    let mut rng = Rng::new(7);
    let inner = |p: Vec3| p.x.abs() < 0.6 * HALF && p.y.abs() < 0.6 * HALF;
    let mut out = vec![];
    for _ in 0..3 {
        out.push(Spot::Anywhere(rng.range(-0.5, 0.5) * HALF, rng.range(-0.5, 0.5) * HALF));
    }
    let vertices = floor.vertices();
    let on_strip = |p: Vec3| mid_lines.iter().any(|&m| (p.y - m).abs() < STRIP);
    let pick = |rng: &mut Rng, want_strip: bool| loop {
        let p = vertices[rng.index(vertices.len())];
        if inner(p) && on_strip(p) == want_strip {
            return p;
        }
    };
    for k in 0..3 {
        out.push(Spot::Vertex(pick(&mut rng, k == 0)));
    }
    let edges = floor.edges();
    let mut sliver_edge = 0;
    while out.len() < 9 {
        let e = &edges[rng.index(edges.len())];
        let [a, b] = e.vertices.map(|i| vertices[i as usize]);
        // One in three from the strips' long edges (longer than two cells).
        let long = (b - a).length() > 4.0 * HALF / CELLS as f64;
        if long != (sliver_edge < 2) {
            continue;
        }
        let p = a + rng.uniform() * (b - a);
        if inner(p) {
            sliver_edge += long as usize;
            out.push(Spot::Edge(p));
        }
    }
    for &m in mid_lines {
        out.push(Spot::Anywhere(rng.range(-0.5, 0.5) * HALF, m));
    }
    out
}

/// The impacts' launch: a normal one spinning about the normal (the centre then stays over the
/// spot to the bit: its contact force is along z, its contact point at rest), and an oblique
/// one with spin (which slides, and rolls across seams, while in contact).
const LAUNCHES: [(Vec3, Vec3); 2] = [
    (Vec3::new(0.0, 0.0, -0.5), Vec3::new(0.0, 0.0, 400.0)),
    (Vec3::new(0.3, -0.2, -0.5), Vec3::new(200.0, 300.0, -100.0)),
];

// A normal impact on the plane lasts some 150 µs for these laws; 2e-7 s resolves it in 750
// steps.
const IMPACT_DT: f64 = 2e-7;

/// One impact on the random floor and on the plane z = 0: the worst state difference while
/// the runs last ([`differ`], scales R and |v0|), the final velocity and spin differences
/// relative to |v0| and |v0|/R, and the steps in contact.
fn impact(
    law: (ContactLaw, ContactParams),
    spot: Spot,
    (v0, w0): (Vec3, Vec3),
    z0: f64,
) -> (f64, f64, usize) {
    let (floor, _) = random_floor();
    let (x, y) = spot.xy();
    let init = [bead(v(x, y, z0), v0, w0)];
    let planes = vec![Wall::plane("floor", Vec3::ZERO, Vec3::Z, 0)];
    let (mut plane, mut mesh) = pair_of_runs(law, planes, vec![floor.clone()], GRAVITY, IMPACT_DT, &init);
    let u = v0.length();
    let (mut worst, mut touched) = (0.0f64, 0);
    for _ in 0..20_000 {
        plane.step();
        mesh.step();
        worst = worst.max(differ(&plane, &mesh, R, u));
        let (a, b) = (plane.diagnostics(), mesh.diagnostics());
        assert_eq!(a.contacts, b.contacts, "at step {}: contact counts differ", plane.step_index());
        touched += a.contacts;
        let p = plane.particles();
        if touched > 0 && a.contacts == 0 && p.velocity[0].z > 0.0 {
            break;
        }
    }
    let (p, q) = (plane.particles(), mesh.particles());
    assert!(touched > 100 && q.velocity[0].z > 0.0, "no rebound at {spot:?}");
    let last =
        ((p.velocity[0] - q.velocity[0]).length() / u).max((p.omega[0] - q.omega[0]).length() / (u / R));
    (worst, last, touched)
}

/// A bead hitting the random floor — anywhere, exactly on an edge (long slivers among them),
/// exactly on a vertex (the strips' among them, where slivers meet) — rebounds as off the plane
/// z = 0: the same state all through the impact and the same velocity and spin after it, to
/// 1e-12 of their scales (see the module doc: the floor is exactly planar, so every contact is
/// the plane's to one rounding), for every law.
#[test]
fn an_impact_anywhere_on_a_random_floor_is_the_planes() {
    let mut report = Vec::new();
    for (what, law, params) in laws() {
        let mut worst = 0.0f64;
        for spot in spots() {
            for launch in LAUNCHES {
                // Launched just touching at the spot (overlap 1e-9·R, clear of the edge case of
                // a zero overlap, tested on its own below): the first contact is exactly there.
                let (during, after, _) = impact((law, params), spot, launch, R * (1.0 - 1e-9));
                assert!(
                    during < 1e-12 && after < 1e-12,
                    "{what} at {spot:?}, {launch:?}: {during:e} {after:e}"
                );
                worst = worst.max(during).max(after);
            }
        }
        report.push(format!("{what}: {worst:e}"));
    }
    println!("worst relative differences: {}", report.join(", "));
}

/// A bead launched exactly touching the floor (centre at z = R, overlap 0) is in contact from
/// the first force evaluation, as with the plane wall, whose contact test is overlap ≥ 0: the
/// LSD and Hertz dashpots already push at zero overlap (−η·v_n), so a mesh that took the touch
/// for no contact would part from the plane at once (by 3e-4 of the bead's velocity, the
/// dashpot's impulse over one step). Same tolerance as the impacts above.
#[test]
fn a_bead_exactly_touching_the_floor_is_in_contact_as_with_the_plane() {
    for (what, law, params) in laws().into_iter().filter(|(_, law, _)| !law.normal.reaches()) {
        for spot in spots() {
            for launch in LAUNCHES {
                let (during, after, _) = impact((law, params), spot, launch, R);
                assert!(
                    during < 1e-12 && after < 1e-12,
                    "{what} at {spot:?}, {launch:?}: {during:e} {after:e}"
                );
            }
        }
    }
}

/// The same for JKR: the mesh stage finds its contacts out to the radius plus the pull-off
/// distance, but forms the overlap as R − d, as the plane does (not (R + δ_c − d) − δ_c, which
/// rounds either side of 0 at the exact touch and would refuse a contact not yet formed).
#[test]
fn a_jkr_bead_exactly_touching_the_floor_is_in_contact_as_with_the_plane() {
    let (what, law, params) = laws().pop().unwrap();
    assert_eq!(law.normal, NormalModel::Jkr);
    for spot in spots() {
        let (during, after, _) = impact((law, params), spot, LAUNCHES[0], R);
        assert!(during < 1e-12 && after < 1e-12, "{what} at {spot:?}: {during:e} {after:e}");
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Rolling and sliding across the seams of the random floor.

/// The contacts of a sphere with `mesh` by the geometry alone (for counting seams), with the
/// candidates of `grid`.
fn touched(mesh: &Mesh, grid: &TriangleGrid, centre: Vec3, radius: f64) -> Vec<MeshContact> {
    let (mut near, mut out) = (Vec::new(), Vec::new());
    grid.near(mesh, centre, radius, &mut near);
    sphere_contacts(mesh, &near, centre, radius, &mut out);
    out
}

/// An elastic bead (e_n = 1: no normal dashpot) set down on the random floor at its static
/// overlap, sliding at 0.3 m/s without spin: friction turns the slip into rolling within
/// 0.03 s, and it rolls on, across some 100 seams of the jittered grid and a sliver strip, or
/// along the strip's mid line over its slivers (2e-8 m high, up to 0.02 m long), for LSD and
/// Hertz.
/// Step by step its contact force, torque and elastic energy, and the total energy, are the
/// plane's: no jump at a seam. Tolerances: the overlap R − z (3e-8 m for LSD, 2e-7 m for
/// Hertz) is formed from z ≈ R = 5e-4 m, so it is known only to about ε·R = 1e-19 m, 4e-12 of
/// it; a load or an energy (∝ δ to δ^2.5) to 1e-11 then, plus the load quanta (2⁻⁴⁰ of the
/// peak, 1e-12). The total energy, mostly kinetic, is compared to 1e-12 of itself (the states
/// agree to 1e-12 of their scales, as for the impacts).
#[test]
fn rolling_and_sliding_across_seams_feels_the_plane() {
    let (floor, mid_lines) = random_floor();
    let grid = TriangleGrid::new(floor, 2.0 * R);
    let elastic = [
        ("LSD", ContactLaw::mfix(NormalModel::LinearSpringDashpot), lsd_params(500.0, 1.0, 0.3)),
        ("Hertz", ContactLaw::mfix(NormalModel::Hertz), hertz_params(1.0, 1.0, 0.3)),
    ];
    let strip = mid_lines[1];
    for (what, law, params) in elastic {
        let dt = 2e-6;
        let probe = simulation(
            setup(law, params, vec![], vec![], GRAVITY, dt),
            &[bead(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO)],
        );
        let kn = probe.coefficients().wall(0, 0).kn;
        let weight = probe.particles().mass[0] * GRAVITY.length();
        let static_overlap =
            if law.normal == NormalModel::Hertz { (weight / kn).powf(2.0 / 3.0) } else { weight / kn };
        // Across the grid and the strip, and along the strip's mid line (the centre's y stays
        // there to the bit: the slip, hence friction, is along x).
        for (start, v0) in
            [(v(-0.007, strip - 1e-3, 0.0), v(0.3, 0.05, 0.0)), (v(-0.007, strip, 0.0), v(0.3, 0.0, 0.0))]
        {
            let init = [bead(start + v(0.0, 0.0, R - static_overlap), v0, Vec3::ZERO)];
            let planes = vec![Wall::plane("floor", Vec3::ZERO, Vec3::Z, 0)];
            let (mut plane, mut mesh) =
                pair_of_runs((law, params), planes, vec![floor.clone()], GRAVITY, dt, &init);
            let (mut worst_load, mut worst_elastic, mut worst_total) = (0.0f64, 0.0f64, 0.0f64);
            let (mut seams, mut owner, mut on_strip) = (0, None, 0);
            let rel = |a: f64, b: f64| if a == b { 0.0 } else { (a - b).abs() / a.abs().max(b.abs()) };
            for _ in 0..20_000 {
                plane.step();
                mesh.step();
                let (p, q) = (plane.particles(), mesh.particles());
                let (a, b) = (plane.diagnostics(), mesh.diagnostics());
                assert!(
                    a.contacts == 1 && b.contacts == 1,
                    "{what}: the bead left the floor at {}",
                    p.position[0]
                );
                let load = ((p.force[0] - q.force[0]).length() / p.force[0].length())
                    .max((p.torque[0] - q.torque[0]).length() / (R * p.force[0].length()));
                worst_load = worst_load.max(load);
                worst_elastic = worst_elastic.max(rel(a.elastic, b.elastic));
                worst_total = worst_total.max(rel(a.total_energy(), b.total_energy()));
                let found = touched(floor, &grid, q.position[0], R);
                assert_eq!(found.len(), 1, "{what}: {found:?}");
                seams += (owner.is_some_and(|t| t != found[0].triangle)) as usize;
                owner = Some(found[0].triangle);
                on_strip += ((q.position[0].y - strip).abs() < STRIP) as usize;
            }
            let p = mesh.particles();
            let slip = p.velocity[0] + p.omega[0].cross(v(0.0, 0.0, -R));
            assert!(slip.length() < 1e-3, "{what}: not rolling at the end (slip {slip})");
            if v0.y == 0.0 {
                assert_eq!(on_strip, 20_000, "{what}: the bead left the strip's mid line");
            } else {
                assert!(p.position[0].y > strip, "{what}: the bead did not cross the strip");
            }
            assert!(seams > 40, "{what}: only {seams} seams crossed");
            println!(
                "{what}: {seams} seams ({on_strip} steps over a strip): load {worst_load:e}, elastic {worst_elastic:e}, \
             total {worst_total:e}"
            );
            assert!(worst_load < 1e-11 && worst_elastic < 1e-11 && worst_total < 1e-12, "{what}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 3. A closed box of triangles.

/// The faces of the box [0, L]³ with `m` × `m` squares a face, each split along a random
/// diagonal, normals inwards: 12·m² triangles. Every coordinate is one of L·(i/m), the same
/// bits on every face, so the faces weld along the box's edges, and each face lies exactly in
/// its coordinate plane.
fn box_mesh(l: f64, m: usize, seed: u64) -> Mesh {
    let mut rng = Rng::new(seed);
    // l·(i/m), not l·i/m: the far faces then lie at l exactly, where the plane walls are.
    let c: Vec<f64> = (0..=m).map(|i| l * (i as f64 / m as f64)).collect();
    let id = |i: usize, j: usize, k: usize| ((k * (m + 1) + j) * (m + 1) + i) as u32;
    let vertices: Vec<Vec3> = (0..(m + 1).pow(3))
        .map(|n| v(c[n % (m + 1)], c[(n / (m + 1)) % (m + 1)], c[n / (m + 1).pow(2)]))
        .collect();
    let mut triangles = Vec::new();
    for axis in 0..3 {
        // (b, c) cyclic after the axis: e_b × e_c = e_axis, the inward normal of the face at 0;
        // the face at L turns round by taking them the other way.
        let (b, cc) = ((axis + 1) % 3, (axis + 2) % 3);
        for (side, (u, w)) in [(0, (b, cc)), (m, (cc, b))] {
            let at = |p: usize, q: usize| {
                let mut ijk = [0; 3];
                ijk[axis] = side;
                ijk[u] = p;
                ijk[w] = q;
                id(ijk[0], ijk[1], ijk[2])
            };
            for p in 0..m {
                for q in 0..m {
                    let (a, b1, c1, d) = (at(p, q), at(p + 1, q), at(p + 1, q + 1), at(p, q + 1));
                    if rng.uniform() < 0.5 {
                        triangles.extend([[a, b1, c1], [a, c1, d]]);
                    } else {
                        triangles.extend([[a, b1, d], [b1, c1, d]]);
                    }
                }
            }
        }
    }
    let mesh = mesh("box", &vertices, &triangles);
    let inward = |t: u32| {
        let centroid = mesh.corners(t).iter().sum::<Vec3>() / 3.0;
        mesh.normals()[t as usize].dot(Vec3::splat(l / 2.0) - centroid) > 0.0
    };
    assert!((0..mesh.triangle_count() as u32).all(inward), "the box's normals must point inwards");
    mesh
}

/// Particles in the box [0, L]³: one in each corner and one at the middle of each edge,
/// touching the walls there (overlap 1e-3 of the radius); four on the floor over the faces'
/// seams (two over vertices, two over edges of the subdivision); the rest at random, apart;
/// radii 0.97R to R. All but those in the corners and on the edges with random velocities of
/// 0.3 m/s and spins.
fn box_particles(l: f64, m: usize, count: usize, seed: u64) -> Vec<ParticleInit> {
    let mut rng = Rng::new(seed);
    let radius = |rng: &mut Rng| R * rng.range(0.97, 1.0);
    let mut placed: Vec<(Vec3, f64)> = Vec::new();
    let near = |r: f64| r * (1.0 - 1e-3);
    let wall_at = |s: usize, r: f64| if s == 0 { near(r) } else { l - near(r) };
    for corner in 0..8 {
        let r = radius(&mut rng);
        placed.push((v(wall_at(corner & 1, r), wall_at((corner >> 1) & 1, r), wall_at(corner >> 2, r)), r));
    }
    for axis in 0..3 {
        for s in 0..4 {
            let r = radius(&mut rng);
            let mut x = [l / 2.0; 3];
            x[(axis + 1) % 3] = wall_at(s & 1, r);
            x[(axis + 2) % 3] = wall_at(s >> 1, r);
            placed.push((Vec3::from_array(x), r));
        }
    }
    let h = l / m as f64;
    for (x, y) in [(h, h), (2.0 * h, 2.0 * h), (1.5 * h, h), (2.0 * h, 0.5 * h)] {
        let r = radius(&mut rng);
        placed.push((v(x, y, near(r)), r));
    }
    while placed.len() < count {
        let r = radius(&mut rng);
        let x = rng.in_box(Vec3::splat(R), Vec3::splat(l - R));
        if placed.iter().all(|&(y, s)| (x - y).length() > 1.05 * (r + s)) {
            placed.push((x, r));
        }
    }
    for (k, a) in placed.iter().enumerate() {
        for b in &placed[..k] {
            assert!((a.0 - b.0).length() > a.1 + b.1, "particles {a:?} and {b:?} overlap");
        }
    }
    placed
        .into_iter()
        .enumerate()
        .map(|(k, (x, r))| {
            // Those in the corners and along the edges start at rest (the lower ones stay there,
            // hit by the others); the rest move.
            let moving = k >= 20;
            let u = if moving { 0.3 } else { 0.0 };
            let mut p = particle(k as u32 + 1, 0, r, DENSITY, x, u * rng.unit());
            p.omega = (u * 1000.0 * rng.uniform()) * rng.unit();
            p
        })
        .collect()
}

/// Forty beads bouncing about a closed 6 mm box of 108 triangles (each face 3 × 3 squares), in
/// its corners, along its edges and over its seams from the start, under gravity tilted into
/// a corner where they settle, for LSD and Hertz: the total energy (kinetic, potential, elastic) is that of the same box of six
/// plane walls step for step, and so are the contact count and every particle's state.
/// Every face lies exactly in its coordinate plane, so every contact is a plane's to the bit
/// or to one rounding (module doc), and a corner's three contacts are its three planes'. In a
/// bed of colliding beads a difference of an ulp grows with every collision, so the tolerance,
/// 1e-12 of the total energy and of the state's scales (L, 0.3 m/s), allows a few ulps grown
/// over a few collisions, not a mesh contact that differs from its plane's.
#[test]
fn a_closed_box_of_triangles_holds_beads_as_six_planes() {
    let (l, m) = (0.006, 3);
    let mesh = box_mesh(l, m, 3);
    assert_eq!(mesh.triangle_count(), 12 * m * m);
    assert_eq!(mesh.bounds(), (Vec3::ZERO, Vec3::splat(l)));
    let init = box_particles(l, m, 40, 11);
    for (what, law, params) in laws().into_iter().take(2) {
        let planes = Wall::domain_box(Vec3::ZERO, Vec3::splat(l), 0);
        // Gravity tilted towards the corner at the origin, so that the beads settle into it and
        // along its three edges, pressed against two or three faces at once.
        let g = 9.81 * v(-0.35, -0.25, -1.0).normalize();
        let (mut plane, mut boxed) = pair_of_runs((law, params), planes, vec![mesh.clone()], g, 2e-6, &init);
        let grid = TriangleGrid::new(&mesh, 2.0 * R);
        let (mut worst, mut worst_state, mut on_edges, mut in_corners) = (0.0f64, 0.0f64, 0, 0);
        let e0 = plane.diagnostics().total_energy();
        for _ in 0..50_000 {
            plane.step();
            boxed.step();
            let (a, b) = (plane.diagnostics(), boxed.diagnostics());
            assert_eq!(a.contacts, b.contacts, "{what}: contact counts differ at step {}", a.step);
            worst = worst.max((a.total_energy() - b.total_energy()).abs() / a.total_energy().abs());
            worst_state = worst_state.max(differ(&plane, &boxed, l, 0.3));
            // Beads touching two faces (along an edge of the box) and three (in a corner).
            let q = boxed.particles();
            for i in 0..q.len() {
                let faces = touched(&mesh, &grid, q.position[i], q.radius[i]).len();
                on_edges += (faces >= 2) as usize;
                in_corners += (faces == 3) as usize;
            }
        }
        let e1 = plane.diagnostics().total_energy();
        println!(
            "{what}: energy {e0:e} → {e1:e} J; {on_edges} bead-steps on edges, {in_corners} in corners; \
             worst energy {worst:e}, state {worst_state:e}"
        );
        assert!(e1 < 0.8 * e0, "{what}: the beads did not collide much");
        assert!(on_edges > 20_000 && in_corners > 5_000, "{what}: too few contacts on edges and corners");
        assert!(worst < 1e-12 && worst_state < 1e-12, "{what}: {worst:e} {worst_state:e}");
    }
}

// ---------------------------------------------------------------------------------------------
// 4. Concave corners, and convex edges.

/// Faces of the box [lo, hi] as triangles, `m` × `m` squares a face, each split along a random
/// diagonal: for each (axis, at the high end, normal towards the box's inside) the face there.
/// Coordinates are lo + (hi − lo)·(i/m), and exactly hi at i = m, shared by every face.
fn faces(lo: Vec3, hi: Vec3, m: usize, seed: u64, which: &[(usize, bool, bool)]) -> Mesh {
    let mut rng = Rng::new(seed);
    let coord = |a: usize, i: usize| {
        let (l, h) = (lo.to_array()[a], hi.to_array()[a]);
        if i == m { h } else { l + (h - l) * (i as f64 / m as f64) }
    };
    let mut vertices = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut id = |ijk: [usize; 3]| {
        *index.entry(ijk).or_insert_with(|| {
            vertices.push(v(coord(0, ijk[0]), coord(1, ijk[1]), coord(2, ijk[2])));
            (vertices.len() - 1) as u32
        })
    };
    let mut triangles = Vec::new();
    for &(axis, high, inward) in which {
        // e_b × e_c = e_axis: (b, c) winds a face whose normal is +e_axis, (c, b) one facing −e_axis.
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        let (u, w) = if inward != high { (b, c) } else { (c, b) };
        for p in 0..m {
            for q in 0..m {
                let mut at = |p: usize, q: usize| {
                    let mut ijk = [0; 3];
                    ijk[axis] = if high { m } else { 0 };
                    ijk[u] = p;
                    ijk[w] = q;
                    id(ijk)
                };
                let (a, b1, c1, d) = (at(p, q), at(p + 1, q), at(p + 1, q + 1), at(p, q + 1));
                if rng.uniform() < 0.5 {
                    triangles.extend([[a, b1, c1], [a, c1, d]]);
                } else {
                    triangles.extend([[a, b1, d], [b1, c1, d]]);
                }
            }
        }
    }
    mesh("faces", &vertices, &triangles)
}

/// A bead thrown into a concave corner of triangles — a floor and a wall (two faces of 4 × 4
/// squares meeting along a crease), or a floor and two walls (three faces meeting at a corner)
/// — rolls into it, bounces off the walls and settles under gravity tilted towards it, as into the same
/// corner of two or three plane walls: the same state step by step to 1e-12 of its scales
/// (R, |v0|), for every law but JKR (each face lies in its coordinate plane: module doc),
/// ending in the corner. The faces (10 mm, 30 mm along the
/// crease) are large enough that the bead stays over them.
#[test]
fn a_concave_corner_of_triangles_is_two_or_three_planes() {
    // 30 mm along y, the free direction of the crease, along which the bead may drift.
    let l = 0.01;
    let (lo, hi) = (Vec3::ZERO, v(l, 3.0 * l, l));
    let floor = (2, false, true);
    let cases = [
        (vec![floor, (0, false, true)], v(-1.0, 0.0, -1.0)),
        (vec![floor, (0, false, true), (1, false, true)], v(-1.0, -0.8, -1.2)),
    ];
    let mut report = Vec::new();
    for (which, towards) in cases {
        let corner = faces(lo, hi, 4, 5, &which);
        assert_eq!(corner.triangle_count(), 32 * which.len());
        let planes: Vec<Wall> = which
            .iter()
            .map(|&(axis, _, _)| Wall::plane("face", Vec3::ZERO, [Vec3::X, Vec3::Y, Vec3::Z][axis], 0))
            .collect();
        // Set down on the floor, rolling towards the wall(s) and spinning about the vertical.
        let start = if which.len() == 2 { v(1.5e-3, 1.5 * l, R) } else { v(1.5e-3, 1.5e-3, R) };
        let v0 = if which.len() == 2 { v(-0.1, 0.0, 0.0) } else { v(-0.1, -0.05, 0.0) };
        let w0 = v(-v0.y / R, v0.x / R, 100.0);
        // Not JKR: the mesh stage forms its overlap as (R + δ_c − d) − δ_c, one rounding off the
        // plane's R − d (some 1e-20 m), and each sticky bounce in the corner, where the contact
        // holds or lets go near the pull-off distance, amplifies a difference about tenfold (a
        // few 1e-14 after the first, 4e-11 after the fourth). The impacts above compare JKR
        // with the plane where no such amplification occurs.
        for (what, law, params) in laws().into_iter().filter(|(_, law, _)| law.normal != NormalModel::Jkr) {
            let (mut plane, mut mesh) = pair_of_runs(
                (law, params),
                planes.clone(),
                vec![corner.clone()],
                9.81 * towards.normalize(),
                5e-6,
                &[bead(start, v0, w0)],
            );
            let (mut worst, mut in_corner) = (0.0f64, 0);
            for _ in 0..120_000 {
                plane.step();
                mesh.step();
                worst = worst.max(differ(&plane, &mesh, R, v0.length()));
                let contacts = mesh.diagnostics().contacts;
                assert_eq!(plane.diagnostics().contacts, contacts, "{what}, {} faces", which.len());
                in_corner += (contacts == which.len()) as usize;
                let x = mesh.particles().position[0];
                assert!(
                    x.cmpgt(Vec3::ZERO).all() && x.cmplt(hi - Vec3::splat(R)).all(),
                    "{what}: the bead left the faces at {x} (step {})",
                    mesh.step_index()
                );
            }
            // In the corner at the end (a lightly damped law, LAMMPS's hooke with e ≈ 0.95,
            // still chatters there), having touched all faces at once.
            let x = mesh.particles().position[0].to_array();
            let gaps = which.iter().map(|&(axis, _, _)| x[axis] - R).fold(0.0, f64::max);
            assert!(
                in_corner > 0 && gaps < 0.1 * R,
                "{what}: not in the corner ({in_corner} steps, gap {gaps:e} m)"
            );
            assert!(worst < 1e-12, "{what}, {} faces: {worst:e}", which.len());
            report.push(format!("{what}/{}: {worst:e} ({in_corner} steps in the corner)", which.len()));
        }
    }
    println!("worst relative differences: {}", report.join(", "));
}

/// A bead at rest on a convex edge feels exactly one contact, with the edge, whatever the
/// triangles around it: on the outer edge of a step (the top z = 0 and the side x = 0 of the
/// block [−L, 0] × [0, L] × [−L, 0], 4 × 4 squares a face, so that the edge is four segments),
/// over the middle of a segment and exactly over a vertex between two, at angles from the top
/// (0°) to the side (90°); and on the ridge of a roof of 26.6° slopes. The closed form of one
/// contact with the edge: n = (c − q)/|c − q|, q the closest point of the edge's line, overlap
/// δ = R − |c − q|, force k_n·δ (LSD) or K_n·δ^1.5 (Hertz) along n, no torque (at rest, no
/// tangential force). Tolerance: each load component is rounded to the sums' quantum, at most
/// 2⁻⁴⁰ of the peak bound (1 + μ)|F|, so |F − F_closed| ≤ 2⁻⁴⁰(1 + μ)|F|·√3/2, plus the closed
/// form's own rounding (δ from c − q, a few ε·R/δ ≤ 1e-14 relative). After one step the
/// velocity, (F₀ + F₁)·Δt/2m, is along n too: the bead moves along n, keeping q its closest
/// point, so to the rounding of n (1e-12).
#[test]
fn a_bead_on_a_convex_edge_feels_one_contact_along_the_edge_normal() {
    let l = 0.004;
    let step = faces(v(-l, 0.0, -l), v(0.0, l, 0.0), 4, 9, &[(2, true, false), (0, true, false)]);
    // The roof: ridge y from 0 to L at x = 0, z = h; eaves at x = ±2h, z = 0; 4 squares a slope
    // along y, so the ridge is four segments too.
    let h = 0.001;
    let mut roof_v = Vec::new();
    for j in 0..=4 {
        let y = l * (j as f64 / 4.0);
        roof_v.extend([v(-2.0 * h, y, 0.0), v(0.0, y, h), v(2.0 * h, y, 0.0)]);
    }
    let mut roof_t = Vec::new();
    for j in 0..4u32 {
        let (a, b) = (3 * j, 3 * (j + 1));
        roof_t.extend([[a, a + 1, b + 1], [a, b + 1, b], [a + 1, a + 2, b + 2], [a + 1, b + 2, b + 1]]);
    }
    let roof = mesh("roof", &roof_v, &roof_t);
    for m in [&step, &roof] {
        let convex = m.edges().iter().filter(|e| e.kind == grainflow::mesh::EdgeKind::Convex).count();
        assert_eq!(convex, 4, "{}: the edge must be four convex segments", m.name());
    }
    // Each case: the mesh, the ridge point q and the unit directions (on the edge's normal plane)
    // between which the centre is put: the faces' normals.
    let slope = v(-1.0, 0.0, 2.0).normalize();
    let cases = [
        ("step", &step, v(0.0, 0.0, 0.0), Vec3::Z, Vec3::X),
        ("roof", &roof, v(0.0, 0.0, h), slope, v(-slope.x, 0.0, slope.z)),
    ];
    let mut worst = (0.0f64, 0.0f64);
    for (what, law, params) in laws().into_iter().take(2) {
        for &(name, mesh, q0, from, to) in &cases {
            for y in [0.3 * l, 0.5 * l] {
                for t in [0.0, 0.1, 0.5, 0.77, 1.0] {
                    // On the arc from one face's normal to the other's.
                    let n = (from * (1.0 - t) + to * t).normalize();
                    let q = q0 + v(0.0, y, 0.0);
                    for rho in [0.5 * R, 0.95 * R] {
                        let c = q + rho * n;
                        let init = [bead(c, Vec3::ZERO, Vec3::ZERO)];
                        let mut sim = simulation(
                            setup(law, params, vec![], vec![mesh.clone()], Vec3::ZERO, 1e-6),
                            &init,
                        );
                        sim.compute_forces();
                        let d = sim.diagnostics();
                        assert_eq!(d.contacts, 1, "{what} on the {name} at y = {y}, t = {t}, ρ = {rho}");
                        // The closed form, from the centre as stored.
                        let c = sim.particles().position[0];
                        let q = v(q0.x, c.y, q0.z);
                        let n = (c - q) / (c - q).length();
                        let delta = R - (c - q).length();
                        let coeffs = sim.coefficients().wall(0, 0);
                        let f = if law.normal == NormalModel::Hertz {
                            coeffs.kn * delta.powf(1.5)
                        } else {
                            coeffs.kn * delta
                        };
                        let p = sim.particles();
                        let tol = 2f64.powi(-40) * (1.0 + coeffs.mu) * f + 1e-14 * f;
                        let err = (p.force[0] - f * n).length();
                        assert!(err <= tol, "{what} on the {name}: force {} against {}", p.force[0], f * n);
                        assert!(
                            p.torque[0].length() <= tol * R,
                            "{what} on the {name}: torque {}",
                            p.torque[0]
                        );
                        worst.0 = worst.0.max(err / f);
                        sim.step();
                        assert_eq!(sim.diagnostics().contacts, 1, "{what} on the {name} after a step");
                        let u = sim.particles().velocity[0];
                        let off = u.cross(n).length() / u.length();
                        assert!(
                            off <= 1e-12 && u.dot(n) > 0.0,
                            "{what} on the {name}: velocity {u} against n = {n}"
                        );
                        worst.1 = worst.1.max(off);
                    }
                }
            }
        }
    }
    println!("worst: force {:e} of |F|, velocity off the normal {:e}", worst.0, worst.1);
}
