//! Moving mesh walls: a floor translating under a bouncing bead is the fixed floor seen from a
//! moving frame; a conveyor's surface velocity is the translating floor's; a drum carries the
//! particles held to its wall as a rigid body; an oscillating floor carries a resting bead; the
//! load on a mesh is what its particles feel, reversed; restarts continue bit for bit.

mod common;

use common::*;
use grainflow::contact::{ContactLaw, NormalModel};
use grainflow::mesh::{Mesh, MeshMotion, MeshTransform, MeshWall, SurfaceMotion};
use grainflow::{Integrator, Simulation, SimulationConfig, Vec3};
use std::f64::consts::{PI, TAU};

/// A flat n×n grid of squares (two triangles each) on z = 0 over [−a, a]².
fn floor(n: usize, a: f64) -> Mesh {
    let h = 2.0 * a / n as f64;
    let mut v = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            v.push(Vec3::new(-a + i as f64 * h, -a + j as f64 * h, 0.0));
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

const KN: f64 = 500.0;

/// One phase of 1 mm glass beads, LSD (k_n = 500 N/m, e = 0.8, μ = 0.3) or Hertz; `meshes`.
fn setup(law: ContactLaw, meshes: Vec<MeshWall>, gravity: Vec3, dt: f64) -> SimulationConfig {
    let hertz = law.normal != NormalModel::LinearSpringDashpot;
    let params = if hertz { hertz_params(0.8, 0.9, 0.3) } else { lsd_params(KN, 0.8, 0.3) };
    let mut cfg = config(
        law,
        vec![elastic_phase("glass", 1e-3, 2500.0, 1e7, 0.3)],
        vec![wall_material("steel", Some(1e7), Some(0.3))],
        vec![],
        vec![params],
        vec![params],
        Integrator::VelocityVerlet,
        dt,
    );
    cfg.meshes = meshes;
    cfg.gravity = gravity;
    cfg
}

fn laws() -> [(&'static str, ContactLaw); 2] {
    [
        ("LSD", ContactLaw::mfix(NormalModel::LinearSpringDashpot)),
        ("Hertz", ContactLaw::mfix(NormalModel::Hertz)),
    ]
}

const G: Vec3 = Vec3::new(0.0, 0.0, -9.81);

/// A bead bouncing obliquely, with spin, on a floor that slides at u in its plane is the bead
/// on the fixed floor launched at v₀ − u, seen from the floor (Galilean invariance): x − u·t
/// and v − u of the one are x and v of the other. The floor's velocity enters only the
/// contact's relative velocity, so the runs differ by the rounding of the frame change (a few
/// ulps of x ≈ 1e-2 m and v ≈ 1 m/s a step, not amplified by one bounce and roll): 1e-10 of the
/// scales.
#[test]
fn a_floor_sliding_in_its_plane_is_the_fixed_floor_in_a_moving_frame() {
    let u = Vec3::new(0.3, -0.2, 0.0);
    let (v0, w0, x0) =
        (Vec3::new(0.5, 0.4, -0.3), Vec3::new(0.0, 200.0, 0.0), Vec3::new(-4e-3, -3e-3, 5.1e-4));
    let dt = 2e-7;
    for (what, law) in laws() {
        let moving =
            MeshWall { motion: MeshMotion::Translate { velocity: u }, ..MeshWall::fixed(floor(10, 0.02), 0) };
        let mut a = simulation(setup(law, vec![moving], G, dt), &[spun(x0, v0, w0)]);
        let mut b =
            simulation(setup(law, vec![MeshWall::fixed(floor(10, 0.02), 0)], G, dt), &[spun(x0, v0 - u, w0)]);
        let (mut worst, mut touched) = (0.0f64, 0);
        for _ in 0..20_000 {
            a.step();
            b.step();
            let (p, q) = (a.particles(), b.particles());
            let t = a.time();
            worst = worst
                .max((p.position[0] - u * t - q.position[0]).length() / 1e-2)
                .max((p.velocity[0] - u - q.velocity[0]).length())
                .max((p.omega[0] - q.omega[0]).length() / 1e3);
            touched += (q.position[0].z < 5e-4) as usize;
        }
        assert!(touched > 100, "{what}: the bead never touched the floor");
        assert!(worst < 1e-10, "{what}: the moving floor's run differs by {worst:e}");
    }
}

/// A conveyor — the fixed floor with the surface velocity u — moves the bead as the floor
/// translating at u does: at every contact the surface's velocity is u (in the plane, so none
/// of it is removed) and the flat floor's geometry is the same wherever it is. The runs differ
/// only by where the contact falls on the triangles (a few ulps): 1e-12 of the scales.
#[test]
fn a_conveyor_carries_a_bead_as_a_translating_floor_does() {
    let u = Vec3::new(0.4, 0.1, 0.0);
    let (x0, dt) = (Vec3::new(-4e-3, -3e-3, 5e-4 - 1e-8), 2e-6);
    for (what, law) in laws() {
        // The floor moves 2.4 cm in the run: a 20 cm floor keeps the bead on it.
        let belt = MeshWall {
            surface: SurfaceMotion::Translate { velocity: u },
            ..MeshWall::fixed(floor(10, 0.1), 0)
        };
        let moving =
            MeshWall { motion: MeshMotion::Translate { velocity: u }, ..MeshWall::fixed(floor(10, 0.1), 0) };
        let mut a = simulation(setup(law, vec![belt], G, dt), &[spun(x0, Vec3::ZERO, Vec3::ZERO)]);
        let mut b = simulation(setup(law, vec![moving], G, dt), &[spun(x0, Vec3::ZERO, Vec3::ZERO)]);
        let mut worst = 0.0f64;
        for _ in 0..30_000 {
            a.step();
            b.step();
            let (p, q) = (a.particles(), b.particles());
            worst = worst
                .max((p.position[0] - q.position[0]).length() / 1e-2)
                .max((p.velocity[0] - q.velocity[0]).length())
                .max((p.omega[0] - q.omega[0]).length() / 1e3);
        }
        // The belt brings the bead to roll at 2u/7: its angular momentum about the contact
        // point stays zero (I·ω + m·r·v = 0, so ω = −5v/2r) and rolling means v + 5v/2 = u.
        // Sliding ends after u/(3.5·μg) = 0.04 s of the 0.06 s run; to 1 % of u for the
        // tangential spring's stick-slip about the rolling state.
        let v = a.particles().velocity[0];
        assert!(
            (v - u * (2.0 / 7.0)).length() < 1e-2 * u.length(),
            "{what}: the bead moves at {v}, not 2u/7"
        );
        assert!(worst < 1e-12, "{what}: the belt's run differs from the moving floor's by {worst:e}");
    }
}

/// A bead at `x` moving at `v` and spinning at `w`.
fn spun(x: Vec3, v: Vec3, w: Vec3) -> grainflow::state::ParticleInit {
    let mut p = particle(1, 0, 5e-4, 2500.0, x, v);
    p.omega = w;
    p
}

/// A drum (36 flat facets, radius 20 mm, turning about z at 1 rev/s without gravity) carries
/// twelve beads resting on its facets, pressed there by their centrifugal force, as a rigid
/// body: each bead starts at rest relative to its facet (at its equilibrium overlap
/// δ = m·ω²·ρ / k_n, moving at ω × x, spinning at ω), so the contact's relative velocity is
/// zero only if the wall's velocity ω × x enters it. After a quarter turn each bead must be
/// where the rotation takes it, but for the integrator's error: within 10 % of δ (2e-10 m of a
/// 3 cm path) at Δt = 1e-5 s, and at least 3 times closer at Δt / 5 (the error converges with
/// the step). A drum that carried the wall's velocity wrongly would brake the beads by
/// μ·m·ω²ρ: a fixed drum puts them millimetres off.
#[test]
fn a_turning_drum_carries_beads_on_its_wall_as_a_rigid_body() {
    let law = ContactLaw::mfix(NormalModel::LinearSpringDashpot);
    let (n, r_drum, omega, r) = (36, 0.02, TAU, 5e-4);
    let m = sphere_mass(r, 2500.0);
    let d = r_drum * (PI / n as f64).cos();
    // ρ = d − r + δ with δ = m ω² ρ / k_n: ρ = (d − r) / (1 − m ω² / k_n).
    let rho = (d - r) / (1.0 - m * omega * omega / KN);
    let beads: Vec<_> = (0..12)
        .map(|k| {
            let a = TAU * (3 * k) as f64 / n as f64 + PI / n as f64;
            let x = Vec3::new(rho * a.cos(), rho * a.sin(), 0.0);
            let mut p = particle(k as u32 + 1, 0, r, 2500.0, x, Vec3::Z.cross(x) * omega);
            p.omega = Vec3::Z * omega;
            p
        })
        .collect();
    let run = |motion: MeshMotion, dt: f64| {
        let drum = MeshWall { motion, ..MeshWall::fixed(tube(n, r_drum, 5e-3), 0) };
        let mut s = simulation(setup(law, vec![drum], Vec3::ZERO, dt), &beads);
        s.advance((0.25 / dt).round() as u64);
        let turn = s.time() * omega;
        let p = s.particles();
        (0..12)
            .map(|k| {
                let (c, sn) = (turn.cos(), turn.sin());
                let x0 = beads[p.id[k] as usize - 1].position;
                let want = Vec3::new(c * x0.x - sn * x0.y, sn * x0.x + c * x0.y, x0.z);
                (p.position[k] - want).length()
            })
            .fold(0.0, f64::max)
    };
    let delta = m * omega * omega * rho / KN;
    let turning = MeshMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Z, omega, ramp: 0.0 };
    let (coarse, fine) = (run(turning, 1e-5), run(turning, 2e-6));
    assert!(coarse < 0.1 * delta, "the beads left the rigid rotation by {coarse:e} m (overlap {delta:e} m)");
    assert!(
        fine < coarse / 3.0,
        "the departure does not converge with the step: {coarse:e} m, then {fine:e} m"
    );
    // The control: a drum standing still brakes them.
    assert!(run(MeshMotion::Fixed, 1e-5) > 1e-3, "a fixed drum should not carry the beads");
}

/// A bead resting on a floor that oscillates vertically (2 mm at 5 Hz: peak acceleration
/// 0.2 g, so the bead never leaves it) moves with the floor. Its relative motion is the
/// spring's response to the floor's acceleration, (ω/ω_n)² ≈ 1e-4 of the floor's motion
/// (ω_n = √(k_n/m) ≈ 7 000 rad/s) once the start's transient has died (e = 0.8 damps it within
/// a few ms): the velocities agree to 1e-3 of the floor's peak speed.
#[test]
fn an_oscillating_floor_carries_a_resting_bead() {
    let law = ContactLaw::mfix(NormalModel::LinearSpringDashpot);
    let (amp, f) = (2e-3, 5.0);
    let motion = MeshMotion::Oscillate { amplitude: Vec3::new(0.0, 0.0, amp), frequency: f };
    let floor = MeshWall { motion, ..MeshWall::fixed(floor(4, 0.01), 0) };
    let m = sphere_mass(5e-4, 2500.0);
    let x0 = Vec3::new(1e-3, 2e-3, 5e-4 - m * 9.81 / KN);
    let peak = amp * TAU * f;
    let mut s = simulation(setup(law, vec![floor], G, 1e-5), &[spun(x0, Vec3::Z * peak, Vec3::ZERO)]);
    s.advance(2_000);
    let mut worst = 0.0f64;
    for _ in 0..20_000 {
        s.step();
        let floor_v = peak * (TAU * f * s.time()).cos();
        worst = worst.max((s.particles().velocity[0].z - floor_v).abs());
    }
    assert!(worst < 1e-3 * peak, "the bead's velocity left the floor's by {worst:e} m/s");
}

/// The load on a mesh is the particles' loads from it, reversed, to the bit (Newton's third
/// law; the force stage adds the same rounded loads to the particles), and its torque about a
/// point is that of those loads about it (to rounding of the lever, 1e-15 relative).
#[test]
fn the_load_on_a_mesh_is_its_particles_loads_reversed() {
    let law = ContactLaw::mfix(NormalModel::Hertz);
    let beads: Vec<_> = (0..3)
        .map(|k| {
            let x = Vec3::new(-3e-3 + 3e-3 * k as f64, 1e-3, 5e-4 - 1e-7);
            spun(x, Vec3::new(0.1 * k as f64, 0.0, 0.0), Vec3::ZERO)
        })
        .enumerate()
        .map(|(k, mut p)| {
            p.id = 10 - k as u32;
            p
        })
        .collect();
    let mut s = simulation(setup(law, vec![MeshWall::fixed(floor(6, 0.01), 0)], G, 1e-6), &beads);
    s.advance(500);
    let about = Vec3::new(0.01, -0.02, 0.03);
    let load = s.mesh_load(0, about);
    let p = s.particles();
    let force: Vec3 = p.force.iter().copied().sum();
    assert_eq!(load.force, -force, "the mesh's force is not the particles' reversed");
    let torque: Vec3 = (0..p.len()).map(|i| (p.position[i] - about).cross(p.force[i]) + p.torque[i]).sum();
    assert!(
        (load.torque + torque).length() <= 1e-15 * torque.length().max(1e-30) * 10.0,
        "torque {} vs {}",
        load.torque,
        -torque
    );
    // The beads' weight is on the floor once they rest: 3 m g to the damping's transient.
    assert!(load.force.z < 0.0);
}

/// The beads of the restart tests: 60 in the lower half of [`small_drum`].
fn drum_beads() -> Vec<grainflow::state::ParticleInit> {
    bed(60, Vec3::new(-0.012, -0.012, -4e-3), Vec3::new(0.012, 0.0, 4e-3), 5e-4, 7)
}

/// A drum of radius 20 mm about z, 10 mm deep between two plane walls, moving by `motion`.
fn small_drum(motion: MeshMotion) -> SimulationConfig {
    let drum = MeshWall { motion, ..MeshWall::fixed(tube(48, 0.02, 5e-3), 0) };
    let mut c = setup(ContactLaw::mfix(NormalModel::Hertz), vec![drum], Vec3::new(0.0, -9.81, 0.0), 5e-6);
    c.walls = vec![
        grainflow::Wall::plane("back", Vec3::new(0.0, 0.0, -5e-3), Vec3::Z, 0),
        grainflow::Wall::plane("front", Vec3::new(0.0, 0.0, 5e-3), -Vec3::Z, 0),
    ];
    c
}

/// The bits of every particle's position, velocity and spin, in slot order.
fn state_bits(s: &Simulation) -> Vec<[u64; 3]> {
    let p = s.particles();
    (0..p.len())
        .flat_map(|i| [p.position[i], p.velocity[i], p.omega[i]])
        .map(|v| v.to_array().map(f64::to_bits))
        .collect()
}

/// A run with a turning drum and a bed in it, checkpointed and restarted, continues bit for
/// bit; restarted with another angular velocity it continues from where the drum was.
#[test]
fn a_restart_with_a_turning_drum_is_bit_identical() {
    let beads = drum_beads();
    let cfg =
        |omega: f64| small_drum(MeshMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Z, omega, ramp: 0.01 });
    let mut whole = simulation(cfg(20.0), &beads);
    let mut first = simulation(cfg(20.0), &beads);
    whole.advance(14_000);
    first.advance(10_000);
    assert!(first.diagnostics().contacts > 0);
    let bytes = first.checkpoint("drum");
    let mut rest = Simulation::restore(cfg(20.0), &bytes, Some("drum")).expect("a restart");
    rest.advance(4_000);
    assert_eq!(state_bits(&whole), state_bits(&rest), "the restarted run departs from the whole one");
    // Another angular velocity: the drum starts where the checkpoint left it (the same pose,
    // to the bit), then turns at the new rate.
    let changed = Simulation::restore(cfg(40.0), &bytes, None).expect("a restart of a changed case");
    assert_eq!(changed.mesh_pose(0), first.mesh_pose(0));
    let before = first.mesh_pose(0).rotation;
    let mut changed = changed;
    changed.advance(1_000);
    let turned = (changed.mesh_pose(0).rotation * before.conjugate()).to_axis_angle().1;
    assert!((turned - 40.0 * 1_000.0 * 5e-6).abs() < 1e-12, "turned {turned} rad");
}

