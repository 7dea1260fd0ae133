//! Periodic boundaries: nearest-image neighbour search against brute force, a collision
//! across the periodic face identical to the same collision inside the box, and momentum
//! conservation in a fully periodic box.

mod common;

use common::*;
use grainflow::contact::{ContactLaw, NormalModel};
use grainflow::neighbor::NeighborList;
use grainflow::state::ParticleInit;
use grainflow::{Integrator, Particles, Periodic, Simulation, Vec3};
use std::collections::BTreeSet;

fn periodic_xy(lo: Vec3, hi: Vec3) -> Periodic {
    Periodic { lo, hi, axes: [true, true, false] }
}

#[test]
fn nearest_image_pairs_match_brute_force() {
    let (lo, hi) = (Vec3::ZERO, Vec3::new(0.05, 0.04, 0.03));
    let per = periodic_xy(lo, hi);
    let mut rng = Rng::new(3);
    let init: Vec<ParticleInit> = (0..1500)
        .map(|k| particle(k + 1, 0, rng.range(0.0006, 0.0018), 2500.0, rng.in_box(lo, hi), Vec3::ZERO))
        .collect();
    let p = Particles::from_init(&init);
    let skin = 0.0004;
    let mut nl = NeighborList::with_periodic(skin, per);
    nl.build(&p, &[]);
    let got: BTreeSet<(u32, u32)> = nl.pairs().map(|[i, j]| (p.id[i as usize], p.id[j as usize])).collect();
    let mut want = BTreeSet::new();
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let cut = p.radius[i] + p.radius[j] + skin;
            if per.min_image(p.position[j] - p.position[i]).length_squared() < cut * cut {
                want.insert((p.id[i].min(p.id[j]), p.id[i].max(p.id[j])));
            }
        }
    }
    let across = want
        .iter()
        .filter(|&&(a, b)| {
            let d = p.position[(b - 1) as usize] - p.position[(a - 1) as usize];
            d.x.abs() > 0.025 || d.y.abs() > 0.02
        })
        .count();
    assert!(across > 20, "only {across} pairs across the periodic faces: the test would not exercise them");
    assert_eq!(got, want);
}

/// Two spheres colliding head-on: once in the middle of the box, once exactly across the
/// periodic face (the same relative configuration shifted by half a box). Translation
/// invariance: final velocities and spins equal to rounding. Shifting the coordinates by
/// 0.02 m changes their rounding by up to ulp(0.04 m) ≈ 7e-18 m, i.e. 7e-13 of the ~1e-5 m
/// overlap at every force evaluation; over ~1 000 contact steps that bounds the relative
/// difference by ~1e-9.
#[test]
fn a_collision_across_the_periodic_face_equals_one_inside() {
    let (lo, hi) = (Vec3::ZERO, Vec3::new(0.04, 0.04, 0.04));
    let run = |shift: f64| {
        let params = lsd_params(1000.0, 0.8, 0.3);
        let mut cfg = config(
            ContactLaw::mfix(NormalModel::LinearSpringDashpot),
            vec![phase("g", 0.004, 2500.0)],
            vec![],
            vec![],
            vec![params],
            vec![],
            Integrator::VelocityVerlet,
            2e-6,
        );
        cfg.periodic = Some(Periodic { lo, hi, axes: [true, true, true] });
        let c = Vec3::new(0.02 + shift, 0.02, 0.02);
        let init = [
            particle(1, 0, 0.002, 2500.0, c - Vec3::new(0.0025, 0.0003, 0.0), Vec3::new(0.3, 0.0, 0.05)),
            particle(2, 0, 0.002, 2500.0, c + Vec3::new(0.0025, 0.0003, 0.0), Vec3::new(-0.3, 0.01, 0.0)),
        ];
        let mut sim: Simulation = simulation(cfg, &init);
        for _ in 0..5000 {
            sim.step();
        }
        sim
    };
    let inside = run(0.0);
    let across = run(0.02); // the pair now straddles x = 0.04 ≡ 0
    let (a, b) = (inside.particles(), across.particles());
    assert!(a.velocity[0].x < 0.0, "the spheres did not collide");
    for i in 0..2 {
        for (u, w) in [(a.velocity[i], b.velocity[i]), (a.omega[i], b.omega[i])] {
            assert!((u - w).length() <= 1e-9 * (1.0 + u.length()), "particle {i}: {u:?} vs {w:?}");
        }
        let d = Periodic { lo, hi, axes: [true; 3] }
            .min_image(b.position[i] - a.position[i] - Vec3::new(0.02, 0.0, 0.0));
        assert!(d.length() < 1e-12, "particle {i} position differs by {d:?}"); // metres: 1e-9 of the 1e-3 m travelled
        assert!(
            b.position[i].x >= lo.x && b.position[i].x < hi.x,
            "position not wrapped: {:?}",
            b.position[i]
        );
    }
}

/// 400 frictional particles in a fully periodic box without gravity or walls: total linear
/// momentum is conserved to rounding (pair forces are equal and opposite across the faces too).
#[test]
fn momentum_is_conserved_in_a_fully_periodic_box() {
    let (lo, hi) = (Vec3::ZERO, Vec3::splat(0.03));
    let params = lsd_params(800.0, 0.7, 0.5);
    let mut cfg = config(
        ContactLaw::mfix(NormalModel::LinearSpringDashpot),
        vec![phase("g", 0.003, 2500.0)],
        vec![],
        vec![],
        vec![params],
        vec![],
        Integrator::Euler,
        5e-6,
    );
    cfg.periodic = Some(Periodic { lo, hi, axes: [true; 3] });
    let mut rng = Rng::new(11);
    let mut init: Vec<ParticleInit> = Vec::new();
    while init.len() < 400 {
        let x = rng.in_box(lo, hi);
        let per = Periodic { lo, hi, axes: [true; 3] };
        if init.iter().all(|q| per.min_image(q.position - x).length() > 0.0031) {
            init.push(particle(init.len() as u32 + 1, 0, 0.0015, 2500.0, x, rng.unit() * 0.5));
        }
    }
    let mut sim: Simulation = simulation(cfg, &init);
    let momentum = |s: &Simulation| {
        let p = s.particles();
        (0..p.len()).fold(Vec3::ZERO, |acc, i| acc + p.mass[i] * p.velocity[i])
    };
    let scale: f64 =
        init.iter().map(|q| grainflow::math::sphere_mass(q.radius, q.density) * q.velocity.length()).sum();
    let p0 = momentum(&sim);
    let mut contacts = 0;
    for _ in 0..4000 {
        sim.step();
        contacts = contacts.max(sim.diagnostics().contacts);
    }
    assert!(contacts > 10, "too few collisions ({contacts})");
    let dp = (momentum(&sim) - p0).length();
    // Rounding only: ~1e-16 per force addition, 4 000 steps × ~10 contacts.
    assert!(dp <= 1e-11 * scale, "momentum changed by {dp:e} (scale {scale:e})");
}
