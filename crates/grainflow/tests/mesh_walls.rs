//! Mesh walls in the time step: a triangulated floor must act as the analytic plane it
//! triangulates, for every contact law, through an oblique impact that slides and rolls the
//! sphere across triangle seams (the tangential history carried from triangle to triangle).

mod common;

use common::*;
use grainflow::contact::{ContactLaw, NormalModel};
use grainflow::mesh::{Mesh, MeshTransform, MeshWall};
use grainflow::{Integrator, Simulation, Vec3, Wall};

/// A flat n×n grid of squares (two triangles each) on z = 0 over [−0.01, 0.01]² m.
fn floor(n: usize) -> Mesh {
    let h = 0.02 / n as f64;
    let mut v = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            v.push(Vec3::new(-0.01 + i as f64 * h, -0.01 + j as f64 * h, 0.0));
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

/// A 1 mm glass bead at height `z` launched at `v0`, spinning at `w0`, against the plane z = 0
/// (`mesh` None) or the mesh, with time step `dt`.
fn bead(law: ContactLaw, mesh: Option<Mesh>, z: f64, v0: Vec3, w0: Vec3, dt: f64) -> Simulation {
    let (cfg, init) = bead_setup(law, mesh, z, v0, w0, dt);
    simulation(cfg, &init)
}

/// The configuration and particle of [`bead`].
fn bead_setup(
    law: ContactLaw,
    mesh: Option<Mesh>,
    z: f64,
    v0: Vec3,
    w0: Vec3,
    dt: f64,
) -> (grainflow::SimulationConfig, Vec<grainflow::state::ParticleInit>) {
    let hertz = law.normal != NormalModel::LinearSpringDashpot;
    let params = if hertz { hertz_params(0.8, 0.9, 0.3) } else { lsd_params(500.0, 0.8, 0.3) };
    let walls = if mesh.is_none() { vec![Wall::plane("floor", Vec3::ZERO, Vec3::Z, 0)] } else { vec![] };
    let mut cfg = config(
        law,
        vec![elastic_phase("glass", 1e-3, 2500.0, 1e7, 0.3)],
        vec![wall_material("steel", Some(1e7), Some(0.3))],
        walls,
        vec![params],
        vec![params],
        Integrator::VelocityVerlet,
        dt,
    );
    cfg.meshes = mesh.into_iter().map(|mesh| MeshWall::fixed(mesh, 0)).collect();
    cfg.gravity = Vec3::new(0.0, 0.0, -9.81);
    let mut p = particle(1, 0, 5e-4, 2500.0, Vec3::new(-8e-3, -6e-3, z), v0);
    p.omega = w0;
    (cfg, vec![p])
}

/// The largest relative difference of the two runs' state, against the scale of each.
fn differ(a: &Simulation, b: &Simulation) -> f64 {
    let (p, q) = (a.particles(), b.particles());
    let rel = |x: Vec3, y: Vec3, scale: f64| (x - y).length() / scale;
    rel(p.position[0], q.position[0], 1e-3)
        .max(rel(p.velocity[0], q.velocity[0], 1.0))
        .max(rel(p.omega[0], q.omega[0], 1e3))
}

fn laws() -> [(&'static str, ContactLaw); 2] {
    [
        ("LSD", ContactLaw::mfix(NormalModel::LinearSpringDashpot)),
        ("Hertz", ContactLaw::mfix(NormalModel::Hertz)),
    ]
}

/// Runs the bead against the plane and against `floor(n)` side by side for `steps` steps;
/// returns the largest difference of their states ([`differ`]) and the steps in contact.
fn side_by_side(
    law: ContactLaw,
    n: usize,
    z: f64,
    v0: Vec3,
    w0: Vec3,
    dt: f64,
    steps: usize,
) -> (f64, usize) {
    let mut plane = bead(law, None, z, v0, w0, dt);
    let mut mesh = bead(law, Some(floor(n)), z, v0, w0, dt);
    let (mut worst, mut touched) = (0.0f64, 0);
    for _ in 0..steps {
        plane.step();
        mesh.step();
        worst = worst.max(differ(&plane, &mesh));
        touched += (plane.particles().position[0].z < 5e-4) as usize;
        // The diagnostics see the mesh contact as the plane's: the same count, and the elastic
        // energy and largest overlap ratio to 1e-9 relative. The overlap r − z (1e-8 to 1e-6 m)
        // is formed from z ≈ r = 5e-4 m, so it is known only to ~ε·r ≈ 1e-19 m, ~1e-11 of it,
        // and the energy (∝ δ² or δ^2.5) to ~3e-11.
        let (a, b) = (plane.diagnostics(), mesh.diagnostics());
        assert_eq!(a.contacts, b.contacts, "contact counts differ");
        let rel = |x: f64, y: f64| if x == y { 0.0 } else { (x - y).abs() / x.abs().max(y.abs()) };
        assert!(rel(a.elastic, b.elastic) < 1e-9, "elastic energy {} vs {}", a.elastic, b.elastic);
        assert!(
            rel(a.max_overlap_ratio, b.max_overlap_ratio) < 1e-9,
            "overlap ratio {} vs {}",
            a.max_overlap_ratio,
            b.max_overlap_ratio
        );
    }
    (worst, touched)
}

// The mesh's contact has the plane's normal and overlap to rounding (the face contact's
// projection against the plane's distance): differences of a few ulps, which the contact's
// dynamics do not amplify beyond 1e-12 of the state's scale over these runs.
const SAME: f64 = 1e-12;

#[test]
fn an_oblique_impact_on_a_triangulated_floor_is_the_planes() {
    for (what, law) in laws() {
        for n in [1, 10] {
            let (worst, touched) = side_by_side(
                law,
                n,
                5.2e-4,
                Vec3::new(1.0, 0.6, -0.5),
                Vec3::new(0.0, 300.0, 0.0),
                2e-7,
                20_000,
            );
            assert!(touched > 100, "{what}, {n}×{n}: the bead never touched the floor");
            assert!(worst < SAME, "{what}, {n}×{n}: the mesh run differs from the plane's by {worst:e}");
        }
    }
}

/// Sliding, then rolling, across 8 seams of the 10×10 grid (2 mm squares) while in contact:
/// the tangential spring must carry over from triangle to triangle, or the friction force
/// would drop to zero at each seam and the runs part.
#[test]
fn a_bead_rolling_across_triangle_seams_is_the_planes() {
    for (what, law) in laws() {
        let (worst, touched) =
            side_by_side(law, 10, 5e-4, Vec3::new(0.2, 0.1, 0.0), Vec3::ZERO, 2e-6, 40_000);
        assert!(touched > 30_000, "{what}: the bead left the floor ({touched} steps in contact)");
        assert!(worst < SAME, "{what}: the mesh run differs from the plane's by {worst:e}");
    }
}

/// A run with mesh contacts checkpointed mid-roll and restarted continues bit for bit as the
/// run that never stopped (the contacts' histories and normals are in the checkpoint).
#[test]
fn a_restart_with_mesh_contacts_is_bit_identical() {
    let law = ContactLaw::mfix(NormalModel::Hertz);
    let (v0, dt) = (Vec3::new(0.2, 0.1, 0.0), 2e-6);
    let mut whole = bead(law, Some(floor(10)), 5e-4, v0, Vec3::ZERO, dt);
    let mut first = bead(law, Some(floor(10)), 5e-4, v0, Vec3::ZERO, dt);
    // Checkpointed while rolling (the slip, 0.22 m/s, stops after 21 ms at μg·7/2): the spring
    // then holds the friction force, which a restart without it would lose (while sliding, the
    // cap sets the force whatever the spring held).
    whole.advance(30_000);
    first.advance(15_000);
    let p = first.particles();
    let slip = p.velocity[0] + p.omega[0].cross(Vec3::new(0.0, 0.0, -5e-4));
    assert!(
        p.position[0].z < 5e-4 && slip.length() < 1e-3,
        "not rolling on the floor at the checkpoint: slip {slip}"
    );
    let bytes = first.checkpoint("case");
    let (cfg, _) = bead_setup(law, Some(floor(10)), 5e-4, v0, Vec3::ZERO, dt);
    let mut rest = Simulation::restore(cfg, &bytes, Some("case")).expect("a restart");
    // The restored state reports its mesh contact before any evaluation, as the state it was
    // written from (outputs at the restart step).
    assert_eq!(first.contacts().len(), 1);
    assert_eq!(rest.contacts(), first.contacts());
    assert_eq!(rest.diagnostics().contacts, first.diagnostics().contacts);
    rest.advance(15_000);
    let bits = |s: &Simulation| {
        let p = s.particles();
        [p.position[0], p.velocity[0], p.omega[0]].map(|v| v.to_array().map(f64::to_bits))
    };
    assert_eq!(bits(&whole), bits(&rest));
}

/// A new simulation reports a particle's mesh contact before its first step (the first
/// output of a run), as it reports a plane wall's.
#[test]
fn a_new_simulation_reports_its_mesh_contacts() {
    let law = ContactLaw::mfix(NormalModel::Hertz);
    let on_mesh = bead(law, Some(floor(10)), 4.99e-4, Vec3::ZERO, Vec3::ZERO, 2e-6);
    let on_plane = bead(law, None, 4.99e-4, Vec3::ZERO, Vec3::ZERO, 2e-6);
    let (m, p) = (on_mesh.contacts(), on_plane.contacts());
    assert_eq!((m.len(), p.len()), (1, 1));
    assert!(matches!(m[0].other, grainflow::ContactPartner::Mesh { mesh: 0, .. }), "{:?}", m[0]);
    // The same overlap and point: a face contact of a flat mesh is the plane's.
    assert!((m[0].overlap - p[0].overlap).abs() < 1e-18 && (m[0].point - p[0].point).length() < 1e-15);
    assert_eq!(on_mesh.diagnostics().contacts, 1);
}

/// A mesh naming a wall material the case does not define is refused.
#[test]
fn a_mesh_with_an_unknown_material_is_refused() {
    let law = ContactLaw::mfix(NormalModel::LinearSpringDashpot);
    let mut cfg = config(
        law,
        vec![phase("glass", 1e-3, 2500.0)],
        vec![wall_material("steel", None, None)],
        vec![],
        vec![lsd_params(500.0, 0.8, 0.3)],
        vec![lsd_params(500.0, 0.8, 0.3)],
        Integrator::VelocityVerlet,
        1e-6,
    );
    cfg.meshes = vec![MeshWall::fixed(floor(1), 3)];
    let init = [particle(1, 0, 5e-4, 2500.0, Vec3::new(0.0, 0.0, 1e-3), Vec3::ZERO)];
    let err = Simulation::new(cfg, grainflow::Particles::from_init(&init)).expect_err("an unknown material");
    assert!(err.to_string().contains("mesh 'floor' uses wall material 3"), "{err}");
}