/// A drum whose motion a script sets between steps (still, then turning) and that is
/// checkpointed after: the restart goes on with the script's motion, bit for bit, though its
/// case says the drum stands still; each kind of motion survives the bytes.
#[test]
fn a_restart_keeps_the_motion_a_script_set() {
    let beads = drum_beads();
    let cfg = || small_drum(MeshMotion::Fixed);
    let turning = MeshMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Z, omega: 25.0, ramp: 2e-3 };
    let script = |s: &mut Simulation| {
        s.advance(3_000);
        s.set_mesh_motion(0, turning).expect("a valid motion");
        s.advance(3_000);
    };
    let mut whole = simulation(cfg(), &beads);
    let mut first = simulation(cfg(), &beads);
    script(&mut whole);
    script(&mut first);
    assert!(first.has_scripted_motion());
    whole.advance(4_000);
    let bytes = first.checkpoint("drum");
    let mut rest = Simulation::restore(cfg(), &bytes, Some("drum")).expect("a restart");
    assert_eq!(rest.mesh_pose(0), first.mesh_pose(0));
    assert!(rest.has_scripted_motion(), "the restart forgot that a script set the motion");
    rest.advance(4_000);
    assert_eq!(rest.mesh_pose(0), whole.mesh_pose(0), "the restarted drum is elsewhere");
    assert_eq!(state_bits(&whole), state_bits(&rest), "the restarted run departs from the whole one");
    // The other kinds, each recorded and read back as set (the drum's pose after 100 steps
    // is the same to the bit in the restarted and the whole run).
    for motion in [
        MeshMotion::Translate { velocity: Vec3::new(0.0, 0.0, 1e-3) },
        MeshMotion::Oscillate { amplitude: Vec3::new(1e-4, 0.0, 0.0), frequency: 7.0 },
        MeshMotion::Fixed,
    ] {
        let mut a = simulation(cfg(), &beads);
        a.advance(10);
        a.set_mesh_motion(0, motion).expect("a valid motion");
        a.advance(10);
        let set = a.mesh_pose(0);
        let mut b = Simulation::restore(cfg(), &a.checkpoint("drum"), Some("drum")).expect("a restart");
        a.advance(100);
        b.advance(100);
        assert_eq!(a.mesh_pose(0), b.mesh_pose(0), "{motion:?} did not survive the checkpoint");
        // A moving motion moved the drum (so that the equal poses are not the case's rest).
        assert_eq!(motion == MeshMotion::Fixed, a.mesh_pose(0) == set, "{motion:?}");
    }
}

