//! Particles that come and go, and particles stored in another order: re-sorting during a run,
//! a particle inserted mid-run, particles removed, and checkpoints across both, compared bit
//! for bit (the force stage's sums do not depend on their order, so none of this may change a
//! result). Comparisons are by particle id: re-sorting moves particles to other slots.
//!
//! Each comparison has teeth: the same run with a 10⁻¹⁰ change in one particle's initial
//! velocity differs (`threads.rs` shows it for these beds).

mod common;

use common::*;
use grainflow::state::ParticleInit;
use grainflow::{Integrator, ResortRule, Simulation, Vec3, Wall};

/// Every particle's id, position, velocity, spin, force and torque, in id order, as bits.
fn by_id(sim: &Simulation) -> Vec<u64> {
    let p = sim.particles();
    let p = p.gathered(&p.id_order());
    let mut out: Vec<u64> = p.id.iter().map(|&i| i as u64).collect();
    for v in [&p.position, &p.velocity, &p.omega, &p.force, &p.torque] {
        out.extend(v.iter().flat_map(|x| x.to_array()).map(f64::to_bits));
    }
    out
}

/// A walled Hertz–Mindlin bed settling (velocity Verlet), or a linear one (Adams–Bashforth),
/// with particles in random order (`bed` places them at random).
fn bed_case(integrator: Integrator, hertz: bool) -> (grainflow::SimulationConfig, Vec<ParticleInit>) {
    let (lo, hi) = (Vec3::ZERO, Vec3::new(0.03, 0.03, 0.06));
    let (law, params, ph, wm) = if hertz {
        let (law, p) = lammps_mindlin();
        (
            law,
            p,
            elastic_phase("glass", 0.002, 2500.0, 5.0e6, 0.3),
            wall_material("wall", Some(5.0e6), Some(0.3)),
        )
    } else {
        let (law, p) = lammps_hooke();
        (law, p, phase("glass", 0.002, 2500.0), wall_material("wall", None, None))
    };
    let mut cfg = config(
        law,
        vec![ph],
        vec![wm],
        Wall::domain_box(lo, hi, 0),
        vec![params],
        vec![params],
        integrator,
        2.0e-5,
    );
    cfg.gravity = Vec3::new(0.0, 0.0, -9.81);
    (cfg, bed(1500, lo, hi, 0.001, 21))
}

fn run(
    cfg: &grainflow::SimulationConfig,
    init: &[ParticleInit],
    rule: ResortRule,
    threads: usize,
    steps: u64,
) -> Simulation {
    let mut c = cfg.clone();
    c.resort = rule;
    let mut sim = simulation(c, init);
    sim.set_threads(threads).expect("threads");
    sim.advance(steps);
    sim
}

/// Re-sorting every 50 steps, or when the order decays, or never; on 1 and 2 threads: the
/// same bits. The bed flows enough for the sorts to move particles (checked).
#[test]
fn resorting_changes_no_result_on_any_thread_count() {
    for (integrator, hertz) in [(Integrator::VelocityVerlet, true), (Integrator::AdamsBashforth, false)] {
        let (cfg, init) = bed_case(integrator, hertz);
        let steps = 2500;
        let never = run(&cfg, &init, ResortRule::Never, 1, steps);
        let want = by_id(&never);
        let contacts = never.diagnostics().contacts;
        assert!(contacts > 50, "a bed with contacts: {contacts}");
        for (rule, threads) in [
            (ResortRule::Every(50), 1),
            (ResortRule::Every(50), 2),
            (ResortRule::Auto, 2),
            (ResortRule::Never, 2),
        ] {
            let sim = run(&cfg, &init, rule, threads, steps);
            if let ResortRule::Every(_) = rule {
                assert!(sim.resorts() >= 10, "{rule:?}: sorted {} times", sim.resorts());
                assert_ne!(sim.particles().id, never.particles().id, "{rule:?}: the sort moved nobody");
            }
            let got = by_id(&sim);
            let differing = want.iter().zip(&got).filter(|(a, b)| a != b).count();
            assert_eq!(
                differing, 0,
                "{integrator:?}, {rule:?} on {threads} threads: {differing} values differ"
            );
            assert_eq!(sim.diagnostics(), never.diagnostics(), "diagnostics are order-free sums");
            assert_eq!(sim.inexact_sums(), 0);
        }
    }
}

