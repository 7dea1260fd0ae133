//! A run spread over ranks equals the one-process run to the bit: the same run on 1, 2, 3 and
//! 4 ranks (threads of this process talking through `LocalComm`) gives the same particles
//! (positions, velocities, spins, forces, torques, by id) and the same diagnostics as without
//! ranks — for a walled bed with the Hertz–Mindlin law (velocity Verlet) and for a chute
//! periodic in x and y on a held base with the linear law (Adams–Bashforth), where the boxes
//! wrap onto each other and onto themselves — and for a bed thrown at the wall of a turning
//! drum, once a mesh of flat facets and once an exact cylinder, whose loads are summed over the
//! ranks and whose contact histories travel with their particles.
//!
//! Equality is exact: each pair's load is the same bits on either rank, and the sums do not
//! depend on their order. The comparison has teeth: a 10⁻¹⁰ change in one particle's initial
//! velocity changes the final state.

mod common;

use common::*;
use grainflow::contact::{ContactLaw, NormalModel};
use grainflow::domain::{Comm, LocalComm};
use grainflow::mesh::{MeshMotion, MeshWall};
use grainflow::motion::{MotionRule, PrescribedMotion};
use grainflow::state::ParticleInit;
use grainflow::{Cylinder, CylinderSide, Integrator, Simulation, SimulationConfig, Vec3, Wall};
use std::sync::Arc;

/// Everything a step produces, by particle id, the diagnostics and the load on every mesh and
/// cylinder, as bits.
fn fingerprint(sim: &Simulation) -> Vec<u64> {
    let about = Vec3::new(0.001, -0.002, 0.003);
    let loads: Vec<_> = (0..sim.meshes().len())
        .map(|m| sim.mesh_load(m, about))
        .chain((0..sim.cylinders().len()).map(|c| sim.cylinder_load(c, about)))
        .flat_map(|l| [l.force, l.torque])
        .flat_map(|v| v.to_array())
        .map(f64::to_bits)
        .collect();
    let p = sim.gathered_in_id_order();
    let d = sim.diagnostics();
    let vecs = [&p.position, &p.velocity, &p.omega, &p.force, &p.torque];
    let ids = p.id.iter().map(|&i| i as u64);
    let diag = [d.kinetic_translational, d.kinetic_rotational, d.potential, d.elastic, d.max_overlap_ratio];
    ids.chain(vecs.iter().flat_map(|v| v.iter()).flat_map(|v| v.to_array()).map(f64::to_bits))
        .chain(diag.iter().map(|x| x.to_bits()))
        .chain([d.contacts as u64, d.step])
        .chain(loads)
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
                    // Boxes cut again at every rebuild whose work is uneven at all, so that
                    // particles also move between ranks by the re-cuts.
                    sim.decompose(comm, Some(0.0)).expect("spread over ranks");
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
    let (cfg, init) = periodic_chute_case(nudged);
    simulation(cfg, &init)
}

fn periodic_chute_case(nudged: bool) -> (SimulationConfig, Vec<ParticleInit>) {
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
    (cfg, init)
}

/// The chute with ten free beads of the upper bed under rules that follow a leader in z
/// (their own x and y kept): five follow beads on the far side in x (on another rank when
/// the boxes are cut across x), one of those follows a follower whose rule comes after its
/// own (it copies where its leader was before that rule moved it, as one process applies
/// the rules in order), and the others follow it after its rule.
fn followed_chute_case(nudged: bool) -> (SimulationConfig, Vec<ParticleInit>) {
    let (mut cfg, init) = periodic_chute_case(nudged);
    let mut upper: Vec<&ParticleInit> = init.iter().filter(|q| q.position.z > 0.012).collect();
    upper.sort_by(|a, b| a.position.x.total_cmp(&b.position.x));
    let (near, far) = (&upper[..5], &upper[upper.len() - 10..]);
    let follow = |particle: u32, leader: u32| PrescribedMotion {
        particle,
        rule: MotionRule::Follow { leader, axes: [false, false, true] },
    };
    cfg.motion.push(follow(far[9].id, far[0].id));
    for (f, l) in far[..5].iter().zip(near) {
        cfg.motion.push(follow(f.id, l.id));
    }
    for f in &far[5..9] {
        cfg.motion.push(follow(f.id, far[0].id));
    }
    (cfg, init)
}

