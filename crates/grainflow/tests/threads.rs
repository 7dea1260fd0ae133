//! Deterministic parallelism: the same run on 1, 2, 3 and 4 threads, and twice on 2 threads,
//! gives bit-identical particles, forces and contact histories — for a walled bed with the
//! Hertz–Mindlin law and mass-dependent damping (velocity Verlet), and for a periodic chute on
//! a held base with the linear law (Adams–Bashforth). Slots are in random spatial order, so
//! many pairs cross between the threads' blocks.
//!
//! Equality is exact (no tolerance): the force stage's sums do not depend on their order
//! (`forces::sum`), whatever the thread count. That the comparison has teeth is shown on the
//! way: a difference of 10⁻¹⁰ in a single particle's initial velocity changes the final state.
//! (A difference of one ulp may not: the sums resolve a load to 2⁻⁴² of the largest, and a
//! change below that is rounded away.)
//!
//! Steps taken together ([`Simulation::advance`]), where velocity Verlet does one step's
//! second half kick and the next one's first in one pass, give the same bits as steps taken one
//! at a time.

mod common;

use common::*;
use grainflow::motion::{MotionRule, PrescribedMotion};
use grainflow::{Integrator, Simulation};

/// Everything a step depends on or produces, as bits.
fn fingerprint(sim: &Simulation) -> Vec<u64> {
    let p = sim.particles();
    let nl = sim.neighbors();
    let pair_history = nl.pair_history();
    let vecs = [&p.position, &p.velocity, &p.omega, &p.force, &p.torque];
    vecs.iter()
        .flat_map(|v| v.iter())
        .chain(&pair_history)
        .chain(nl.wall_history())
        .flat_map(|v| v.to_array())
        .map(f64::to_bits)
        .collect()
}

fn run(make: &dyn Fn() -> Simulation, threads: usize, steps: usize) -> Simulation {
    let mut sim = make();
    sim.set_threads(threads).expect("thread pool");
    assert_eq!(sim.threads(), threads);
    for _ in 0..steps {
        sim.step();
    }
    sim
}

fn check_thread_counts(
    name: &str,
    make: &dyn Fn() -> Simulation,
    steps: usize,
    perturbed: &dyn Fn() -> Simulation,
) {
    let reference = run(make, 1, steps);
    // Enough going on that a wrong order of the sums would show: thousands of contacts at the
    // start (the jittered lattice overlaps), still over a hundred at the end, and
    // neighbour-list rebuilds (which re-cut the threads' blocks) during the run.
    let (start, end) = (make().diagnostics().contacts, reference.diagnostics().contacts);
    assert!(start > 2000 && end > 100, "{name}: only {start} contacts at the start, {end} at the end");
    assert!(reference.neighbors().stats().builds > 2, "{name}: the list was never rebuilt");
    let want = fingerprint(&reference);
    for threads in [2, 3, 4] {
        let got = fingerprint(&run(make, threads, steps));
        let differing = want.iter().zip(&got).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{name}: {differing} values differ between 1 and {threads} threads");
    }
    let again = fingerprint(&run(make, 2, steps));
    assert!(again == want, "{name}: two runs on 2 threads differ");
    // The teeth: 1e-10 relative in one particle's initial velocity is visible at the end.
    let nudged = fingerprint(&run(perturbed, 2, steps));
    let differing = want.iter().zip(&nudged).filter(|(a, b)| a != b).count();
    assert!(differing > 100, "{name}: a 1e-10 change left the state alone ({differing} values differ)");
}

fn periodic_chute(nudged: bool) -> Simulation {
    periodic_chute_with(nudged, Integrator::AdamsBashforth, false)
}

