//! The cost of the ranks' exchanges on this machine, for the weak-scaling model of
//! docs/parallel.md: the time of one `Comm::exchange` (the call the domain stage makes: a
//! count exchange, then the words) of `s` bytes to every other rank, and of a one-word
//! `all_gather` (the agreements of a step), medians over many calls.
//!
//! ```sh
//! cargo build --release -p grainflow-cli --features mpi --example comm_cost
//! mpirun -np 2 target/release/examples/comm_cost
//! ```

// The program's own MPI layer, compiled in here, so that what is timed is what runs.
#[path = "../src/ranks.rs"]
#[allow(dead_code)]
mod ranks;

use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let ranks = ranks::start().unwrap_or_else(|e| panic!("{e}"));
    let comm = ranks.comm.clone();
    let (me, n) = (comm.rank(), comm.size());
    let time = |f: &dyn Fn(), calls: usize| -> f64 {
        let mut t = Vec::with_capacity(9);
        for _ in 0..9 {
            comm.all_gather(&[]);
            let start = Instant::now();
            for _ in 0..calls {
                f();
            }
            t.push(start.elapsed().as_secs_f64() / calls as f64);
        }
        // Every rank reports the slowest rank's time: the exchange ends for all at once.
        let all = comm.all_gather(&[median(t).to_bits()]);
        all.iter().map(|w| f64::from_bits(w[0])).fold(0.0, f64::max)
    };
    let gather = time(&|| drop(comm.all_gather(&[1])), 2_000);
    if me == 0 {
        println!("ranks = {n}");
        println!("all_gather of one word: {:.2} µs", gather * 1e6);
        println!("| bytes to each other rank | µs per exchange | GB/s out of a rank |");
        println!("|---|---|---|");
    }
    for bytes in [0usize, 64, 1 << 10, 8 << 10, 16 << 10, 32 << 10, 64 << 10, 512 << 10, 4 << 20] {
        let words = bytes / 8;
        let calls = (200_000_000 / (bytes.max(1 << 12) * n)).clamp(20, 5_000);
        let t = time(
            &|| {
                let out = (0..n).map(|r| if r == me { Vec::new() } else { vec![7u64; words] }).collect();
                drop(comm.exchange(out));
            },
            calls,
        );
        if me == 0 {
            let rate = (bytes * (n - 1)) as f64 / t / 1e9;
            println!("| {bytes} | {:.2} | {rate:.2} |", t * 1e6);
        }
    }
}