fn followed_chute(nudged: bool) -> Simulation {
    let (cfg, init) = followed_chute_case(nudged);
    simulation(cfg, &init)
}

#[test]
fn a_chute_with_followers_on_other_ranks_is_bit_identical_on_any_rank_count() {
    // On 2 ranks some follower's leader is another rank's.
    let (cfg, _) = followed_chute_case(false);
    let pairs: Vec<(u32, u32)> = cfg
        .motion
        .iter()
        .filter_map(|m| match m.rule {
            MotionRule::Follow { leader, .. } => Some((m.particle, leader)),
            MotionRule::Hold => None,
        })
        .collect();
    let owned = on_ranks(2, &|comm| {
        let mut sim = followed_chute(false);
        sim.decompose(comm, None).expect("spread over ranks");
        sim.particles().id[..sim.owned()].to_vec()
    });
    let rank_of = |id: u32| owned.iter().position(|ids| ids.contains(&id));
    assert!(pairs.iter().any(|&(f, l)| rank_of(f) != rank_of(l)), "every follower is on its leader's rank");
    check_rank_counts("followed chute", &|| followed_chute(false), &|| followed_chute(true), 400);
    check_restarts("followed chute", &|| followed_chute_case(false), 200, 400, 0);
}

#[test]
fn walled_hertz_bed_is_bit_identical_on_any_rank_count() {
    check_rank_counts("walled bed", &|| walled_bed(false), &|| walled_bed(true), 400);
}

#[test]
fn periodic_chute_is_bit_identical_on_any_rank_count() {
    check_rank_counts("periodic chute", &|| periodic_chute(false), &|| periodic_chute(true), 400);
}

/// 2 500 beads of 1 mm (Hertz–Mindlin) thrown at 1 m/s at the lower half of a drum of radius
/// 28 mm turning at 30 rad/s about z, its ends two planes: the drum a mesh of 64 flat facets
/// (`mesh`) or an exact cylinder.
fn thrown_at_a_drum(nudged: bool, mesh: bool) -> Simulation {
    let (cfg, init) = thrown_at_a_drum_case(nudged, mesh);
    simulation(cfg, &init)
}

fn thrown_at_a_drum_case(nudged: bool, mesh: bool) -> (SimulationConfig, Vec<ParticleInit>) {
    let law = ContactLaw::mfix(NormalModel::Hertz);
    let mut cfg = config(
        law,
        vec![elastic_phase("glass", 1e-3, 2500.0, 1e7, 0.3)],
        vec![wall_material("steel", Some(1e7), Some(0.3))],
        vec![
            Wall::plane("back", Vec3::new(0.0, 0.0, -5e-3), Vec3::Z, 0),
            Wall::plane("front", Vec3::new(0.0, 0.0, 5e-3), -Vec3::Z, 0),
        ],
        vec![hertz_params(0.8, 0.9, 0.3)],
        vec![hertz_params(0.8, 0.9, 0.3)],
        Integrator::VelocityVerlet,
        5e-6,
    );
    cfg.gravity = Vec3::new(0.0, -9.81, 0.0);
    let (r, omega) = (0.028, 30.0);
    if mesh {
        let motion = MeshMotion::Rotate { origin: Vec3::ZERO, axis: Vec3::Z, omega, ramp: 0.0 };
        cfg.meshes = vec![MeshWall { motion, ..MeshWall::fixed(tube(64, r, 5e-3), 0) }];
    } else {
        cfg.cylinders = vec![Cylinder::new("drum", Vec3::ZERO, Vec3::Z, r, CylinderSide::Inside, 0, omega)];
    }
    let mut init = bed(2_500, Vec3::new(-0.019, -0.019, -4e-3), Vec3::new(0.019, 0.0, 4e-3), 5e-4, 11);
    for b in &mut init {
        b.velocity = Vec3::new(0.0, -1.0, 0.0);
    }
    if nudged {
        nudge(&mut init);
    }
    (cfg, init)
}