/// The periodic chute with `integrator`; with `follower`, one particle above the base follows
/// another along x: prescribed motion that moves at every step, so that the forces must be
/// evaluated again before each first half kick.
fn periodic_chute_with(nudged: bool, integrator: Integrator, follower: bool) -> Simulation {
    let (lo, hi) = CHUTE_BOX;
    let (law, params) = lammps_hooke();
    let mut cfg = chute_config(
        law,
        phase("glass", 0.002, 2500.0),
        wall_material("lid", None, None),
        params,
        integrator,
    );
    let mut init = bed(3000, lo, hi, 0.001, 12);
    if nudged {
        nudge(&mut init);
    }
    // The lowest layer is a rough base, held in place.
    let base_top = 0.0045;
    cfg.motion = init
        .iter()
        .filter(|q| q.position.z < base_top)
        .map(|q| PrescribedMotion { particle: q.id, rule: MotionRule::Hold })
        .collect();
    assert!(cfg.motion.len() > 300, "a base of {} particles", cfg.motion.len());
    if follower {
        // The leader is nearly above or below the follower, so that the follower moves little.
        let f = init.iter().find(|q| q.position.z > base_top).expect("a free particle");
        let leader = init
            .iter()
            .filter(|q| q.position.z > base_top && (q.position.z - f.position.z).abs() > 0.004)
            .min_by(|a, b| {
                (a.position.x - f.position.x).abs().total_cmp(&(b.position.x - f.position.x).abs())
            })
            .expect("a leader")
            .id;
        let follower = f.id;
        cfg.motion.push(PrescribedMotion {
            particle: follower,
            rule: MotionRule::Follow { leader, axes: [true, false, false] },
        });
    }
    simulation(cfg, &init)
}

#[test]
fn walled_hertz_bed_is_bit_identical_on_any_thread_count() {
    check_thread_counts("walled bed", &|| walled_bed(false), 300, &|| walled_bed(true));
}

/// The walled bed under LIGGGHTS's law, whose pairs keep their histories apart: through the
/// rebuilds, which cut the threads' blocks anew.
#[test]
fn walled_liggghts_bed_is_bit_identical_on_any_thread_count() {
    let bed = |nudged| {
        let (mut cfg, init) = walled_bed_case(nudged);
        cfg.law = liggghts_hertz();
        simulation(cfg, &init)
    };
    check_thread_counts("walled LIGGGHTS bed", &|| bed(false), 300, &|| bed(true));
}

#[test]
fn periodic_chute_on_a_held_base_is_bit_identical_on_any_thread_count() {
    check_thread_counts("periodic chute", &|| periodic_chute(false), 300, &|| periodic_chute(true));
}

#[test]
fn verlet_steps_taken_together_equal_steps_taken_one_at_a_time() {
    for follower in [false, true] {
        let make = || periodic_chute_with(false, Integrator::VelocityVerlet, follower);
        for threads in [1, 2] {
            let one_by_one = run(&make, threads, 120);
            let mut together = make();
            together.set_threads(threads).expect("thread pool");
            // Calls of several lengths, one of a single step among them.
            for steps in [50, 1, 69] {
                together.advance(steps);
            }
            assert_eq!(together.step_index(), 120);
            let (want, got) = (fingerprint(&one_by_one), fingerprint(&together));
            let differing = want.iter().zip(&got).filter(|(a, b)| a != b).count();
            assert_eq!(differing, 0, "follower {follower}, {threads} thread(s): {differing} values differ");
        }
    }
}

/// The force stage's accounting on threads ([`grainflow::StageTimes`]): the threads' mean
/// working time, the slowest thread's and the stage's wall time are parts of one another
/// (mean ≤ slowest ≤ stage), and on one thread, where no thread waits for another, nothing is
/// counted.
#[test]
fn thread_working_times_are_parts_of_the_force_stage() {
    for threads in [1, 2, 3] {
        let mut sim = periodic_chute(false);
        sim.set_threads(threads).expect("thread pool");
        sim.enable_stage_timing();
        sim.advance(30);
        let t = sim.stage_times().expect("timing is on");
        if threads == 1 {
            assert_eq!((t.threads_mean, t.threads_slowest), (0.0, 0.0));
            continue;
        }
        // The mean is the sum of all parts over the thread count, the slowest the largest
        // sum of one thread's parts: with equal parts the two roundings can put the mean an
        // ulp or so above; 1e-12 relative is thousands of ulps and far below any real wait.
        assert!(t.threads_mean > 0.0, "{threads} threads: {t:?}");
        assert!(t.threads_mean <= t.threads_slowest * (1.0 + 1e-12), "{threads} threads: {t:?}");
        // Each thread's time is measured inside the stage's own (monotonic clock).
        assert!(t.threads_slowest <= t.walls + t.pairs, "{threads} threads: {t:?}");
    }
}
