//! Work shared out over the threads of the current rayon pool with every part pinned to one
//! thread: part i runs on thread i (modulo the thread count) every time. The force stage uses it
//! for its blocks, so that a block's histories and accumulators stay in one core's cache from
//! step to step (work stealing would hand the blocks to whichever thread is free); the
//! integrators, the neighbour list's displacement check and the periodic wrap share the slots
//! out by the same blocks, so each particle's state is read and written on one core.

use smallvec::SmallVec;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

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
    fn lock<X>(m: &Mutex<X>) -> std::sync::MutexGuard<'_, X> {
        m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }
    let take = |i: usize| lock(&cells[i]).take().expect("every part is taken by one thread only");
    let finished = AtomicUsize::new(0);
    rayon::broadcast(|ctx| {
        for i in (ctx.index()..n).step_by(ctx.num_threads()) {
            let r = work(i, take(i));
            *lock(&results[i]) = Some(r);
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
    results
        .into_iter()
        .map(|r| {
            r.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner()).expect("one result per part")
        })
        .collect()
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
    use rayon::prelude::*;
    let runs: Vec<_> = runs(n, RUNS_PER_THREAD * rayon::current_num_threads()).collect();
    runs.into_par_iter().map(&work).collect()
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
}