#[test]
fn a_bed_thrown_at_a_turning_mesh_drum_is_bit_identical_on_any_rank_count() {
    let touching = |s: &Simulation| {
        s.contacts().iter().filter(|c| matches!(c.other, grainflow::ContactPartner::Mesh { .. })).count()
    };
    let mut one = thrown_at_a_drum(false, true);
    one.advance(2_500);
    assert!(touching(&one) > 50, "only {} beads touch the drum", touching(&one));
    check_rank_counts(
        "mesh drum",
        &|| thrown_at_a_drum(false, true),
        &|| thrown_at_a_drum(true, true),
        2_500,
    );
}

/// The mesh drum with each rank re-sorting its own particles every 50 steps (at the rebuild
/// after): the slots change under the pairs' and the mesh contacts' histories and the mesh
/// candidates, and the run keeps the one process's bits (which sorts by its own rule).
#[test]
fn a_mesh_drum_whose_ranks_re_sort_keeps_the_one_process_bits() {
    let steps = 1_500;
    let mut one = thrown_at_a_drum(false, true);
    one.advance(steps);
    let want = fingerprint(&one);
    for ranks in [2, 3] {
        let got = on_ranks(ranks, &|comm| {
            let mut sim = thrown_at_a_drum(false, true);
            sim.set_resort(grainflow::ResortRule::Every(50));
            sim.decompose(comm, Some(0.0)).expect("spread over ranks");
            sim.advance(steps);
            (fingerprint(&sim), sim.resorts())
        });
        for (r, (bits, sorts)) in got.iter().enumerate() {
            // One at the start, then at the first rebuild 50 steps after each.
            assert!(*sorts >= 10, "rank {r} of {ranks} re-sorted only {sorts} times in {steps} steps");
            assert!(*bits == want, "rank {r} of {ranks}, re-sorting, departs from one process");
        }
    }
}

#[test]
fn a_bed_thrown_at_a_turning_cylinder_is_bit_identical_on_any_rank_count() {
    let touching = |s: &Simulation| {
        s.contacts().iter().filter(|c| matches!(c.other, grainflow::ContactPartner::Cylinder(_))).count()
    };
    let mut one = thrown_at_a_drum(false, false);
    one.advance(2_500);
    assert!(touching(&one) > 50, "only {} beads touch the drum", touching(&one));
    check_rank_counts(
        "cylinder drum",
        &|| thrown_at_a_drum(false, false),
        &|| thrown_at_a_drum(true, false),
        2_500,
    );
}

/// `f` on each of `ranks` ranks (threads joined by a [`LocalComm`]), their results by rank.
fn on_ranks<T: Send>(ranks: usize, f: &(dyn Fn(Arc<dyn Comm>) -> T + Sync)) -> Vec<T> {
    std::thread::scope(|s| {
        let handles: Vec<_> =
            LocalComm::team(ranks).into_iter().map(|comm| s.spawn(move || f(Arc::new(comm)))).collect();
        handles.into_iter().map(|h| h.join().expect("rank")).collect()
    })
}

/// A run over 2 ranks checkpointed after `at` steps goes on from the checkpoint on 3 ranks
/// and in one process to the bits of the run that never stopped, for `steps` steps in all;
/// the checkpoint is the same bytes written from 2, 3 or 4 ranks (the whole run gathered in id
/// order), and it carries the contacts' histories (pairs, and walls, meshes or cylinders:
/// `walls` of them at least), without which the run would go on otherwise.
fn check_restarts(
    name: &str,
    case: &(dyn Fn() -> (SimulationConfig, Vec<ParticleInit>) + Sync),
    at: u64,
    steps: u64,
    walls: usize,
) {
    let make = || {
        let (cfg, init) = case();
        simulation(cfg, &init)
    };
    let mut whole = make();
    whole.advance(steps);
    let want = fingerprint(&whole);
    let checkpoint = |ranks: usize| -> Vec<u8> {
        let mut written = on_ranks(ranks, &|comm| {
            let mut sim = make();
            sim.decompose(comm, Some(0.1)).expect("spread over ranks");
            sim.advance(at);
            sim.gathered_whole().map(|w| {
                let (pairs, others) = w.contacts().iter().fold((0, 0), |(p, o), c| match c.other {
                    grainflow::ContactPartner::Particle(_) => (p + 1, o),
                    _ => (p, o + 1),
                });
                assert!(pairs > 100 && others >= walls, "{name}: {pairs} pairs and {others} wall contacts");
                w.checkpoint("case")
            })
        });
        assert!(written[1..].iter().all(Option::is_none), "{name}: a rank other than 0 holds the whole");
        written.swap_remove(0).expect("rank 0 holds the whole")
    };
    let bytes = checkpoint(2);
    for ranks in [3, 4] {
        assert!(
            bytes == checkpoint(ranks),
            "{name}: the checkpoint from {ranks} ranks differs from 2 ranks'"
        );
    }
    let restored = || Simulation::restore(case().0, &bytes, Some("case")).expect("a restart");
    let mut one = restored();
    one.advance(steps - at);
    assert!(fingerprint(&one) == want, "{name}: restarted in one process, the run departs");
    let got = on_ranks(3, &|comm| {
        let mut sim = restored();
        sim.decompose(comm, Some(0.1)).expect("spread over ranks");
        sim.advance(steps - at);
        fingerprint(&sim)
    });
    assert!(got.iter().all(|g| *g == want), "{name}: restarted on 3 ranks, the run departs");
}

