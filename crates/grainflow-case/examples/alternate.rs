//! Thread counts compared in one process, in turns: one simulation of the case per thread count
//! given, each taking `chunk` steps in its turn, until the case ends. A slow spell of a shared
//! machine then falls on all of them alike, where separate runs minutes apart can differ by a
//! third. Prints each one's time and its ratio to the first; on threads, where its force stage
//! went (the threads' mean work, waiting for the slowest thread, handing work over), in units of
//! the first one's force stage divided by the thread count. The final states must agree to the
//! bit (checked).
//!
//! A simulation whose threads sat idle for a while takes a few milliseconds to resume on some
//! virtual machines: keep `chunk` at 100 steps or more.
//!
//! ```text
//! cargo run --release -p grainflow-case --example alternate -- bench/cases/chute.toml 1,2 100
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
            eprintln!("usage: alternate CASE.toml THREADS[,THREADS...] [CHUNK_STEPS (default 100)]");
            ExitCode::from(2)
        }
    }
}

fn run(args: &[String]) -> Result<(), String> {
    let [case, threads, rest @ ..] = args else {
        return Err("a case file and thread counts are needed".into());
    };
    let threads: Vec<usize> = threads
        .split(',')
        .map(|t| t.parse().ok().filter(|&t| t > 0).ok_or(format!("{t:?} is not a thread count")))
        .collect::<Result<_, _>>()?;
    let chunk: u64 = match rest.first() {
        Some(c) => c.parse().ok().filter(|&c| c > 0).ok_or(format!("{c:?} is not a step count"))?,
        None => 100,
    };
    let mut sims = Vec::new();
    for &t in &threads {
        let case = grainflow_case::load(std::path::Path::new(case)).map_err(|e| e.to_string())?;
        let mut sim = Simulation::new(case.config, case.particles).map_err(|e| e.to_string())?;
        sim.set_threads(t).map_err(|e| e.to_string())?;
        sim.enable_stage_timing();
        sims.push(sim);
    }
    let mut seconds = vec![0.0; sims.len()];
    while !sims[0].finished() {
        for (sim, s) in sims.iter_mut().zip(&mut seconds) {
            let t0 = Instant::now();
            sim.on_pool(|sim| sim.advance(chunk));
            *s += t0.elapsed().as_secs_f64();
        }
    }
    let stages: Vec<_> = sims.iter().map(|s| s.stage_times().unwrap_or_default()).collect();
    let force = |i: usize| stages[i].walls + stages[i].pairs;
    let n = sims[0].particles().len() as f64 * sims[0].step_index() as f64;
    for (i, &t) in threads.iter().enumerate() {
        print!(
            "{t} thread{}: {:.3} s, {:.3e} particle-steps/s, {:.3} of the first's time",
            if t == 1 { "" } else { "s" },
            seconds[i],
            n / seconds[i],
            seconds[i] / seconds[0]
        );
        let st = stages[i];
        if st.threads_slowest > 0.0 {
            let unit = force(0) / t as f64;
            print!(
                "; force stage in units of the first's ÷ {t}: working {:.3}, waiting for the slowest thread {:.3}, handing over {:.3}",
                st.threads_mean / unit,
                (st.threads_slowest - st.threads_mean) / unit,
                (force(i) - st.threads_slowest).max(0.0) / unit
            );
        }
        println!();
    }
    let bits = |s: &Simulation| {
        s.particles().position.iter().flat_map(|x| x.to_array()).map(f64::to_bits).collect::<Vec<_>>()
    };
    if sims.iter().any(|s| bits(s) != bits(&sims[0])) {
        return Err("the final positions differ between thread counts".into());
    }
    println!("final positions bit-identical on every thread count");
    Ok(())
}
