//! Criterion benchmarks of whole steps on the shipped benchmark cases (`bench/cases`): the
//! settled box bed with the Hertz–Mindlin and with the linear law, and the chute-like flow,
//! on 1 and 2 threads. Each iteration takes 20 steps in one call, as `grainflow run` takes the
//! steps between two outputs or checks (`Simulation::advance`). Throughput is in particles per
//! second of one step, i.e. particle-steps/s.
//!
//! The cases start from states written by LAMMPS (`bench/compare-peers.sh` writes them into
//! `bench/cases/data/`); a case whose state is missing is skipped with a note.
//!
//! Run: `cargo bench -p grainflow-case --bench cases` (add a filter such as `chute` to run
//! one case).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use grainflow::Simulation;
use std::path::Path;
use std::time::Duration;

const CASES: [&str; 3] = ["box_hm", "box_lsd", "chute"];

/// Steps per iteration.
const STEPS: u64 = 20;

fn steps(c: &mut Criterion) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../bench/cases");
    for name in CASES {
        let path = dir.join(format!("{name}.toml"));
        let mut case = match grainflow_case::load(&path) {
            Ok(case) => case,
            Err(e) => {
                eprintln!("{name}: skipped ({e}); bench/compare-peers.sh writes the LAMMPS states");
                continue;
            }
        };
        // Steps for as long as criterion asks (the cases themselves stop after 200–1 000).
        case.config.t_stop = case.config.t_start + 1e6;
        let n = case.particles.len() as u64;
        let mut group = c.benchmark_group(name);
        group.throughput(Throughput::Elements(n * STEPS));
        group.sample_size(20).warm_up_time(Duration::from_secs(2)).measurement_time(Duration::from_secs(10));
        for threads in [1, 2] {
            let mut sim =
                Simulation::new(case.config.clone(), case.particles.clone()).expect("the case is valid");
            sim.set_threads(threads).expect("threads");
            // A long run's steps, not its first: the first builds the neighbour list.
            sim.advance(STEPS);
            group.bench_function(format!("{threads} thread{}", if threads > 1 { "s" } else { "" }), |b| {
                b.iter(|| sim.advance(STEPS))
            });
        }
        group.finish();
    }
}

criterion_group!(benches, steps);
criterion_main!(benches);