#[test]
fn a_checkpoint_over_ranks_restarts_on_any_rank_count_with_the_same_bits() {
    check_restarts("mesh drum", &|| thrown_at_a_drum_case(false, true), 2_300, 2_700, 30);
    check_restarts("cylinder drum", &|| thrown_at_a_drum_case(false, false), 2_300, 2_700, 30);
    check_restarts("periodic chute", &|| periodic_chute_case(false), 200, 400, 0);
}

/// 1 200 beads of 2 mm thrown down at 1 m/s from a column 24 mm tall, 40 mm above the floor
/// of a walled 20 × 20 × 80 mm box (LAMMPS's Hertz–Mindlin law, restitution 0.3): two ranks
/// first cut the column across its height, and as it lands on the floor the upper rank's box
/// empties.
fn falling_column(nudged: bool) -> Simulation {
    let (lo, hi) = (Vec3::ZERO, Vec3::new(0.02, 0.02, 0.08));
    let mut cfg = walled_mindlin(lo, hi, 0.3);
    cfg.gravity = Vec3::new(0.0, 0.0, -9.81);
    let mut init = bed(1_200, Vec3::new(0.0, 0.0, 0.04), Vec3::new(0.02, 0.02, 0.08), 0.001, 17);
    for b in &mut init {
        b.velocity.z -= 1.0;
    }
    if nudged {
        nudge(&mut init);
    }
    simulation(cfg, &init)
}

/// Rebalancing follows the particles: without it the column's landing leaves one of two
/// ranks with all the work (slowest ÷ mean → 2 once the column has passed the first cut, 550
/// of the 3 000 steps in); with a re-cut whenever the slowest rank has more than 10 % over
/// the mean, it is back near 1 after each re-cut, and only the rebuild intervals in which
/// the work shifts count above 1.1. Either way, and on 3 ranks, the run is the one
/// process's to the bit; a nudge of 10⁻¹⁰ shows the comparison can fail.
#[test]
fn a_landing_column_is_rebalanced_and_keeps_the_one_process_bits() {
    let steps = 3_000;
    let mut one = falling_column(false);
    one.advance(steps);
    let want = fingerprint(&one);
    let top = one.particles().position.iter().map(|x| x.z).fold(0.0, f64::max);
    assert!(top < 0.03, "the column has not landed: a bead at z = {top} m");
    let spread = |make: &(dyn Fn() -> Simulation + Sync), ranks: usize, rebalance: Option<f64>| {
        let got = on_ranks(ranks, &|comm| {
            let mut sim = make();
            sim.decompose(comm, rebalance).expect("spread over ranks");
            sim.advance(steps);
            (fingerprint(&sim), sim.domain_stats())
        });
        // The work and the re-cuts are the ranks' common knowledge (what each sent is not).
        let same = |g: &(Vec<u64>, grainflow::DomainStats)| {
            let (a, b) = (&g.1, &got[0].1);
            g.0 == got[0].0
                && (a.work_slowest, a.work_total, a.recuts) == (b.work_slowest, b.work_total, b.recuts)
        };
        assert!(got.iter().all(same), "the ranks disagree");
        got.into_iter().next().expect("rank 0")
    };
    let (fixed, without) = spread(&|| falling_column(false), 2, None);
    let (balanced, with) = spread(&|| falling_column(false), 2, Some(0.1));
    let (three, _) = spread(&|| falling_column(false), 3, Some(0.1));
    assert!(fixed == want, "2 ranks without rebalancing depart from one process");
    assert!(balanced == want, "2 ranks with rebalancing depart from one process");
    assert!(three == want, "3 ranks with rebalancing depart from one process");
    let (slow_without, slow_with) = (without.imbalance(2), with.imbalance(2));
    assert_eq!(without.recuts, 0);
    assert!(with.recuts >= 1, "never re-cut");
    assert!(slow_without > 1.6, "without rebalancing, slowest ÷ mean {slow_without}");
    assert!(slow_with < 1.25, "with rebalancing, slowest ÷ mean {slow_with} ({} re-cuts)", with.recuts);
    let (nudged, _) = spread(&|| falling_column(true), 2, Some(0.1));
    let differing = want.iter().zip(&nudged).filter(|(a, b)| a != b).count();
    assert!(differing > 100, "a 1e-10 change left the state alone ({differing} values differ)");
}

