//! Ways of running a case compared in one process, in turns: each entry takes `lead` untimed
//! steps and then `chunk` timed ones in its turn, until the case ends. A slow spell of a shared
//! machine then falls on all of them alike, where separate runs minutes apart can differ by a
//! third. The untimed steps let the caches refill and idle cores wake after the other entries'
//! turns, which `grainflow run`, going on without a pause, never waits for: with none, 2
//! threads on box_lsd came out at 1.34-1.41 times 1 thread, with 10 at 1.51-1.62 (3 runs each,
//! turns of 100 steps; two copies at once 1.59-1.68 and 1.73-1.78).
//!
//! An entry is a thread count `T` (one simulation on T threads) or `TxC`: C copies of the
//! simulation at once, each on T threads of its own. `1x2` measures what two cores give this
//! code on this machine when nothing is shared between them: two independent 1-thread
//! simulations running side by side, each with its own data. A simulation split over two
//! threads cannot expect more, unless each core holding half the data helps it.
//!
//! Prints each entry's time, its speed (particle-steps per second, all copies together) and
//! that speed's ratio to the first entry's; for a single simulation on threads, where its force
//! stage went (the threads' mean work, waiting for the slowest thread, handing work over), in
//! units of the first entry's force stage divided by the thread count (meaningful when the
//! first entry is `1`). The final states of every simulation must agree to the bit (checked).
//!
//! ```text
//! cargo run --release -p grainflow-case --example alternate -- bench/cases/chute.toml 1,1x2,2 100 10
//! ```

use std::process::ExitCode;
use std::time::Instant;

use grainflow::Simulation;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("alternate: {message}");
            eprintln!(
                "usage: alternate CASE.toml ENTRY[,ENTRY...] [CHUNK_STEPS (default 100)] [LEAD_STEPS (default 10)]"
            );
            eprintln!(
                "       ENTRY: THREADS, or THREADSxCOPIES (copies run at once, each on its own threads)"
            );
            ExitCode::from(2)
        }
    }
}

/// One way of running the case: `copies` simulations at once, each on `threads` threads.
#[derive(Clone, Copy)]
struct Entry {
    threads: usize,
    copies: usize,
}

fn parse_entry(e: &str) -> Result<Entry, String> {
    let count = |s: &str, what: &str| {
        s.parse().ok().filter(|&n: &usize| n > 0).ok_or(format!("{s:?} is not a {what}"))
    };
    match e.split_once('x') {
        Some((t, c)) => Ok(Entry { threads: count(t, "thread count")?, copies: count(c, "copy count")? }),
        None => Ok(Entry { threads: count(e, "thread count")?, copies: 1 }),
    }
}

fn run(args: &[String]) -> Result<(), String> {
    let [case, entries, rest @ ..] = args else {
        return Err("a case file and entries are needed".into());
    };
    let entries: Vec<Entry> = entries.split(',').map(parse_entry).collect::<Result<_, _>>()?;
    let chunk: u64 = match rest.first() {
        Some(c) => c.parse().ok().filter(|&c| c > 0).ok_or(format!("{c:?} is not a step count"))?,
        None => 100,
    };
    let lead: u64 = match rest.get(1) {
        Some(c) => c.parse().map_err(|_| format!("{c:?} is not a step count"))?,
        None => 10,
    };
    let mut groups: Vec<Vec<Simulation>> = Vec::new();
    for e in &entries {
        let mut group = Vec::new();
        for _ in 0..e.copies {
            let case = grainflow_case::load(std::path::Path::new(case)).map_err(|e| e.to_string())?;
            let mut sim = Simulation::new(case.config, case.particles).map_err(|e| e.to_string())?;
            sim.set_threads(e.threads).map_err(|e| e.to_string())?;
            sim.enable_stage_timing();
            group.push(sim);
        }
        groups.push(group);
    }
    // Per entry: the seconds of its timed steps, and its (first copy's) force stage's times in
    // them.
    let mut seconds = vec![0.0; groups.len()];
    let mut stage_sums = vec![Timed::default(); groups.len()];
    let mut timed_steps = 0;
    while !groups[0][0].finished() {
        for (g, group) in groups.iter_mut().enumerate() {
            advance_all(group, lead);
            let (before, step) = (Timed::of(&group[0]), group[0].step_index());
            let t0 = Instant::now();
            advance_all(group, chunk);
            seconds[g] += t0.elapsed().as_secs_f64();
            stage_sums[g].add_since(&before, &Timed::of(&group[0]));
            if g == 0 {
                timed_steps += group[0].step_index() - step;
            }
        }
    }
    let first = &groups[0][0];
    let particle_steps = first.particles().len() as f64 * timed_steps as f64;
    let speed = |g: usize| entries[g].copies as f64 * particle_steps / seconds[g];
    for (g, e) in entries.iter().enumerate() {
        let copies = if e.copies == 1 { String::new() } else { format!(" x {} copies at once", e.copies) };
        print!(
            "{} thread{}{copies}: {:.3} s, {:.3e} particle-steps/s, {:.3} times the first's speed",
            e.threads,
            if e.threads == 1 { "" } else { "s" },
            seconds[g],
            speed(g),
            speed(g) / speed(0)
        );
        let st = stage_sums[g];
        if e.copies == 1 && st.slowest > 0.0 {
            let unit = stage_sums[0].force / e.threads as f64;
            print!(
                "; force stage in units of the first's ÷ {}: working {:.3}, waiting for the slowest thread {:.3}, handing over {:.3}",
                e.threads,
                st.mean / unit,
                (st.slowest - st.mean) / unit,
                (st.force - st.slowest).max(0.0) / unit
            );
        }
        println!();
    }
    let bits = |s: &Simulation| {
        s.particles().position.iter().flat_map(|x| x.to_array()).map(f64::to_bits).collect::<Vec<_>>()
    };
    if groups.iter().flatten().any(|s| bits(s) != bits(first)) {
        return Err("the final positions differ between the simulations".into());
    }
    println!("final positions bit-identical in every simulation");
    Ok(())
}

/// `steps` more steps for each simulation of a group, the copies at once, each on its own
/// threads.
fn advance_all(group: &mut [Simulation], steps: u64) {
    if steps == 0 {
        return;
    }
    if let [sim] = group {
        sim.on_pool(|sim| sim.advance(steps));
    } else {
        std::thread::scope(|scope| {
            for sim in group.iter_mut() {
                scope.spawn(move || sim.on_pool(|sim| sim.advance(steps)));
            }
        });
    }
}

/// The force stage's seconds so far: in all (walls and pairs), and the threads' mean and
/// slowest work.
#[derive(Clone, Copy, Default)]
struct Timed {
    force: f64,
    mean: f64,
    slowest: f64,
}

impl Timed {
    fn of(sim: &Simulation) -> Self {
        let st = sim.stage_times().unwrap_or_default();
        Timed { force: st.walls + st.pairs, mean: st.threads_mean, slowest: st.threads_slowest }
    }

    /// Adds what was spent from `before` to `after`.
    fn add_since(&mut self, before: &Timed, after: &Timed) {
        self.force += after.force - before.force;
        self.mean += after.mean - before.mean;
        self.slowest += after.slowest - before.slowest;
    }
}
