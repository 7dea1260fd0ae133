//! Work shared out over the threads of the current rayon pool with every part pinned to one
//! thread: part i runs on thread i (modulo the thread count) every time. The force stage uses it
//! for its blocks, so that a block's histories and accumulators stay in one core's cache from
//! step to step (work stealing would hand the blocks to whichever thread is free); the
//! integrators, the neighbour list's displacement check and the periodic wrap share the slots
//! out by the same blocks, so each particle's state is read and written on one core.
//!
//! While a simulation takes steps on its pool, the pool's other threads form a team
//! ([`team`]) that waits awake between the stages, rather than in rayon's idle loop, which
//! puts them to sleep between most of a step's hand-overs. `pinned`, `in_runs` and
//! `each_taken` hand their work to the team when there is one.

mod team;

use smallvec::SmallVec;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use team::lock;
pub(crate) use team::with_team;

/// True on a thread that leads a team or works on its job (see [`team`]).
pub(crate) fn on_team() -> bool {
    team::in_job() || team::current().is_some()
}

/// Parts of a stage and their results, held inline up to this many (the blocks of a pool of up
/// to 8 threads): sharing a step's stages out asks the allocator for nothing but what rayon's
/// broadcast asks for (its list of jobs, once per call).
pub(crate) type Parts<T> = SmallVec<[T; 8]>;

/// Runs `work(i, part)` for each of `parts`, part i on thread i mod T of the current rayon pool
/// of T threads (outside a pool, on the global one), and returns the results in part order.
/// Allocates nothing itself up to 8 parts (rayon's broadcast allocates once per call).
pub(crate) fn pinned<T: Send, R: Send>(
    parts: impl IntoIterator<Item = T>,
    work: impl Fn(usize, T) -> R + Sync,
) -> Parts<R> {
    let cells: Parts<Mutex<Option<T>>> = parts.into_iter().map(|p| Mutex::new(Some(p))).collect();
    let n = cells.len();
    let results: Parts<Mutex<Option<R>>> = (0..n).map(|_| Mutex::new(None)).collect();
    let take = |i: usize| lock(&cells[i]).take().expect("every part is taken by one thread only");
    if team::in_job() {
        // Within a job of a team: here, part after part.
        for i in 0..n {
            *lock(&results[i]) = Some(work(i, take(i)));
        }
    } else if let Some(team) = team::current() {
        let size = team.size();
        team.run(&|t| {
            for i in (t..n).step_by(size) {
                let r = work(i, take(i));
                *lock(&results[i]) = Some(r);
            }
        });
    } else {
        broadcast_parts(n, &|i| *lock(&results[i]) = Some(work(i, take(i))));
    }
    results.into_iter().map(result).collect()
}

/// A part's result, once its thread has put it in.
fn result<R>(cell: Mutex<Option<R>>) -> R {
    cell.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner()).expect("one result per part")
}

/// `part(i)` for i in 0..n, part i on thread i mod T of the current rayon pool.
fn broadcast_parts(n: usize, part: &(dyn Fn(usize) + Sync)) {
    let finished = AtomicUsize::new(0);
    rayon::broadcast(|ctx| {
        for i in (ctx.index()..n).step_by(ctx.num_threads()) {
            part(i);
        }
        // Wait for the other threads here rather than in rayon's idle loop, which puts a thread
        // to sleep after a few tens of microseconds: the next stage, usually a few
        // microseconds away, would wait tens of microseconds for it to wake. The thread yields its core at
        // each look instead of spinning on it: a spinning thread slowed the other thread's
        // work (bench/results/2026-12-01-design-history.md), and with more threads than cores
        // a yield lets the others run.
        finished.fetch_add(1, Ordering::AcqRel);
        while finished.load(Ordering::Acquire) < ctx.num_threads() {
            std::thread::yield_now();
        }
    });
}

/// Runs of consecutive slots a thread takes at a time in the stages that share slots out by
/// work stealing (the mesh and cylinder walls, the rebuild's wall pairs and merge), per thread:
/// enough for the threads to even out runs with more contacts than others.
pub(crate) const RUNS_PER_THREAD: usize = 4;

/// Below this many slots to work on, those stages stay on one thread (the results do not
/// depend on it).
pub(crate) const MIN_PARALLEL_SLOTS: usize = 256;

/// `n` items in `parts` consecutive runs of nearly equal length (at most `n`, at least one).
pub(crate) fn runs(n: usize, parts: usize) -> impl Iterator<Item = std::ops::Range<usize>> + Clone {
    let parts = parts.clamp(1, n.max(1));
    (0..parts).map(move |k| k * n / parts..(k + 1) * n / parts)
}

