//! Cylinder walls (exact, infinite): a sphere at rest inside a drum and on a rod settles where
//! the wall law's closed forms put it, the drum equals a finely faceted mesh drum within the
//! faceting error, and a restart through a checkpoint continues bit for bit.

mod common;

use common::*;
use grainflow::contact::{ContactLaw, NormalModel};
use grainflow::mesh::{Mesh, MeshTransform, MeshWall, SurfaceMotion};
use grainflow::{Cylinder, CylinderSide, Integrator, Simulation, SimulationConfig, Vec3};
use std::f64::consts::PI;

/// Bead radius, m; density, kg/m³; Young's modulus of bead and wall, Pa; Poisson's ratio.
const R_BEAD: f64 = 5e-4;
const RHO: f64 = 2500.0;
const E: f64 = 1e7;
const NU: f64 = 0.3;
/// LSD wall stiffness, N/m.
const KN: f64 = 500.0;
/// Gravity along −z, m/s².
const G: f64 = 9.81;
/// Time step, s: t_c/80 for LSD (t_c = π√(m/k) = 1.6e-4 s), as the mesh tests use for Hertz.
const DT: f64 = 2e-6;

/// The drum's radius and the rod's, m.
const R_DRUM: f64 = 0.01;
const R_ROD: f64 = 0.005;

/// A configuration of one bead phase and one wall material under gravity, for `law`, with the
/// cylinders `cylinders` and the meshes `meshes`.
fn setup(law: ContactLaw, cylinders: Vec<Cylinder>, meshes: Vec<MeshWall>) -> SimulationConfig {
    let hertz = law.normal != NormalModel::LinearSpringDashpot;
    let params = if hertz { hertz_params(0.5, 0.9, 0.3) } else { lsd_params(KN, 0.5, 0.3) };
    let mut cfg = config(
        law,
        vec![elastic_phase("glass", 2.0 * R_BEAD, RHO, E, NU)],
        vec![wall_material("steel", Some(E), Some(NU))],
        vec![],
        vec![params],
        vec![params],
        Integrator::VelocityVerlet,
        DT,
    );
    cfg.cylinders = cylinders;
    cfg.meshes = meshes;
    cfg.gravity = Vec3::new(0.0, 0.0, -G);
    cfg
}

/// A cylinder about the x axis.
fn cylinder(radius: f64, side: CylinderSide, omega: f64) -> Cylinder {
    Cylinder::new("c", Vec3::ZERO, Vec3::X, radius, side, 0, omega)
}

/// The bead at rest at `x`.
fn bead_at(x: Vec3) -> grainflow::state::ParticleInit {
    particle(1, 0, R_BEAD, RHO, x, Vec3::ZERO)
}

/// The bead's weight, N.
fn weight() -> f64 {
    sphere_mass(R_BEAD, RHO) * G
}

/// The static overlap under the bead's weight by the wall law: m g / k_n (LSD), or
/// (m g / ((4/3) E* √R*))^(2/3) with R* the bead's radius, as at a plane wall (Hertz).
fn static_overlap(law: ContactLaw) -> f64 {
    if law.normal == NormalModel::LinearSpringDashpot {
        weight() / KN
    } else {
        let e_star = 1.0 / (2.0 * (1.0 - NU * NU) / E);
        (weight() / (4.0 / 3.0 * e_star * R_BEAD.sqrt())).powf(2.0 / 3.0)
    }
}