/// A turning drum with 2 500 beads — enough for the force stage to go parallel — gives the same
/// bits on 1, 2 and 3 threads, and with the beads re-sorted in memory every 50 steps (the mesh
/// contacts' histories follow their particles to their new slots): the mesh stage's loads are
/// rounded to the sums' quanta like every other load, so no order can change a sum.
#[test]
fn a_turning_drum_gives_the_same_bits_on_any_thread_count_and_slot_order() {
    let law = ContactLaw::mfix(NormalModel::Hertz);
    // Thrown at the drum's lower half at 1 m/s, so that many touch it within the run.
    let beads: Vec<_> = bed(2_500, Vec3::new(-0.019, -0.019, -4e-3), Vec3::new(0.019, 0.0, 4e-3), 5e-4, 11)
        .into_iter()
        .map(|mut b| {
            b.velocity = Vec3::new(0.0, -1.0, 0.0);
            b
        })
        .collect();
    let run = |threads: usize, resort: grainflow::ResortRule| {
        let motion = MeshMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Z, omega: 30.0, ramp: 0.0 };
        let drum = MeshWall { motion, ..MeshWall::fixed(tube(64, 0.028, 5e-3), 0) };
        let mut c = setup(law, vec![drum], Vec3::new(0.0, -9.81, 0.0), 5e-6);
        c.walls = vec![
            grainflow::Wall::plane("back", Vec3::new(0.0, 0.0, -5e-3), Vec3::Z, 0),
            grainflow::Wall::plane("front", Vec3::new(0.0, 0.0, 5e-3), -Vec3::Z, 0),
        ];
        c.resort = resort;
        let mut s = simulation(c, &beads);
        s.set_threads(threads).expect("threads");
        s.advance(2_500);
        let mesh_contacts =
            s.contacts().iter().filter(|c| matches!(c.other, grainflow::ContactPartner::Mesh { .. })).count();
        let (p, _) = s.in_id_order();
        let bits: Vec<_> = (0..p.len())
            .flat_map(|i| [p.position[i], p.velocity[i], p.omega[i]])
            .map(|v| v.to_array().map(f64::to_bits))
            .collect();
        (bits, mesh_contacts, s.mesh_load(0, Vec3::ZERO))
    };
    let (one, touching, load) = run(1, grainflow::ResortRule::Never);
    assert!(touching > 50, "only {touching} beads touch the drum");
    for (threads, resort) in [
        (2, grainflow::ResortRule::Never),
        (3, grainflow::ResortRule::Never),
        (2, grainflow::ResortRule::Every(50)),
    ] {
        let (other, _, other_load) = run(threads, resort);
        assert!(one == other, "{threads} threads, {resort:?}: the state differs from one thread's");
        assert_eq!(load, other_load, "{threads} threads, {resort:?}: the drum's load differs");
    }
}