/// Re-cut by measured time (threshold 0: at the close of every window of measurement in which
/// the busiest rank was busier than the mean, so nearly always), each rank's particles
/// weighing by its time per unit of work, the landing column keeps the one process's bits on
/// 2 and 3 ranks. The ranks step on until a window has closed (they agree when: its figures
/// are gathered), and one process then runs as many steps.
#[test]
fn a_column_rebalanced_by_measured_time_keeps_the_one_process_bits() {
    for ranks in [2, 3] {
        let got = on_ranks(ranks, &|comm| {
            let mut sim = falling_column(false);
            sim.decompose(comm, Some(0.0)).expect("spread over ranks");
            sim.weigh_ranks_by(grainflow::domain::Weigh::Time);
            sim.advance(1_000);
            while sim.domain_stats().busy_total == 0 && sim.step_index() < 200_000 {
                sim.advance(500);
            }
            (fingerprint(&sim), sim.step_index(), sim.domain_stats())
        });
        let (bits, steps, stats) = &got[0];
        assert!(got.iter().all(|g| (&g.0, g.1) == (bits, *steps)), "{ranks} ranks disagree");
        assert!(stats.time_imbalance(ranks).is_some(), "no window of measurement closed in {steps} steps");
        let mut one = falling_column(false);
        one.advance(*steps);
        assert!(fingerprint(&one) == *bits, "{ranks} ranks weighed by time depart from one process");
    }
}