fn laws() -> [(&'static str, ContactLaw); 2] {
    [
        ("lsd", ContactLaw::mfix(NormalModel::LinearSpringDashpot)),
        ("hertz", ContactLaw::mfix(NormalModel::Hertz)),
    ]
}

/// Steps to settle: 0.04 s, 250 periods of the LSD contact (the slowest, 1.6e-4 s); with
/// e_n = 0.5 the oscillation's amplitude falls by half each half period, to nothing.
const SETTLE: u64 = 20_000;

/// The bead's distance from the x axis, m.
fn axis_distance(s: &Simulation) -> f64 {
    let x = s.particles().position[0];
    (x.y * x.y + x.z * x.z).sqrt()
}

/// A bead let go touching the bottom of a drum (horizontal axis) settles at R − r + δ, δ the
/// wall law's static overlap under its weight; the drum carries its weight.
#[test]
fn a_bead_settles_at_the_bottom_of_a_drum() {
    for (name, law) in laws() {
        let c = cylinder(R_DRUM, CylinderSide::Inside, 0.0);
        let mut s =
            simulation(setup(law, vec![c], vec![]), &[bead_at(Vec3::new(0.0, 0.0, -(R_DRUM - R_BEAD)))]);
        s.advance(SETTLE);
        let delta = static_overlap(law);
        let want = R_DRUM - R_BEAD + delta;
        // After 250 damped periods the oscillation is gone; what is left is rounding: of the
        // position (1e-18 m), of the loads to their quanta (2⁻⁴¹ of the weight, 5e-13 of δ).
        // 1e-6 of δ holds all of it and is 1e-4 of the sagitta the mesh test below resolves.
        let got = axis_distance(&s);
        assert!(
            (got - want).abs() <= 1e-6 * delta,
            "{name}: at {got:e} m from the axis, want {want:e} (δ = {delta:e})"
        );
        assert_eq!(s.particles().position[0].y, 0.0, "{name}: the bead left the bottom line");
        let load = s.cylinder_load(0, Vec3::ZERO);
        // The drum carries the bead's weight (the bead's acceleration is gone to the same 1e-6).
        assert!(
            (load.force - Vec3::new(0.0, 0.0, -weight())).length() <= 1e-6 * weight(),
            "{name}: load on the drum {:?}, weight {:e} N",
            load.force,
            weight()
        );
        assert_eq!(s.diagnostics().contacts, 1, "{name}");
    }
}

/// A bead let go touching the top of a rod (horizontal axis) settles at R + r − δ.
#[test]
fn a_bead_settles_on_top_of_a_rod() {
    for (name, law) in laws() {
        let c = cylinder(R_ROD, CylinderSide::Outside, 0.0);
        let mut s = simulation(setup(law, vec![c], vec![]), &[bead_at(Vec3::new(0.0, 0.0, R_ROD + R_BEAD))]);
        s.advance(SETTLE);
        let delta = static_overlap(law);
        let want = R_ROD + R_BEAD - delta;
        // As for the drum.
        let got = axis_distance(&s);
        assert!(
            (got - want).abs() <= 1e-6 * delta,
            "{name}: at {got:e} m from the axis, want {want:e} (δ = {delta:e})"
        );
        let c = s.contacts();
        assert_eq!(c.len(), 1, "{name}");
        assert!(matches!(c[0].other, grainflow::ContactPartner::Cylinder(0)), "{name}: {:?}", c[0]);
        // The contact's normal points from the bead down to the rod's axis.
        assert!((c[0].normal - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-12, "{name}: {:?}", c[0].normal);
    }
}

/// A tube of radius `radius` about the x axis from x = −`half` to `half`, of `n` flat facets
/// (two triangles each) whose corners lie on the circle and whose first facet's centre is at
/// the bottom (−z), normals facing the axis: an OBJ file's text.
fn tube_obj(radius: f64, half: f64, n: usize) -> String {
    let mut s = String::new();
    for x in [-half, half] {
        for j in 0..n {
            // The corners of facet 0 at −π/2 ± π/n: its centre line at the bottom.
            let phi = -PI / 2.0 + (2.0 * j as f64 - 1.0) * PI / n as f64;
            s.push_str(&format!("v {x:e} {:e} {:e}\n", radius * phi.cos(), radius * phi.sin()));
        }
    }
    for j in 0..n {
        let (a, b) = (j + 1, (j + 1) % n + 1);
        let (c, d) = (b + n, a + n);
        // Wound so that the normals face the axis (inwards).
        s.push_str(&format!("f {a} {d} {c}\nf {a} {c} {b}\n"));
    }
    s
}

/// A drum as a [`Cylinder`] equals the same drum as a 256-facet mesh within the faceting
/// error: the bead at rest on the bottom facet sits lower by exactly its sagitta
/// R(1 − cos(π/n)), and the wall law is otherwise the same. Turning, the surface drags the
/// bead alike.
#[test]
fn a_drum_cylinder_equals_a_fine_mesh_drum() {
    let n = 256;
    let sagitta = R_DRUM * (1.0 - (PI / n as f64).cos());
    let mesh = || {
        let obj = tube_obj(R_DRUM, 0.004, n);
        Mesh::from_obj("tube.obj", obj.as_bytes(), &MeshTransform::default()).expect("a valid tube")
    };
    for (name, law) in laws() {
        let start = Vec3::new(0.0, 0.0, -(R_DRUM * (PI / n as f64).cos() - R_BEAD));
        let mut a = simulation(
            setup(law, vec![cylinder(R_DRUM, CylinderSide::Inside, 0.0)], vec![]),
            &[bead_at(start)],
        );
        let mut b = simulation(setup(law, vec![], vec![MeshWall::fixed(mesh(), 0)]), &[bead_at(start)]);
        a.advance(SETTLE);
        b.advance(SETTLE);
        let (da, db) = (axis_distance(&a), axis_distance(&b));
        let delta = static_overlap(law);
        // Both at rest to 1e-6 of δ (as above); the mesh's facet is a sagitta nearer the axis.
        assert!(da - db <= sagitta + 2e-6 * delta, "{name}: {da:e} vs {db:e}, sagitta {sagitta:e}");
        assert!((da - db - sagitta).abs() <= 2e-6 * delta, "{name}: {da:e} − {db:e} ≠ sagitta {sagitta:e}");

        // Turning: the surface at ω = 2 rad/s (U = ωR = 0.02 m/s at the wall) slides under the
        // bead at rest at the bottom; friction at the Coulomb cap, μ m g, speeds it up along the
        // surface's motion (+y here) at μ g, until it rolls (after 2U/(7μg) = 1.9 ms). Between
        // 0.5 ms (the spring charged) and 1.5 ms it gains μ g · 1 ms, drum and mesh alike. The
        // curvature the facet lacks tilts gravity by θ = y/R ≤ 2e-4 rad and adds v²/(gR) ≤ 1e-4
        // to the normal load in that time: 1e-3 of the gain bounds both.
        let omega = 2.0;
        let turning = MeshWall {
            surface: SurfaceMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::X, omega },
            ..MeshWall::fixed(mesh(), 0)
        };
        let start = Vec3::new(0.0, 0.0, -(R_DRUM - R_BEAD + delta));
        let mut a = simulation(
            setup(law, vec![cylinder(R_DRUM, CylinderSide::Inside, omega)], vec![]),
            &[bead_at(start)],
        );
        let mut b =
            simulation(setup(law, vec![], vec![turning]), &[bead_at(start + Vec3::new(0.0, 0.0, sagitta))]);
        let (t0, t1) = (250, 750);
        a.advance(t0);
        b.advance(t0);
        let (va, vb) = (a.particles().velocity[0].y, b.particles().velocity[0].y);
        a.advance(t1 - t0);
        b.advance(t1 - t0);
        let gain = 0.3 * G * (t1 - t0) as f64 * DT;
        let (ga, gb) = (a.particles().velocity[0].y - va, b.particles().velocity[0].y - vb);
        assert!(
            (ga - gain).abs() <= 1e-3 * gain,
            "{name}: the drum's bead gained {ga:e} m/s, μ g Δt = {gain:e}"
        );
        assert!(
            (gb - gain).abs() <= 1e-3 * gain,
            "{name}: the mesh's bead gained {gb:e} m/s, μ g Δt = {gain:e}"
        );
        assert!((ga - gb).abs() <= 1e-3 * gain, "{name}: {ga:e} vs {gb:e} m/s");
        // It rolls from 2U/(7μg) = 1.9 ms on, at 2U/7 (its spin 5μg t/(2r) then makes up the
        // rest of U). By 4 ms the spring's ringing at the stick is damped out and gravity,
        // tilted by θ ≤ 3e-3 rad, has slowed it by (5/7) g θ · 2 ms, about 0.5 %: 1 % bounds it.
        a.advance(2000 - t1);
        b.advance(2000 - t1);
        let rolling = 2.0 / 7.0 * omega * R_DRUM;
        for (what, s) in [("drum", &a), ("mesh", &b)] {
            let v = s.particles().velocity[0].y;
            assert!(
                (v - rolling).abs() <= 0.01 * rolling,
                "{name}: the {what}'s bead rolls at {v:e} m/s, 2U/7 = {rolling:e}"
            );
        }
    }
}

/// A run with a cylinder contact checkpointed while the bead is carried by a turning drum
/// (the spring holding the friction) and restarted continues bit for bit.
#[test]
fn a_restart_with_cylinder_contacts_is_bit_identical() {
    let law = ContactLaw::mfix(NormalModel::Hertz);
    let cfg = || setup(law, vec![cylinder(R_DRUM, CylinderSide::Inside, 2.0)], vec![]);
    let start = [bead_at(Vec3::new(0.0, 0.0, -(R_DRUM - R_BEAD)))];
    let mut whole = simulation(cfg(), &start);
    let mut first = simulation(cfg(), &start);
    whole.advance(20_000);
    first.advance(10_000);
    assert_eq!(first.contacts().len(), 1, "the bead should touch the drum at the checkpoint");
    let bytes = first.checkpoint("case");
    let mut rest = Simulation::restore(cfg(), &bytes, Some("case")).expect("a restart");
    assert_eq!(rest.contacts(), first.contacts());
    rest.advance(10_000);
    let bits = |s: &Simulation| {
        let p = s.particles();
        [p.position[0], p.velocity[0], p.omega[0]].map(|v| v.to_array().map(f64::to_bits))
    };
    assert_eq!(bits(&whole), bits(&rest));
}

/// A cylinder with a material the configuration does not define, or a zero radius, is refused.
#[test]
fn a_bad_cylinder_is_refused() {
    let law = ContactLaw::mfix(NormalModel::Hertz);
    let start = [bead_at(Vec3::new(0.0, 0.0, -0.005))];
    let bad_material = Cylinder { material: 3, ..cylinder(R_DRUM, CylinderSide::Inside, 0.0) };
    let e = Simulation::new(setup(law, vec![bad_material], vec![]), grainflow::Particles::from_init(&start))
        .expect_err("refused");
    assert!(e.to_string().contains("cylinder 'c' uses wall material 3"), "{e}");
    let flat = Cylinder { radius: 0.0, ..cylinder(R_DRUM, CylinderSide::Inside, 0.0) };
    let e = Simulation::new(setup(law, vec![flat], vec![]), grainflow::Particles::from_init(&start))
        .expect_err("refused");
    assert!(e.to_string().contains("a finite radius > 0"), "{e}");
}

/// 300 beads tumbling in a turning drum (its ends two planes) give the same bits on 1 and 3
/// threads (every stage on them), and with the particles re-sorted along the way: the cylinder loads are rounded to
/// the sums' quanta, and their histories follow the particles to their new slots.
#[test]
fn a_tumbling_bed_in_a_drum_is_the_same_on_threads_and_re_sorted() {
    let law = ContactLaw::mfix(NormalModel::Hertz);
    let make = || {
        let mut cfg = setup(law, vec![cylinder(R_DRUM, CylinderSide::Inside, 5.0)], vec![]);
        cfg.walls = vec![
            grainflow::Wall::plane("left", Vec3::new(-0.0035, 0.0, 0.0), Vec3::X, 0),
            grainflow::Wall::plane("right", Vec3::new(0.0035, 0.0, 0.0), -Vec3::X, 0),
        ];
        let lo = Vec3::new(-0.003, -0.004, -0.0085);
        let hi = Vec3::new(0.003, 0.004, -0.001);
        simulation(cfg, &bed(300, lo, hi, R_BEAD, 7))
    };
    let bits = |s: &Simulation| -> Vec<u64> {
        let (p, _) = s.in_id_order();
        p.position
            .iter()
            .chain(&p.velocity)
            .chain(&p.omega)
            .flat_map(|v| v.to_array())
            .map(f64::to_bits)
            .collect()
    };
    let run = |threads: usize, sort: bool| {
        let mut s = make();
        s.set_threads(threads).expect("thread pool");
        // Every stage on the threads from the first particle (300 are below the default).
        s.set_parallel_from(1);
        s.advance(10_000);
        if sort {
            s.sort_spatially().expect("a re-sort");
        }
        s.advance(10_000);
        s
    };
    let one = run(1, false);
    let touching =
        one.contacts().iter().filter(|c| matches!(c.other, grainflow::ContactPartner::Cylinder(_))).count();
    assert!(touching > 10, "only {touching} beads touch the drum");
    assert!(bits(&one) == bits(&run(3, false)), "3 threads differ from 1");
    assert!(bits(&one) == bits(&run(1, true)), "re-sorted differs");
}
