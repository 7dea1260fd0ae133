//! No allocation per step: on one thread, a step that does not rebuild the neighbour list asks
//! the allocator for nothing, and a rebuild for a bounded handful of blocks (the new list's
//! arrays grow in place or are kept between builds). Counted by a global allocator that
//! counts the calls made on the test's own thread.

mod common;

use common::*;
use grainflow::{Integrator, NormalModel, Simulation};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

thread_local! {
    /// Allocations and reallocations made on this thread.
    static CALLS: Cell<usize> = const { Cell::new(0) };
}

/// The system allocator, counting the allocations of each thread.
struct Counting;

#[allow(unsafe_code)]
// SAFETY: every call is passed on to the system allocator unchanged; the count is a
// thread-local cell without a destructor, which allocates nothing.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        CALLS.with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        CALLS.with(|c| c.set(c.get() + 1));
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        CALLS.with(|c| c.set(c.get() + 1));
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