/// 600 beads resting on a mesh floor (two triangles, 2 mm above the box's) of a walled 40 ×
/// 20 × 30 mm box, cut across x by two ranks. The second rank's own particles are removed, so
/// that it holds only ghosts for a while, and then the first rank's particles near the cut,
/// its last ghosts: a rank left with no slots at all still takes part in the mesh stage. Each
/// stage's state is the one process's with the same removals, to the bit.
#[test]
fn a_rank_emptied_beside_a_mesh_goes_on_with_the_one_process_bits() {
    let make = || {
        let (lo, hi) = (Vec3::ZERO, Vec3::new(0.04, 0.02, 0.03));
        let mut cfg = walled_mindlin(lo, hi, 0.3);
        cfg.gravity = Vec3::new(0.0, 0.0, -9.81);
        let (a, b, z) = (-0.01, 0.05, 0.002);
        let corners = [Vec3::new(a, a, z), Vec3::new(b, a, z), Vec3::new(b, 0.03, z), Vec3::new(a, 0.03, z)];
        let floor = grainflow::mesh::Mesh::from_indexed(
            "floor",
            &corners,
            &[[0, 1, 2], [0, 2, 3]],
            &grainflow::mesh::MeshTransform::default(),
        )
        .expect("a valid floor");
        cfg.meshes = vec![grainflow::mesh::MeshWall::fixed(floor, 0)];
        simulation(cfg, &bed(600, Vec3::new(0.0, 0.0, 0.00195), Vec3::new(0.04, 0.02, 0.02), 0.001, 5))
    };
    // Beyond x = 10 mm: every particle of the second rank and the first rank's near the cut.
    let far = |sim: &Simulation| -> Vec<u32> {
        let all = sim.gathered_in_id_order();
        (0..all.len()).filter(|&i| all.position[i].x > 0.01).map(|i| all.id[i]).collect()
    };
    let got = on_ranks(2, &|comm| {
        let mut sim = make();
        sim.decompose(comm.clone(), None).expect("spread over ranks");
        sim.advance(50);
        let own: Vec<u64> = sim.particles().id[..sim.owned()].iter().map(|&id| id as u64).collect();
        let second: Vec<u32> = comm.all_gather(&own)[1].iter().map(|&id| id as u32).collect();
        sim.remove_ids(&second).expect("removed");
        let ghosts_only = (sim.owned(), sim.particles().len());
        sim.advance(200);
        let gone = far(&sim);
        sim.remove_ids(&gone).expect("removed");
        sim.advance(200);
        (second, ghosts_only, fingerprint(&sim))
    });
    let (second, _, want_bits) = &got[0];
    let (owned, slots) = got[1].1;
    assert!(owned == 0 && slots > 10, "the second rank holds {owned} own particles and {slots} slots");
    assert!(got[1].2 == *want_bits, "the ranks disagree");
    let mut one = make();
    one.advance(50);
    one.remove_ids(second).expect("removed");
    one.advance(200);
    let gone = far(&one);
    one.remove_ids(&gone).expect("removed");
    one.advance(200);
    let meshed =
        one.contacts().iter().filter(|c| matches!(c.other, grainflow::ContactPartner::Mesh { .. })).count();
    assert!(meshed > 0, "no bead touches the mesh floor");
    assert!(fingerprint(&one) == *want_bits, "2 ranks depart from one process");
}

/// The fingerprint after `steps` steps of the run set up on `ranks` ranks from shares of the
/// case's particles (rank r the r-th of `ranks` runs of them, as listed) — no rank ever holds
/// them all — with the most particles a rank held.
fn run_from_shares(
    case: &(dyn Fn() -> (SimulationConfig, Vec<ParticleInit>) + Sync),
    ranks: usize,
    steps: u64,
) -> (Vec<u64>, usize) {
    let results = on_ranks(ranks, &|comm| {
        let (cfg, init) = case();
        let (r, n) = (comm.rank(), init.len());
        let share = grainflow::Particles::from_init(&init[r * n / ranks..(r + 1) * n / ranks]);
        let mut sim = Simulation::new_over_ranks(cfg, share, comm, Some(0.0)).expect("set up over ranks");
        let mut most = sim.particles().len();
        for _ in 0..steps / 10 {
            sim.advance(10);
            most = most.max(sim.particles().len());
        }
        sim.advance(steps % 10);
        (fingerprint(&sim), most)
    });
    for r in &results[1..] {
        assert!(r.0 == results[0].0, "ranks see different gathered states");
    }
    (results[0].0.clone(), results.iter().map(|r| r.1).max().unwrap_or(0))
}

/// The walled bed of `common` with beads poured in above it at the start and again later.
fn bed_poured_into_case(nudged: bool) -> (SimulationConfig, Vec<ParticleInit>) {
    use grainflow::insertion::psd::{Basis, Mixture, MixturePart, SizeDistribution};
    use grainflow::insertion::region::Region;
    use grainflow::insertion::{Amount, Insertion, Schedule};
    let hi = Vec3::new(0.03, 0.03, 0.06);
    let (mut cfg, init) = walled_bed_case(nudged);
    let pour = |name: &str, at: f64| Insertion {
        name: name.into(),
        region: Region::Box { lo: Vec3::new(0.0, 0.0, 0.04), hi },
        mixture: Mixture {
            parts: vec![MixturePart {
                phase: 0,
                density: 2500.0,
                fraction: 1.0,
                sizes: SizeDistribution::Uniform { min: 1.8e-3, max: 2.0e-3 },
            }],
            basis: Basis::Mass,
        },
        amount: Some(Amount::VolumeFraction(0.2)),
        schedule: Schedule::Once { at },
        velocity: Vec3::new(0.0, 0.0, -0.5),
        seed: 3,
        given: Vec::new(),
        max_initial_overlap: grainflow::insertion::DEFAULT_MAX_INITIAL_OVERLAP,
        plane_z: None,
    };
    cfg.insertions = vec![pour("at the start", 0.0), pour("later", 0.004)];
    (cfg, init)
}

