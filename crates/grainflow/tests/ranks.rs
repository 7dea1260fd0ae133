//! A run spread over ranks equals the one-process run to the bit: the same run on 1, 2, 3 and
//! 4 ranks (threads of this process talking through `LocalComm`) gives the same particles
//! (positions, velocities, spins, forces, torques, by id) and the same diagnostics as without
//! ranks — for a walled bed with the Hertz–Mindlin law (velocity Verlet) and for a chute
//! periodic in x and y on a held base with the linear law (Adams–Bashforth), where the boxes
//! wrap onto each other and onto themselves.
//!
//! Equality is exact: each pair's load is the same bits on either rank, and the sums do not
//! depend on their order. The comparison has teeth: a 10⁻¹⁰ change in one particle's initial
//! velocity changes the final state.

mod common;

use common::*;
use grainflow::domain::{Comm, LocalComm};
use grainflow::motion::{MotionRule, PrescribedMotion};
use grainflow::{Integrator, Simulation, Vec3, Wall};
use std::sync::Arc;

/// Everything a step produces, by particle id, and the diagnostics, as bits.
fn fingerprint(sim: &Simulation) -> Vec<u64> {
    let p = sim.gathered_in_id_order();
    let d = sim.diagnostics();
    let vecs = [&p.position, &p.velocity, &p.omega, &p.force, &p.torque];
    let ids = p.id.iter().map(|&i| i as u64);
    let diag = [d.kinetic_translational, d.kinetic_rotational, d.potential, d.elastic, d.max_overlap_ratio];
    ids.chain(vecs.iter().flat_map(|v| v.iter()).flat_map(|v| v.to_array()).map(f64::to_bits))
        .chain(diag.iter().map(|x| x.to_bits()))
        .chain([d.contacts as u64, d.step])
        .collect()
}

/// The fingerprint after `steps` steps on `ranks` ranks (0: one process, no ranks), with the
/// most particles a rank held and the particles that moved between ranks (the list builds in
/// one process).
fn run(make: &(dyn Fn() -> Simulation + Sync), ranks: usize, steps: usize) -> (Vec<u64>, usize, u64) {
    if ranks == 0 {
        let mut sim = make();
        sim.advance(steps as u64);
        return (fingerprint(&sim), sim.particles().len(), sim.neighbors().stats().builds);
    }
    let comms = LocalComm::team(ranks);
    let results: Vec<(Vec<u64>, usize, u64)> = std::thread::scope(|s| {
        let handles: Vec<_> = comms
            .into_iter()
            .map(|comm| {
                s.spawn(move || {
                    let comm: Arc<dyn Comm> = Arc::new(comm);
                    let mut sim = make();
                    sim.decompose(comm).expect("spread over ranks");
                    let mut most = sim.owned();
                    // Steps one at a time and in calls of several (whose inner steps leave
                    // the ghosts behind until the next evaluation).
                    let mut done = 0;
                    while done < steps {
                        let k = if done % 2 == 0 { 1 } else { 7.min(steps - done) };
                        sim.advance(k as u64);
                        done += k;
                        most = most.max(sim.owned());
                    }
                    (fingerprint(&sim), most, sim.domain_stats().migrated)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("rank")).collect()
    });
    for r in &results[1..] {
        assert!(r.0 == results[0].0, "ranks see different gathered states");
    }
    let most = results.iter().map(|r| r.1).max().unwrap_or(0);
    (results[0].0.clone(), most, results.iter().map(|r| r.2).sum())
}

fn check_rank_counts(
    name: &str,
    make: &(dyn Fn() -> Simulation + Sync),
    perturbed: &(dyn Fn() -> Simulation + Sync),
    steps: usize,
) {
    let n = make().particles().len();
    let (want, _, builds) = run(make, 0, steps);
    assert!(builds > 2, "{name}: the list was rebuilt only {builds} times: no particle migrated");
    for ranks in [1, 2, 3, 4] {
        let (got, most, migrated) = run(make, ranks, steps);
        let differing = want.iter().zip(&got).filter(|(a, b)| a != b).count();
        assert_eq!(want.len(), got.len(), "{name}: {ranks} ranks hold another number of particles");
        assert_eq!(differing, 0, "{name}: {differing} values differ between one process and {ranks} ranks");
        // The work was spread: no rank held more than its share and a halo.
        if ranks > 1 {
            assert!(most < n * 3 / 4, "{name}: a rank of {ranks} held {most} of {n} particles");
            assert!(migrated > 10, "{name}: only {migrated} particles moved between {ranks} ranks");
        }
    }
    let (nudged, _, _) = run(perturbed, 2, steps);
    let differing = want.iter().zip(&nudged).filter(|(a, b)| a != b).count();
    assert!(differing > 100, "{name}: a 1e-10 change left the state alone ({differing} values differ)");
}

/// The chute of `common`, on a floor and a rough base held in place (whose pairs with each
/// other are left out, and with the free particles not).
fn periodic_chute(nudged: bool) -> Simulation {
    let (lo, hi) = CHUTE_BOX;
    let (law, params) = lammps_hooke();
    let mut cfg = chute_config(
        law,
        phase("glass", 0.002, 2500.0),
        wall_material("lid", None, None),
        params,
        Integrator::AdamsBashforth,
    );
    cfg.walls.push(Wall::plane("floor", Vec3::ZERO, Vec3::Z, 0));
    let mut init = bed(3000, lo, hi, 0.001, 12);
    if nudged {
        nudge(&mut init);
    }
    cfg.motion = init
        .iter()
        .filter(|q| q.position.z < 0.0045)
        .map(|q| PrescribedMotion { particle: q.id, rule: MotionRule::Hold })
        .collect();
    assert!(cfg.motion.len() > 300, "a base of {} particles", cfg.motion.len());
    simulation(cfg, &init)
}

#[test]
fn walled_hertz_bed_is_bit_identical_on_any_rank_count() {
    check_rank_counts("walled bed", &|| walled_bed(false), &|| walled_bed(true), 400);
}

#[test]
fn periodic_chute_is_bit_identical_on_any_rank_count() {
    check_rank_counts("periodic chute", &|| periodic_chute(false), &|| periodic_chute(true), 400);
}
