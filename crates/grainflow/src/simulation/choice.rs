//! The engine's choice of threads. With a pool chosen by [`Simulation::choose_threads`], a
//! step runs on the pool only while that is measured to pay: the steps are timed in short
//! windows on the pool and on one thread, alternately, and the faster way is kept until the
//! particle count changes by a fifth or a long stretch of steps has passed, when it is
//! measured again. The results do not depend on the choice: every stage gives the same bits on
//! any number of threads.

use super::Simulation;

/// Steps in a window of the trial.
const WINDOW: u32 = 16;
/// Windows of the trial, alternately on the pool and on one thread.
const TRIAL_WINDOWS: usize = 6;
/// Steps a choice holds before it is measured again: the trial costs at most about 1 % of
/// them.
const HOLD: u64 = 100 * (WINDOW as u64) * TRIAL_WINDOWS as u64;
/// The pool is kept only if its median step is this much faster than one thread's: a tie
/// leaves the other cores free.
const PAYS: f64 = 0.97;

/// What the choice of threads did over a run, for its summary.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ThreadReport {
    /// True when the engine chose (false: every step used the pool it was given).
    pub automatic: bool,
    /// Threads of the pool.
    pub pool_threads: usize,
    /// Steps taken on the pool, and on one thread.
    pub steps_on_pool: u64,
    pub steps_on_one: u64,
    /// Trials measured.
    pub trials: u32,
    /// The last trial's median step time on one thread and on the pool, s.
    pub last_trial: Option<(f64, f64)>,
}

/// The state of the choice.
#[derive(Debug, Clone, Default)]
pub(crate) struct ThreadChoice {
    automatic: bool,
    /// Use the pool between trials.
    on_pool: bool,
    /// The step from which the choice is measured again.
    until: u64,
    /// The particle count the choice was made for.
    n: usize,
    /// A trial is running.
    trial: bool,
    /// Windows measured in the current trial, s per step.
    windows: Vec<f64>,
    /// The steps and seconds of the current window.
    steps: u32,
    seconds: f64,
    pub(crate) report: ThreadReport,
}

impl ThreadChoice {
    /// A choice that always uses the pool (`automatic` false) or measures.
    pub(crate) fn new(automatic: bool, pool_threads: usize) -> ThreadChoice {
        ThreadChoice {
            automatic,
            on_pool: true,
            report: ThreadReport { automatic, pool_threads, ..Default::default() },
            ..Default::default()
        }
    }

    /// Whether step `step` of `n` particles runs on the pool.
    pub(crate) fn use_pool(&mut self, step: u64, n: usize) -> bool {
        if !self.automatic {
            return true;
        }
        if !self.trial {
            let changed = (n as f64 - self.n as f64).abs() > 0.2 * self.n as f64;
            if step >= self.until || changed {
                self.trial = true;
                self.windows.clear();
                (self.steps, self.seconds, self.n) = (0, 0.0, n);
            }
        }
        if self.trial { self.windows.len().is_multiple_of(2) } else { self.on_pool }
    }

    /// Records that step `step` took `seconds` (`pool`: on the pool).
    pub(crate) fn record(&mut self, pool: bool, seconds: f64, step: u64) {
        if pool {
            self.report.steps_on_pool += 1;
        } else {
            self.report.steps_on_one += 1;
        }
        if !self.trial {
            return;
        }
        self.steps += 1;
        self.seconds += seconds;
        if self.steps < WINDOW {
            return;
        }
        self.windows.push(self.seconds / f64::from(self.steps));
        (self.steps, self.seconds) = (0, 0.0);
        if self.windows.len() < TRIAL_WINDOWS {
            return;
        }
        let median = |parity: usize| {
            let mut w: Vec<f64> = self.windows.iter().skip(parity).step_by(2).copied().collect();
            w.sort_by(f64::total_cmp);
            w[w.len() / 2]
        };
        let (pool_s, one_s) = (median(0), median(1));
        self.on_pool = pool_s < PAYS * one_s;
        self.report.trials += 1;
        self.report.last_trial = Some((one_s, pool_s));
        self.trial = false;
        self.until = step + HOLD;
    }

    /// Records a step that could not use the pool (too few particles).
    pub(crate) fn record_unpooled(&mut self) {
        self.report.steps_on_one += 1;
    }
}

impl Simulation {
    /// Gives the simulation a pool of `threads` threads and lets it choose, from the measured
    /// time of its steps, whether a step runs on the pool or on one thread (see the module
    /// doc). [`set_threads`](Self::set_threads) instead uses the pool for every step.
    pub fn choose_threads(&mut self, threads: usize) -> Result<(), crate::error::EngineError> {
        self.set_threads(threads)?;
        self.choice = ThreadChoice::new(threads > 1, threads);
        Ok(())
    }

    /// Steps run on the pool only with at least `n` particles (default
    /// [`crate::forces::MIN_PARALLEL_PARTICLES`]: below it, handing the stages to threads costs more
    /// than it saves). The results do not depend on it; a test of the threads on a small
    /// system lowers it.
    pub fn set_parallel_from(&mut self, n: usize) {
        self.parallel_from = n;
    }

    /// What the choice of threads did so far.
    pub fn thread_report(&self) -> ThreadReport {
        self.choice.report
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steps `from..to` of `n` particles, taking `pool_s` on the pool and `one_s` on one thread.
    fn steps(c: &mut ThreadChoice, from: u64, to: u64, n: usize, (pool_s, one_s): (f64, f64)) {
        for step in from..to {
            let pool = c.use_pool(step, n);
            c.record(pool, if pool { pool_s } else { one_s }, step);
        }
    }

    /// The faster way is kept after a trial; a tie keeps one thread; the trial comes again
    /// after `HOLD` steps or when the particle count changes by more than a fifth.
    #[test]
    fn the_faster_way_is_chosen_and_measured_again() {
        let trial = u64::from(WINDOW) * TRIAL_WINDOWS as u64;
        // Powers of two: the windows' means are exact.
        let (fast, slow) = (2f64.powi(-13), 2f64.powi(-12));
        let mut c = ThreadChoice::new(true, 2);
        steps(&mut c, 0, trial, 1000, (fast, slow));
        assert_eq!((c.report.trials, c.report.last_trial), (1, Some((slow, fast))));
        assert!(c.use_pool(trial, 1000));
        // Slower on the pool now: kept until the hold ends, then measured and dropped.
        steps(&mut c, trial, trial + HOLD, 1000, (3e-4, 2e-4));
        assert_eq!(c.report.trials, 1);
        steps(&mut c, trial + HOLD, 2 * trial + HOLD, 1000, (3e-4, 2e-4));
        assert_eq!(c.report.trials, 2);
        assert!(!c.use_pool(2 * trial + HOLD, 1000));
        // A tie within 3 % keeps one thread.
        let mut t = ThreadChoice::new(true, 2);
        steps(&mut t, 0, trial, 1000, (0.99e-4, 1e-4));
        assert!(!t.use_pool(trial, 1000));
        // The bed grew by a half: measured again at once (window 0 is on the pool).
        assert!(t.use_pool(trial + 1, 1500));
        steps(&mut t, trial + 1, 2 * trial + 1, 1500, (1e-4, 2e-4));
        assert_eq!(t.report.trials, 2);
        assert_eq!(t.report.steps_on_pool + t.report.steps_on_one, 2 * trial);
        // Not automatic: the pool always.
        let mut f = ThreadChoice::new(false, 2);
        steps(&mut f, 0, 1000, 1000, (3e-4, 1e-4));
        assert_eq!((f.report.steps_on_pool, f.report.trials), (1000, 0));
    }
}