/// A run set up from shares of its particles, none holding them all, is the one process's to
/// the bit: the time step, the skin, the motion rules (followers whose leaders start on other
/// ranks), insertions at the start and later (their first ids from the largest id anywhere)
/// and a turning mesh — on 2, 3 and 4 ranks; and a 10⁻¹⁰ nudge shows.
#[test]
fn a_run_set_up_from_shares_of_its_particles_has_the_one_process_bits() {
    type CaseOf = dyn Fn(bool) -> (SimulationConfig, Vec<ParticleInit>) + Sync;
    let cases: [(&str, &CaseOf, u64); 3] = [
        ("followed chute", &followed_chute_case, 300),
        ("poured bed", &bed_poured_into_case, 400),
        ("mesh drum", &|nudged| thrown_at_a_drum_case(nudged, true), 1_000),
    ];
    for (name, case, steps) in cases {
        let (cfg, init) = case(false);
        let mut one = simulation(cfg, &init);
        one.advance(steps);
        let want = fingerprint(&one);
        let n = one.particles().len();
        for ranks in [2, 3, 4] {
            let (got, most) = run_from_shares(&|| case(false), ranks, steps);
            let differing = want.iter().zip(&got).filter(|(a, b)| a != b).count();
            assert_eq!(want.len(), got.len(), "{name}: {ranks} ranks hold another number of particles");
            assert_eq!(
                differing, 0,
                "{name}: {differing} values differ between one process and {ranks} ranks"
            );
            assert!(most < n * 3 / 4, "{name}: a rank of {ranks} held {most} of {n} particles");
        }
        let (nudged, _) = run_from_shares(&|| case(true), 2, steps);
        let differing = want.iter().zip(&nudged).filter(|(a, b)| a != b).count();
        assert!(differing > 100, "{name}: a 1e-10 change left the state alone ({differing} values differ)");
    }
}

/// A share's bad particle, an id on two ranks' shares and a rule naming a particle no rank
/// holds are refused on every rank with the one process's message.
#[test]
fn a_bad_share_is_refused_on_every_rank_as_in_one_process() {
    type Edit = dyn Fn(&mut SimulationConfig, &mut Vec<ParticleInit>) + Sync;
    let message = |edit: &Edit| {
        let (mut cfg, mut init) = followed_chute_case(false);
        edit(&mut cfg, &mut init);
        let one = Simulation::new(cfg, grainflow::Particles::from_init(&init)).err().map(|e| e.to_string());
        let ranks = on_ranks(3, &|comm| {
            let (mut cfg, mut init) = followed_chute_case(false);
            edit(&mut cfg, &mut init);
            let (r, n) = (comm.rank(), init.len());
            let share = grainflow::Particles::from_init(&init[r * n / 3..(r + 1) * n / 3]);
            Simulation::new_over_ranks(cfg, share, comm, None).err().map(|e| e.to_string())
        });
        (one, ranks)
    };
    let edits: [&Edit; 4] = [
        // On the last rank's share, and a later one on the second's: the first is named.
        &|_, init| {
            let n = init.len();
            init[n - 2].radius = -1.0;
            init[n / 2].radius = 0.0;
        },
        &|_, init| {
            let n = init.len();
            init[n - 1].id = init[0].id;
        },
        &|cfg, _| cfg.motion.push(PrescribedMotion { particle: 999_999, rule: MotionRule::Hold }),
        &|_, init| {
            let n = init.len();
            init[n - 1].position = init[n / 2].position;
        },
    ];
    for edit in edits {
        let (one, ranks) = message(edit);
        let one = one.expect("one process refuses it");
        for (r, m) in ranks.iter().enumerate() {
            assert_eq!(m.as_deref(), Some(one.as_str()), "rank {r}");
        }
    }
}