/// A particle inserted at step k falls exactly as the same particle present from the start
/// falls from step 0 (bit for bit, relative to its own start): free fall under gravity, the
/// same arithmetic whatever the step it joins at. With Adams–Bashforth its first step is the
/// run's first kind of step, as for a particle there from the start.
#[test]
fn a_particle_inserted_mid_run_falls_as_one_present_from_the_start() {
    for integrator in [Integrator::VelocityVerlet, Integrator::AdamsBashforth, Integrator::Euler] {
        let (cfg, init) = bed_case(integrator, false);
        // The bed's particles lie in z < 0.06; the newcomer falls far above, alone.
        let newcomer =
            |id| particle(id, 0, 0.001, 2500.0, Vec3::new(0.015, 0.015, 5.0), Vec3::new(0.01, 0.0, -0.2));
        let mut cfg = cfg.clone();
        // Without the lid: the newcomer starts above it.
        cfg.walls.retain(|w| w.normal.z > -0.5);
        let mut present = simulation(cfg.clone(), &[newcomer(1)]);
        let mut joined = simulation(cfg.clone(), &init);
        joined.advance(137);
        joined.insert(&[newcomer(99_999)]).expect("insert");
        let trail = |s: &Simulation, id: u32| {
            let i = s.particles().index_of(id).expect("present");
            let p = s.particles();
            [p.position[i], p.velocity[i]].map(|v| v.to_array().map(f64::to_bits))
        };
        for _ in 0..200 {
            present.step();
            joined.step();
            assert_eq!(
                trail(&present, 1),
                trail(&joined, 99_999),
                "{integrator:?} after step {}",
                joined.step_index()
            );
        }
    }
}

/// Insert and remove mid-run, checkpoint, restart: the restarted run equals the uninterrupted
/// one bit for bit (the histories of removed particles go with them; the others keep theirs).
#[test]
fn insert_remove_checkpoint_restart_is_bit_identical() {
    let (cfg, init) = bed_case(Integrator::VelocityVerlet, true);
    let mut cfg = cfg;
    cfg.resort = ResortRule::Every(40);
    let extra: Vec<ParticleInit> = (0..20)
        .map(|k| {
            particle(
                50_000 + k,
                0,
                0.001,
                2500.0,
                Vec3::new(0.004 + 0.0025 * (k % 10) as f64, 0.015, 0.05 + 0.003 * (k / 10) as f64),
                Vec3::ZERO,
            )
        })
        .collect();
    let script = |sim: &mut Simulation, from: u64, to: u64| {
        for s in from..to {
            if s == 100 {
                sim.insert(&extra).expect("insert");
            }
            if s == 180 {
                let gone = sim.remove_where(|p, i| p.position[i].x < 0.004).expect("remove");
                assert!(gone > 10, "removed {gone}");
            }
            sim.step();
        }
    };
    let mut whole = simulation(cfg.clone(), &init);
    script(&mut whole, 0, 400);
    let mut first = simulation(cfg.clone(), &init);
    script(&mut first, 0, 250);
    let bytes = first.checkpoint("h");
    drop(first);
    let mut resumed = Simulation::restore(cfg.clone(), &bytes, Some("h")).expect("restore");
    script(&mut resumed, 250, 400);
    assert!(whole.resorts() > 0);
    assert!(whole.particles().id.iter().any(|&id| id >= 50_000), "the inserted particles are there");
    assert!(whole.particles().len() < init.len() + extra.len(), "and some left");
    assert_eq!(by_id(&whole), by_id(&resumed), "restart after insert, remove and sorts");
    // And the same run without any re-sorting gives the same bits too.
    let mut unsorted_cfg = cfg.clone();
    unsorted_cfg.resort = ResortRule::Never;
    let mut unsorted = simulation(unsorted_cfg, &init);
    script(&mut unsorted, 0, 400);
    assert_eq!(by_id(&whole), by_id(&unsorted), "with and without re-sorting");
}

/// Removing particles takes their contacts with them: the remaining pairs' histories are
/// those the run had, and the list names no removed particle.
#[test]
fn removal_keeps_the_other_histories() {
    let (cfg, init) = bed_case(Integrator::VelocityVerlet, true);
    let mut sim = simulation(cfg, &init);
    sim.advance(300);
    let histories = |s: &Simulation| {
        let p = s.particles();
        let nl = s.neighbors();
        let mut h: Vec<(u32, u32, [u64; 3])> = nl
            .pairs()
            .zip(nl.pair_histories())
            .filter(|(_, h)| *h != Vec3::ZERO)
            .map(|([a, b], h)| {
                let (ia, ib) = (p.id[a as usize], p.id[b as usize]);
                let h = if ia < ib { h } else { -h };
                (ia.min(ib), ia.max(ib), h.to_array().map(f64::to_bits))
            })
            .collect();
        h.sort_unstable();
        h
    };
    let before = histories(&sim);
    assert!(before.len() > 200);
    let gone: Vec<u32> = sim.particles().id.iter().copied().filter(|id| id % 7 == 0).collect();
    assert_eq!(sim.remove_ids(&gone).expect("remove"), gone.len());
    let after = histories(&sim);
    let kept: Vec<_> = before.iter().filter(|(a, b, _)| a % 7 != 0 && b % 7 != 0).cloned().collect();
    assert_eq!(after, kept);
    assert!(sim.particles().id.iter().all(|id| id % 7 != 0));
}
