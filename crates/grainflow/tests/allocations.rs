//! No allocation per step: on one thread, a step that does not rebuild the neighbour list asks
//! the allocator for nothing, and a rebuild for a bounded handful of blocks (the new list's
//! arrays grow in place or are kept between builds); on threads, the engine asks for nothing
//! either, and rayon for one block per parallel stage. Counted by a global allocator that
//! counts the calls made on the test's own thread, and those made on rayon's threads.

mod common;

use common::*;
use grainflow::{Integrator, NormalModel, Simulation};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

thread_local! {
    /// Allocations and reallocations made on this thread.
    static CALLS: Cell<usize> = const { Cell::new(0) };
}

/// Allocations and reallocations made on the threads of any rayon pool (only the test of
/// threaded steps runs a pool).
static ON_POOLS: AtomicUsize = AtomicUsize::new(0);

/// Counts one call on the current thread.
fn count() {
    CALLS.with(|c| c.set(c.get() + 1));
    if rayon::current_thread_index().is_some() {
        ON_POOLS.fetch_add(1, Ordering::Relaxed);
    }
}

/// The system allocator, counting the allocations of each thread.
struct Counting;

#[allow(unsafe_code)]
// SAFETY: every call is passed on to the system allocator unchanged; the counts are a
// thread-local cell without a destructor and an atomic, and rayon's test for a pool thread
// reads such a cell: none allocates.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static COUNTING: Counting = Counting;

fn calls() -> usize {
    CALLS.with(Cell::get)
}

/// A dense periodic bed under a lid, flowing under tilted gravity: contacts forming and
/// breaking, the list rebuilt every few tens of steps.
fn flowing_bed(integrator: Integrator, normal: NormalModel) -> Simulation {
    // LAMMPS's two laws (the yardstick cases').
    let (law, params) = match normal {
        NormalModel::LinearSpringDashpot => lammps_hooke(),
        NormalModel::Hertz => lammps_mindlin(),
        NormalModel::Jkr => unreachable!("JKR is not among the laws this test draws"),
    };
    let cfg = chute_config(
        law,
        elastic_phase("glass", 0.002, 2500.0, 5.0e6, 0.3),
        wall_material("lid", Some(5.0e6), Some(0.3)),
        params,
        integrator,
    );
    let (lo, hi) = CHUTE_BOX;
    simulation(cfg, &bed(3000, lo, hi, 0.001, 5))
}

#[test]
fn steps_allocate_nothing_between_rebuilds() {
    for integrator in [Integrator::VelocityVerlet, Integrator::AdamsBashforth, Integrator::Euler] {
        for normal in [NormalModel::LinearSpringDashpot, NormalModel::Hertz] {
            let what = format!("{integrator:?} {normal:?}");
            let mut sim = flowing_bed(integrator, normal);
            // The first steps size the buffers (a rebuild's key buffer, the batches).
            sim.advance(50);
            let (mut quiet, mut rebuilding, mut most) = (0, 0, 0);
            for _ in 0..400 {
                let (builds, before) = (sim.neighbors().stats().builds, calls());
                sim.step();
                let n = calls() - before;
                if sim.neighbors().stats().builds == builds {
                    assert_eq!(n, 0, "{what}: a step without a rebuild allocated {n} times");
                    quiet += 1;
                } else {
                    most = most.max(n);
                    rebuilding += 1;
                }
            }
            // A rebuild makes the list's arrays anew: a few blocks each time (6-8 here), never
            // one per particle or pair (3 000 particles); 16 leaves room for a growing one.
            assert!(most <= 16, "{what}: a rebuild allocated {most} times");
            assert!(
                quiet > 100 && rebuilding > 2,
                "{what}: {quiet} steps without a rebuild, {rebuilding} with one: too few of either"
            );
            // The same through advance(n), which takes the steps in one call (velocity Verlet:
            // its own path), in calls short enough to fall between rebuilds.
            let mut checked = 0;
            for _ in 0..60 {
                let (builds, before) = (sim.neighbors().stats().builds, calls());
                sim.advance(2);
                if sim.neighbors().stats().builds == builds {
                    assert_eq!(calls() - before, 0, "{what}: advance(2) allocated");
                    checked += 1;
                }
            }
            assert!(checked > 10, "{what}: only {checked} calls of advance(2) without a rebuild");
        }
    }
}

/// On two threads the engine asks the allocator for nothing either: a step's parts for the
/// threads are held inline. rayon's broadcast, which hands a stage's parts to the threads,
/// allocates its list of jobs once per call; a step has at most six such stages (kick and
/// drift, the displacement test, the force stage's two passes, the last half kick, the
/// periodic wrap), so six allocations a step, whatever the number of particles. rayon's own
/// queues take a new block now and then besides (2 steps of 190 with a seventh, when this test
/// was written): at most one more in a step, and in at most 1 step of 20.
#[test]
fn threaded_steps_allocate_only_rayons_job_lists() {
    for integrator in [Integrator::VelocityVerlet, Integrator::AdamsBashforth, Integrator::Euler] {
        let what = format!("{integrator:?}");
        let mut sim = flowing_bed(integrator, NormalModel::LinearSpringDashpot);
        sim.set_threads(2).expect("a pool of two threads");
        sim.advance(50);
        let (mut quiet, mut most, mut total) = (0, 0, 0);
        let all = || calls() + ON_POOLS.load(Ordering::Relaxed);
        for _ in 0..200 {
            let (builds, before) = (sim.neighbors().stats().builds, all());
            sim.step();
            let n = all() - before;
            if sim.neighbors().stats().builds == builds {
                (quiet, most, total) = (quiet + 1, most.max(n), total + n);
            }
        }
        assert!(quiet > 50, "{what}: only {quiet} steps without a rebuild");
        assert!(most <= 7, "{what}: a step without a rebuild on two threads allocated {most} times");
        assert!(
            total <= 6 * quiet + quiet / 20,
            "{what}: {total} allocations in {quiet} steps on two threads"
        );
    }
}