/// 600 beads resting on a fixed floor of 1 600 triangles in a walled 40 × 20 × 30 mm box,
/// cut by the ranks: each rank bins only the floor's triangles near its box (fewer than
/// three quarters of them on 2 ranks), and the run is the one process's to the bit.
#[test]
fn each_rank_bins_the_fixed_triangles_near_its_box_alone() {
    let case = |nudged: bool| {
        let (lo, hi) = (Vec3::ZERO, Vec3::new(0.04, 0.02, 0.03));
        let mut cfg = walled_mindlin(lo, hi, 0.3);
        cfg.gravity = Vec3::new(0.0, 0.0, -9.81);
        let (nx, ny, z) = (40, 20, 0.002);
        let corner = |i: usize, j: usize| {
            Vec3::new(-0.01 + 0.06 * i as f64 / nx as f64, -0.01 + 0.04 * j as f64 / ny as f64, z)
        };
        let corners: Vec<Vec3> = (0..=ny).flat_map(|j| (0..=nx).map(move |i| corner(i, j))).collect();
        let at = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
        let triangles: Vec<[u32; 3]> = (0..ny)
            .flat_map(|j| {
                (0..nx).flat_map(move |i| {
                    [[at(i, j), at(i + 1, j), at(i + 1, j + 1)], [at(i, j), at(i + 1, j + 1), at(i, j + 1)]]
                })
            })
            .collect();
        let floor = grainflow::mesh::Mesh::from_indexed(
            "floor",
            &corners,
            &triangles,
            &grainflow::mesh::MeshTransform::default(),
        )
        .expect("a valid floor");
        cfg.meshes = vec![grainflow::mesh::MeshWall::fixed(floor, 0)];
        let mut init = bed(600, Vec3::new(0.0, 0.0, 0.00195), Vec3::new(0.04, 0.02, 0.02), 0.001, 5);
        if nudged {
            nudge(&mut init);
        }
        (cfg, init)
    };
    let (cfg, init) = case(false);
    let mut one = simulation(cfg, &init);
    one.advance(600);
    let whole = one.binned_triangles();
    assert_eq!(whole, 1_600);
    let meshed =
        one.contacts().iter().filter(|c| matches!(c.other, grainflow::ContactPartner::Mesh { .. })).count();
    assert!(meshed > 20, "only {meshed} beads touch the floor");
    let want = fingerprint(&one);
    for ranks in [2, 3] {
        let got = on_ranks(ranks, &|comm| {
            let (cfg, init) = case(false);
            let (r, n) = (comm.rank(), init.len());
            let share = grainflow::Particles::from_init(&init[r * n / ranks..(r + 1) * n / ranks]);
            let mut sim = Simulation::new_over_ranks(cfg, share, comm, None).expect("set up over ranks");
            sim.advance(600);
            (fingerprint(&sim), sim.binned_triangles())
        });
        for (r, (bits, binned)) in got.iter().enumerate() {
            assert!(*bits == want, "{ranks} ranks depart from one process");
            assert!(*binned < whole * 3 / 4, "rank {r} of {ranks} bins {binned} of {whole} triangles");
        }
    }
    let mut nudged = {
        let (c, i) = case(true);
        simulation(c, &i)
    };
    nudged.advance(600);
    assert!(fingerprint(&nudged) != want, "a 1e-10 change left the state alone");
}

/// A run whose particles all come from a batch at the start (none in the case) is cut for
/// them once they are placed: after the first rebuild each of 2 ranks owns about half.
#[test]
fn a_run_filled_at_the_start_is_cut_for_the_placed_particles() {
    let case = || {
        let (mut cfg, _) = bed_poured_into_case(false);
        cfg.insertions.truncate(1);
        cfg.insertions[0].region = grainflow::insertion::region::Region::Box {
            lo: Vec3::new(0.0, 0.0, 0.0),
            hi: Vec3::new(0.03, 0.03, 0.06),
        };
        cfg
    };
    let owned = on_ranks(2, &|comm| {
        let mut sim = Simulation::new_over_ranks(case(), grainflow::Particles::default(), comm, None)
            .expect("set up over ranks");
        let builds = sim.neighbors().stats().builds;
        while sim.neighbors().stats().builds == builds {
            sim.advance(1);
        }
        (sim.owned(), sim.total_particles())
    });
    let total = owned[0].1;
    assert!(total > 1000, "only {total} placed");
    for (r, &(n, _)) in owned.iter().enumerate() {
        assert!(n * 10 > total * 4, "rank {r} owns {n} of {total}");
    }
}