/// `work` on [`runs`] of `n` slots ([`RUNS_PER_THREAD`] per thread of the current rayon
/// pool), the runs taken by whichever thread is free, the results in run order.
pub(crate) fn in_runs<R: Send>(n: usize, work: impl Fn(std::ops::Range<usize>) -> R + Sync) -> Vec<R> {
    let runs: Vec<_> = runs(n, RUNS_PER_THREAD * rayon::current_num_threads()).collect();
    each_taken(runs, work)
}

/// `work` on each of `parts`, the parts taken by whichever thread of the current rayon pool
/// (or team) is free, the results in part order.
pub(crate) fn each_taken<T: Send, R: Send>(parts: Vec<T>, work: impl Fn(T) -> R + Sync) -> Vec<R> {
    if team::in_job() {
        return parts.into_iter().map(work).collect();
    }
    match team::current() {
        Some(team) => {
            let cells: Vec<Mutex<Option<T>>> = parts.into_iter().map(|p| Mutex::new(Some(p))).collect();
            let results: Vec<Mutex<Option<R>>> = cells.iter().map(|_| Mutex::new(None)).collect();
            let next = AtomicUsize::new(0);
            team.run(&|_| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(cell) = cells.get(k) else { break };
                    let part = lock(cell).take();
                    if let Some(part) = part {
                        *lock(&results[k]) = Some(work(part));
                    }
                }
            });
            results.into_iter().map(result).collect()
        }
        None => {
            use rayon::prelude::*;
            parts.into_par_iter().map(&work).collect()
        }
    }
}

/// Splits `s` at the given ends of consecutive parts (the last end must be `s.len()`).
pub(crate) fn split_at_ends<T>(mut s: &mut [T], ends: impl Iterator<Item = usize>) -> Parts<&mut [T]> {
    let mut parts = Parts::new();
    let mut at = 0;
    for end in ends {
        let (head, tail) = s.split_at_mut(end - at);
        parts.push(head);
        s = tail;
        at = end;
    }
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every part is worked on exactly once, on thread i mod T, and the results come back in
    /// part order — for more, as many and fewer parts than threads.
    #[test]
    fn parts_run_once_each_on_their_thread_in_order() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        for n in [0, 2, 3, 7] {
            let parts: Vec<usize> = (0..n).map(|i| 10 * i).collect();
            let out = pool.install(|| pinned(parts, |i, p| (i, p, rayon::current_thread_index())));
            let expected: Vec<_> = (0..n).map(|i| (i, 10 * i, Some(i % 3))).collect();
            assert_eq!(out.to_vec(), expected);
        }
    }

    /// Inside a team, parts still run once each on thread i mod T with results in part order;
    /// parts taken by whichever thread is free come back in part order; work shared out
    /// from within a job runs on its thread.
    #[test]
    fn a_team_keeps_the_parts_threads_and_order() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        let (pinned_out, taken, nested) = with_team(&pool, || {
            let parts: Vec<usize> = (0..7).map(|i| 10 * i).collect();
            let pinned_out = pinned(parts, |i, p| (i, p, rayon::current_thread_index()));
            let taken = each_taken((0..50).collect(), |k: usize| k * k);
            let nested = pinned(0..3, |i, _| pinned(0..2, |j, _| 10 * i + j).to_vec());
            (pinned_out.to_vec(), taken, nested.to_vec())
        });
        let expected: Vec<_> = (0..7).map(|i| (i, 10 * i, Some(i % 3))).collect();
        assert_eq!(pinned_out, expected);
        assert_eq!(taken, (0..50).map(|k| k * k).collect::<Vec<_>>());
        assert_eq!(nested, vec![vec![0, 1], vec![10, 11], vec![20, 21]]);
    }

    /// A panic in a job of a team reaches the caller, and the team goes on working; a panic of
    /// the leader's own work ends the team instead of leaving its threads waiting.
    #[test]
    fn a_panic_in_a_team_reaches_the_caller() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let after = with_team(&pool, || {
            for bad in [0, 1] {
                let r = std::panic::catch_unwind(|| {
                    pinned(0..2, |i, _| if i == bad { panic!("part {i}") } else { i })
                });
                assert!(r.is_err(), "a panic of part {bad} is raised");
            }
            pinned(0..2, |i, _| i + 1).to_vec()
        });
        assert_eq!(after, vec![1, 2]);
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            with_team(&pool, || -> usize { panic!("the leader") })
        }));
        assert!(r.is_err());
        assert_eq!(with_team(&pool, || pinned(0..2, |i, _| i).to_vec()), vec![0, 1]);
    }
}