/// The fastest point of a moving mesh and the box it sweeps (issue 38's set-up guards), each
/// against its closed form: a translation's |v|; a rotation's ω times the largest distance of a
/// vertex from the axis, whose vertices then sweep circles; an oscillation's 2π·f·|A|, within
/// ± A. Tolerance 1e-12 relative: a few roundings of the same numbers by another route.
#[test]
fn fastest_points_and_swept_boxes_follow_the_motion() {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
    let plate = |motion| MeshWall { motion, ..MeshWall::fixed(floor(2, 0.1), 0) };
    let v = Vec3::new(3.0, -4.0, 0.0);
    let moving = plate(MeshMotion::Translate { velocity: v });
    assert!(close(moving.fastest_point_speed().0, 5.0));
    // Over 2 s: moved by (6, −8, 0).
    let (lo, hi) = moving.swept_bounds(2.0);
    assert_eq!((lo, hi), (Vec3::new(-0.1, -8.1, 0.0), Vec3::new(6.1, 0.1, 0.0)));
    // Turning about the y axis through (0.3, 0, 0): the farthest vertices are at x = −0.1,
    // 0.4 from the axis; every vertex sweeps a circle in the x-z plane.
    let turning = plate(MeshMotion::Rotate {
        origin: Vec3::new(0.3, 0.0, 0.0),
        axis: Vec3::Y,
        omega: -50.0,
        ramp: 0.0,
    });
    assert!(close(turning.fastest_point_speed().0, 50.0 * 0.4));
    let (lo, hi) = turning.swept_bounds(1.0);
    for (got, want) in [(lo.x, -0.1), (hi.x, 0.7), (lo.y, -0.1), (hi.y, 0.1), (lo.z, -0.4), (hi.z, 0.4)] {
        assert!(close(got, want), "{lo:?} {hi:?}");
    }
    let shaking = plate(MeshMotion::Oscillate { amplitude: Vec3::new(0.0, 0.0, 0.002), frequency: 50.0 });
    assert!(close(shaking.fastest_point_speed().0, TAU * 50.0 * 0.002));
    let (lo, hi) = shaking.swept_bounds(1.0);
    assert!(close(lo.z, -0.002) && close(hi.z, 0.002));
    assert_eq!(plate(MeshMotion::Fixed).fastest_point_speed().0, 0.0);
}
