//! A team of threads that stays awake between the stages of a step.
//!
//! A step hands work to the threads several times (the force blocks, the mesh walls, the
//! integrators); between those hand-overs the calling thread works alone for tens of
//! microseconds. Rayon's idle threads fall asleep after a few tens of microseconds of nothing
//! to do, so they were asleep at almost every hand-over (five times a step in the mesh drum)
//! and waking them took longer than the work they were woken for; a core left idle may also
//! lose its caches to other work. While a [`with_team`] call runs, the pool's other threads
//! instead wait in a loop that yields the core at each look, for up to [`LINGER`], and then
//! sleep until the next hand-over. The team decides who runs what, never the order of a sum:
//! results do not depend on it.

use std::cell::RefCell;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// How long an idle thread of the team keeps looking for work before it sleeps: longer than
/// the one-thread stretches of a step, shorter than a pause between runs of steps.
pub(crate) const LINGER: Duration = Duration::from_millis(2);

/// A job of the team: thread t runs `job(t)`.
type Job = &'static (dyn Fn(usize) + Sync);

/// The team's shared state.
pub(crate) struct Team {
    size: usize,
    /// Counts the jobs handed out: a thread takes a job when it sees the count change.
    epoch: AtomicUsize,
    job: Mutex<Option<Job>>,
    /// Threads (other than the caller) that have finished the current job.
    done: AtomicUsize,
    panicked: AtomicBool,
    stop: AtomicBool,
    /// Threads asleep, and where they wait.
    sleepers: Mutex<usize>,
    wake: Condvar,
}

thread_local! {
    /// The team the current thread leads, if any.
    static LEADS: RefCell<Option<Arc<Team>>> = const { RefCell::new(None) };
    /// Set while the current thread works on a job of a team: work shared out from within a
    /// job runs on the thread itself.
    static IN_JOB: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// True while the current thread works on a job of a team.
pub(crate) fn in_job() -> bool {
    IN_JOB.with(|b| b.get())
}

/// `f` with the current thread marked as working on a job.
fn as_job<R>(f: impl FnOnce() -> R) -> R {
    IN_JOB.with(|b| b.set(true));
    let r = catch_unwind(AssertUnwindSafe(f));
    IN_JOB.with(|b| b.set(false));
    r.unwrap_or_else(|payload| resume_unwind(payload))
}

/// `m` locked; a panic on another thread while it held the lock leaves the data usable (every
/// panic is raised again where the work was handed out).
pub(super) fn lock<X>(m: &Mutex<X>) -> MutexGuard<'_, X> {
    m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl Team {
    fn new(size: usize) -> Team {
        Team {
            size,
            epoch: AtomicUsize::new(0),
            job: Mutex::new(None),
            done: AtomicUsize::new(0),
            panicked: AtomicBool::new(false),
            stop: AtomicBool::new(false),
            sleepers: Mutex::new(0),
            wake: Condvar::new(),
        }
    }

    /// Threads of the team, the leader included.
    pub(crate) fn size(&self) -> usize {
        self.size
    }

    /// Runs `work(t)` on every thread t of the team (0: the calling thread, the team's leader)
    /// and returns when all have finished. A panic on any thread is raised here.
    pub(crate) fn run(&self, work: &(dyn Fn(usize) + Sync)) {
        // SAFETY: the reference is only used by the team's threads while this call waits for
        // them to finish the job (the `done` count below, reached after every thread's call of
        // the job has returned, normally or by a caught panic), and it is cleared before this
        // call returns: it never outlives `work`.
        #[allow(unsafe_code)]
        let job: Job = unsafe { std::mem::transmute::<&(dyn Fn(usize) + Sync), Job>(work) };
        *lock(&self.job) = Some(job);
        self.done.store(0, Ordering::SeqCst);
        self.epoch.fetch_add(1, Ordering::SeqCst);
        if *lock(&self.sleepers) > 0 {
            self.wake.notify_all();
        }
        let mine = catch_unwind(AssertUnwindSafe(|| as_job(|| work(0))));
        while self.done.load(Ordering::Acquire) + 1 < self.size {
            std::thread::yield_now();
        }
        *lock(&self.job) = None;
        if let Err(payload) = mine {
            resume_unwind(payload);
        }
        if self.panicked.swap(false, Ordering::AcqRel) {
            panic!("a thread of the team panicked");
        }
    }

    /// The loop of team thread `t` until the team stops.
    fn serve(&self, t: usize) {
        // Jobs count from the team's start (a thread may join after the first was handed out).
        let mut seen = 0;
        loop {
            let since = Instant::now();
            let mut looks = 0u32;
            loop {
                if self.stop.load(Ordering::SeqCst) {
                    return;
                }
                let e = self.epoch.load(Ordering::SeqCst);
                if e != seen {
                    seen = e;
                    break;
                }
                looks += 1;
                if looks.is_multiple_of(64) && since.elapsed() > LINGER {
                    let mut asleep = lock(&self.sleepers);
                    *asleep += 1;
                    while self.epoch.load(Ordering::SeqCst) == seen && !self.stop.load(Ordering::SeqCst) {
                        asleep = self.wake.wait(asleep).unwrap_or_else(|poisoned| poisoned.into_inner());
                    }
                    *asleep -= 1;
                } else {
                    std::thread::yield_now();
                }
            }
            let job = *lock(&self.job);
            if let Some(job) = job
                && catch_unwind(AssertUnwindSafe(|| as_job(|| job(t)))).is_err()
            {
                self.panicked.store(true, Ordering::SeqCst);
            }
            self.done.fetch_add(1, Ordering::AcqRel);
        }
    }

    fn finish(&self) {
        self.stop.store(true, Ordering::SeqCst);
        let _asleep = lock(&self.sleepers);
        self.wake.notify_all();
    }
}

/// The team the current thread leads (inside [`with_team`]), if any.
pub(crate) fn current() -> Option<Arc<Team>> {
    LEADS.with(|t| t.borrow().clone())
}

/// Runs `f` on thread 0 of `pool` with the pool's other threads as its team (see the module
/// doc), directly if the current thread leads a team already.
pub(crate) fn with_team<R: Send>(pool: &rayon::ThreadPool, f: impl FnOnce() -> R + Send) -> R {
    let threads = pool.current_num_threads();
    if threads < 2 || current().is_some() {
        return pool.install(f);
    }
    let team = Arc::new(Team::new(threads));
    let f = Mutex::new(Some(f));
    let out = Mutex::new(None);
    pool.broadcast(|ctx| {
        if ctx.index() == 0 {
            /// Stops the team and leaves it however the leader's work ends.
            struct Leave<'a>(&'a Team);
            impl Drop for Leave<'_> {
                fn drop(&mut self) {
                    LEADS.with(|t| t.borrow_mut().take());
                    self.0.finish();
                }
            }
            LEADS.with(|t| *t.borrow_mut() = Some(team.clone()));
            let _leave = Leave(&team);
            let f = lock(&f).take().expect("the leader's work is taken once");
            *lock(&out) = Some(f());
        } else {
            team.serve(ctx.index());
        }
    });
    out.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner()).expect("the leader's work ran")
}
