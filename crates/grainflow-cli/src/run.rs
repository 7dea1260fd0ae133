//! `grainflow run CASE.toml [--out DIR]`

use crate::EXIT_BAD_INPUT;
use clap::Args;
use grainflow::Simulation;
use grainflow_case::CaseError;
use grainflow_run::run::{CheckpointEvery, Provenance, RunError, RunOptions, run_case};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::Path;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;
use std::time::Instant;

/// Progress of a run: a bar with particle-steps per second, simulated time and ETA on a
/// terminal; off a terminal (logs, batch jobs) a plain line at every tenth of the run and at
/// least every [`LINE_EVERY`]; nothing with `--quiet`. Rates and ETAs count only the steps of
/// this invocation (a restart's first steps are not the whole run's), over the last
/// [`RATE_WINDOW`], and are shown once there are [`RATE_MIN`] of measurements (and at the end).
struct Progress {
    kind: Kind,
    /// (when, step) samples, about a second apart, over the last `RATE_WINDOW`.
    samples: std::collections::VecDeque<(Instant, u64)>,
    last_draw: Option<Instant>,
}

enum Kind {
    Quiet,
    Bar(ProgressBar),
    Lines { next_tenth: u64, last_line: Instant },
}

/// Longest time between two progress lines off a terminal.
const LINE_EVERY: Duration = Duration::from_secs(60);
/// The span of steps the rate is measured over.
const RATE_WINDOW: Duration = Duration::from_secs(30);
/// The shortest span a rate is given for.
const RATE_MIN: Duration = Duration::from_secs(1);

impl Progress {
    fn new(quiet: bool) -> Self {
        let kind = if quiet {
            Kind::Quiet
        } else if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(0);
            let style = ProgressStyle::with_template("{bar:40.cyan/blue} {pos}/{len} steps  {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar());
            bar.set_style(style);
            Kind::Bar(bar)
        } else {
            Kind::Lines { next_tenth: 1, last_line: Instant::now() }
        };
        Progress { kind, samples: Default::default(), last_draw: None }
    }

    /// Steps per second over the window, if it spans long enough (any span at the end).
    fn step_rate(&self, finished: bool) -> Option<f64> {
        let (&(t0, s0), &(t1, s1)) = (self.samples.front()?, self.samples.back()?);
        let secs = (t1 - t0).as_secs_f64();
        (t1 - t0 >= RATE_MIN || (finished && secs > 0.0)).then(|| (s1 - s0) as f64 / secs)
    }

    /// Rate and ETA in words.
    fn rate_and_eta(&self, sim: &Simulation) -> String {
        match self.step_rate(sim.finished()) {
            Some(r) if r > 0.0 => {
                let left = sim.total_steps().saturating_sub(sim.step_index()) as f64 / r;
                format!(
                    "{:.3e} particle-steps/s  ETA {}",
                    r * sim.particles().len() as f64,
                    human_duration(left)
                )
            }
            _ => "measuring speed".into(),
        }
    }

    fn update(&mut self, sim: &Simulation) {
        if matches!(self.kind, Kind::Quiet) {
            return;
        }
        let now = Instant::now();
        let step = sim.step_index();
        if self.samples.back().is_none_or(|&(t, _)| now - t >= RATE_MIN) || sim.finished() {
            self.samples.push_back((now, step));
            while self.samples.len() > 2 && self.samples.front().is_some_and(|&(t, _)| now - t > RATE_WINDOW)
            {
                self.samples.pop_front();
            }
        }
        // The bar is redrawn ten times a second at most.
        if matches!(self.kind, Kind::Bar(_)) {
            if self.last_draw.is_some_and(|t| now - t < Duration::from_millis(100)) && !sim.finished() {
                return;
            }
            self.last_draw = Some(now);
        }
        let total = sim.total_steps().max(1);
        let text = format!("t = {:.4e} s  {}", sim.time(), self.rate_and_eta(sim));
        match &mut self.kind {
            Kind::Quiet => {}
            Kind::Bar(bar) => {
                bar.set_length(sim.total_steps());
                bar.set_position(step);
                bar.set_message(text);
            }
            Kind::Lines { next_tenth, last_line } => {
                let tenth = 10 * step / total;
                if tenth >= *next_tenth || now - *last_line >= LINE_EVERY {
                    eprintln!(
                        "{:5.1}%  step {step}/{}  {text}",
                        100.0 * step as f64 / total as f64,
                        sim.total_steps()
                    );
                    *next_tenth = tenth + 1;
                    *last_line = now;
                }
            }
        }
    }

    fn finish(&self) {
        if let Kind::Bar(bar) = &self.kind {
            bar.finish_and_clear();
        }
    }

    /// A warning on standard error, above the bar if there is one (shown with `--quiet` too).
    fn warn(&self, text: &str) {
        match &self.kind {
            Kind::Bar(bar) => bar.suspend(|| eprintln!("warning: {text}")),
            _ => eprintln!("warning: {text}"),
        }
    }
}

/// The insertions' and outlets' side of a run: the engine's flow notices as warnings while it
/// runs (the engine limits them: an insertion's shortfall when it starts and each time it has
/// doubled), and the books at the last look, for the summary.
#[derive(Default)]
struct FlowReport {
    shown: usize,
    books: Option<grainflow::FlowBooks>,
    insertions: Vec<String>,
    outlets: Vec<String>,
}

impl FlowReport {
    fn update(&mut self, sim: &Simulation, progress: &Progress) {
        if sim.insertions().is_empty() && sim.outlets().is_empty() {
            return;
        }
        for n in &sim.flow_notices()[self.shown.min(sim.flow_notices().len())..] {
            progress.warn(n);
        }
        self.shown = sim.flow_notices().len();
        if self.insertions.is_empty() && self.outlets.is_empty() {
            self.insertions = sim.insertions().iter().map(|i| i.name.clone()).collect();
            self.outlets = sim.outlets().iter().map(|o| o.name.clone()).collect();
        }
        self.books = Some(sim.flow_books());
    }

    /// The summary's lines: per insertion what was asked, inserted and missed; per outlet what
    /// it removed; whether the books close.
    fn lines(&self) -> Vec<String> {
        let Some(b) = &self.books else { return Vec::new() };
        let mut out = Vec::new();
        for (k, name) in self.insertions.iter().enumerate() {
            let (t, missed) = (b.inserted[k], b.missed[k]);
            let mut line = format!(
                "insertion '{name}': {} asked, {} inserted ({:.4e} kg of {:.4e} kg asked), {missed} not placed",
                b.asked[k],
                t.count,
                b.mass(t),
                b.asked_mass[k]
            );
            if missed > 0 {
                line.push_str(" (no room in its region)");
            }
            out.push(line);
        }
        for (k, name) in self.outlets.iter().enumerate() {
            let t = b.removed[k];
            out.push(format!("outlet '{name}': {} removed ({:.4e} kg)", t.count, b.mass(t)));
        }
        out.push(format!(
            "books: {} at the start + {} inserted = {} present + {} removed{}",
            b.initial.count,
            b.inserted_total().count,
            b.present.count,
            b.removed_total().count,
            if b.close() { "" } else { " (NOT CLOSED)" }
        ));
        out
    }
}

/// A duration in the largest units that keep it readable: "42 s", "3 min 20 s", "5 h 12 min",
/// "2 d 3 h".
fn human_duration(secs: f64) -> String {
    if !secs.is_finite() || secs >= 1e9 {
        return "more than 30 years".into();
    }
    let s = secs.round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {} s", s / 60, s % 60),
        3600..86_400 => format!("{} h {} min", s / 3600, s % 3600 / 60),
        _ => format!("{} d {} h", s / 86_400, s % 86_400 / 3600),
    }
}

#[derive(Debug, Args)]
pub struct RunArgs {
    /// The case file: TOML (docs/case-file.md), an MFIX deck, `*.dat` or `*.mfx`, read with
    /// particle_input.dat beside it (docs/mfix-decks.md), or a LIGGGHTS script, `in.*` or
    /// `*.liggghts` (docs/liggghts-scripts.md; its variables as -var NAME VALUE).
    case: PathBuf,
    /// MFIX decks: KEYWORD=VALUE overrides applied after the deck, as on MFIX's command line
    /// (e.g. TSTOP=0.5 KN=2.0e4). LIGGGHTS scripts: their variables, NAME=VALUE or
    /// -var NAME VALUE.
    #[arg(value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// MFIX decks only: a TOML file of [[motion]] tables (docs/case-file.md) that replaces
    /// user-defined functions prescribing particle motion (CALL_USR = .TRUE.).
    #[arg(long, value_name = "FILE")]
    motion: Option<PathBuf>,
    /// Output folder: timeseries.csv, snapshots/, vtk/, run-info.toml and manifest.toml are
    /// written there (default: ./out; with --restart, the checkpoint's own folder). A folder
    /// that holds an earlier run's results is refused unless --overwrite is given; one that
    /// another run is writing into is always refused.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Replace the results of an earlier run in the output folder (only the files its
    /// manifest lists, and nothing through a symbolic link; nothing else in the folder is
    /// touched).
    #[arg(long)]
    overwrite: bool,
    /// No progress bar or progress lines (the summary is still printed).
    #[arg(long, short)]
    quiet: bool,
    /// Write OUT/checkpoint.gfc every N steps ("5000") or every so much wall-clock time
    /// ("90s", "15min", "2h"), and at the last step; written atomically, the previous one
    /// survives a crash.
    #[arg(long, value_name = "STEPS|TIME", value_parser = parse_checkpoint_every)]
    checkpoint_every: Option<CheckpointEvery>,
    /// Continue from a checkpoint of this case (bit-identical to an uninterrupted run), in the
    /// checkpoint's folder unless --out says otherwise; the time series of the same run is
    /// kept up to the checkpoint's step (refused if it changed since the checkpoint).
    #[arg(long, value_name = "FILE")]
    restart: Option<PathBuf>,
    /// With --restart: accept a checkpoint written before the case file was changed (e.g.
    /// after fixing the time step of a failed run); particles must still match.
    #[arg(long, requires = "restart")]
    accept_changed_case: bool,
    /// Threads of the force stage. Default: every core, each step on them only while the
    /// engine measures that they pay (the summary says what it chose). Results are
    /// bit-identical for any count.
    #[arg(long, short = 'j', value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    threads: Option<u16>,
    /// TOML case files only: set a key as if the file said so, by its dotted path (e.g.
    /// --set time.t_stop=0.1 --set insertions.pour.count=500; entries of [[tables]] by
    /// position from 0 or by name). Validated as the file is. May be repeated.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Refuse, before it starts, a run whose memory estimate exceeds this (e.g. 8GB, 500MiB;
    /// default: half the memory available).
    #[arg(long, value_name = "SIZE", value_parser = grainflow_case::plan::parse_size)]
    pub memory_limit: Option<f64>,
}

/// Exit code of a run stopped by SIGINT/SIGTERM (128 + SIGINT, the shell's convention).
pub(crate) const EXIT_INTERRUPTED: u8 = 130;

fn parse_checkpoint_every(s: &str) -> Result<CheckpointEvery, String> {
    let t = s.trim();
    if let Ok(n) = t.parse::<u64>() {
        return if n > 0 {
            Ok(CheckpointEvery::Steps(n))
        } else {
            Err("the step count must be at least 1".into())
        };
    }
    let (num, unit) = t.split_at(t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len()));
    let scale = match unit {
        "s" => 1.0,
        "min" => 60.0,
        "h" => 3600.0,
        _ => return Err(format!("'{s}' is neither a step count nor a time like 90s, 15min or 2h")),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => {
            Ok(CheckpointEvery::WallTime(Duration::from_secs_f64(v * scale)))
        }
        _ => Err(format!("'{s}' is neither a step count nor a time like 90s, 15min or 2h")),
    }
}

/// [`load_case`], its warnings printed; a refusal printed and turned into the bad-input exit.
pub fn load_and_warn(
    case: &Path,
    overrides: &[String],
    motion: Option<&Path>,
    set: &[String],
    relay: &grainflow_case::input::Relay<'_>,
) -> Result<grainflow_case::Case, ExitCode> {
    let case = load_case(case, overrides, motion, set, relay, grainflow_case::Bed::Every).map_err(|e| {
        eprintln!("error: {e}");
        ExitCode::from(EXIT_BAD_INPUT)
    })?;
    for w in &case.warnings {
        eprintln!("warning: {w}");
    }
    Ok(case)
}

/// The `-var NAME VALUE` pairs of a LIGGGHTS script (given as `NAME=VALUE`).
pub fn script_variables(overrides: &[String]) -> Result<Vec<(String, String)>, String> {
    overrides
        .iter()
        .map(|o| match o.split_once('=') {
            Some((k, v)) if !k.is_empty() => Ok((k.to_string(), v.to_string())),
            _ => Err(format!("`{o}`: a LIGGGHTS script takes its variables as -var NAME VALUE")),
        })
        .collect()
}

/// Reads a case file, or translates an MFIX deck or a LIGGGHTS script. The error is the message to print.
/// The files the case names come through `relay` (over ranks, read by rank 0 alone); a case
/// file's initial particles are read as `bed` says (a deck's are read on every rank).
fn load_case(
    case: &Path,
    overrides: &[String],
    motion: Option<&Path>,
    set: &[String],
    relay: &grainflow_case::input::Relay<'_>,
    bed: grainflow_case::Bed,
) -> Result<grainflow_case::Case, String> {
    let sets =
        set.iter().map(|s| grainflow_case::SetOverride::parse(s)).collect::<Result<Vec<_>, String>>()?;
    if grainflow_case::liggghts::is_script(case) {
        if let Some(s) = set.first() {
            return Err(format!(
                "--set {s}: --set applies to TOML case files; {} is a LIGGGHTS script: give its variables as -var NAME VALUE",
                case.display()
            ));
        }
        if motion.is_some() {
            return Err(format!(
                "--motion applies to MFIX decks only; {} is a LIGGGHTS script",
                case.display()
            ));
        }
        let vars = script_variables(overrides)?;
        return grainflow_case::liggghts::load_relayed(case, &vars, relay)
            .map(|d| d.case)
            .map_err(|e| e.to_string());
    }
    if grainflow_case::mfix::is_deck(case) {
        if let Some(s) = set.first() {
            return Err(format!(
                "--set {s}: --set applies to TOML case files; {} is an MFIX deck: give KEYWORD=VALUE overrides after it (e.g. TSTOP=0.1)",
                case.display()
            ));
        }
        // Deck messages name the deck (and its line) already.
        return grainflow_case::mfix::load_relayed(case, overrides, motion, relay)
            .map(|d| d.case)
            .map_err(|e| e.to_string());
    }
    if let Some(o) = overrides.first() {
        return Err(format!(
            "`{o}`: KEY=VALUE overrides apply to MFIX decks (*.dat, *.mfx) only; {} is a TOML case file: edit it instead",
            case.display()
        ));
    }
    if motion.is_some() {
        return Err(format!(
            "--motion applies to MFIX decks (*.dat, *.mfx) only; {} is a TOML case file: put the rules in its [[motion]] tables",
            case.display()
        ));
    }
    grainflow_case::load_scoped(case, &sets, relay, bed).map_err(|e| match e {
        // Syntax and read errors name the file already; the others name table and key.
        CaseError::Syntax(_) | CaseError::Read { .. } => e.to_string(),
        _ => format!("{}: {e}", case.display()),
    })
}

/// The case of `args`, checked and (for a fresh run) its memory planned; the message if not.
/// Over `ranks`, a fresh run of a case file has rank 0 alone read and check the initial
/// particles; the others get their share of them (`grainflow_run::share`).
fn load_checked(
    args: &RunArgs,
    relay: &grainflow_case::input::Relay<'_>,
    ranks: Option<&std::sync::Arc<dyn grainflow::domain::Comm>>,
) -> Result<grainflow_case::Case, String> {
    let bed = match ranks {
        Some(c) if c.size() > 1 && args.restart.is_none() && !grainflow_case::mfix::is_deck(&args.case) => {
            if c.rank() == 0 {
                grainflow_case::Bed::Here
            } else {
                grainflow_case::Bed::Elsewhere
            }
        }
        _ => grainflow_case::Bed::Every,
    };
    let loaded = load_case(&args.case, &args.overrides, args.motion.as_deref(), &args.set, relay, bed)
        .and_then(|case| {
            for w in &case.warnings {
                eprintln!("warning: {w}");
            }
            if args.restart.is_none() && bed != grainflow_case::Bed::Elsewhere {
                let plan = grainflow_case::plan::plan(&case, grainflow_case::plan::memory_limit())
                    .map_err(|e| format!("{}: {e}", args.case.display()))?;
                for w in &plan.warnings {
                    eprintln!("warning: {w}");
                }
            }
            Ok(case)
        });
    match (ranks, bed) {
        (Some(comm), grainflow_case::Bed::Here | grainflow_case::Bed::Elsewhere) => {
            grainflow_run::share::share_case(&**comm, loaded).map_err(|r| match r.rank {
                0 => r.message,
                k => format!("on rank {k}: {}", r.message),
            })
        }
        _ => loaded,
    }
}

pub fn main(args: RunArgs) -> ExitCode {
    // MPI first: the ranks other than 0 say nothing from here on.
    #[cfg(feature = "mpi")]
    let mpi = match crate::ranks::start() {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: cannot start MPI: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    #[cfg(feature = "mpi")]
    let ranks = Some(mpi.comm.clone());
    #[cfg(not(feature = "mpi"))]
    let ranks: Option<std::sync::Arc<dyn grainflow::domain::Comm>> = None;
    let (rank, rank_count) = ranks.as_ref().map_or((0, 1), |c| (c.rank(), c.size()));
    // Before the set-up, which can take long (particle files, seeded lattices, placement).
    let stop = crate::signals::install();
    grainflow_case::plan::set_memory_limit(args.memory_limit);
    // Over ranks, the files the case names are read by rank 0 alone and passed on.
    let relay = ranks.clone().map(grainflow_run::relay::over_ranks);
    let relay: &grainflow_case::input::Relay<'_> = match &relay {
        Some(r) => r,
        None => &grainflow_case::input::direct,
    };
    let loaded = load_checked(&args, relay, ranks.as_ref());
    let case = match loaded {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    };
    let title = if case.title.is_empty() { args.case.display().to_string() } else { case.title.clone() };
    println!("grainflow {}: {title}", env!("CARGO_PKG_VERSION"));
    // A restart continues in its checkpoint's folder unless told otherwise.
    let out = match (&args.out, &args.restart) {
        (Some(out), _) => out.clone(),
        (None, Some(ckpt)) => match ckpt.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        },
        (None, None) => PathBuf::from("out"),
    };
    // Every rank runs the same outputs: rank 0 into the folder, the others into one of their
    // own (their snapshots and frames empty: the particles are gathered on rank 0), removed
    // at the end.
    let scratch =
        (rank > 0).then(|| std::env::temp_dir().join(format!("grainflow-rank{rank}-{}", std::process::id())));
    let out = scratch.clone().unwrap_or(out);
    let options = RunOptions {
        overwrite: args.overwrite,
        provenance: Provenance {
            case_file: args.case.clone(),
            mfix_overrides: args.overrides.clone(),
            motion_file: args.motion.clone(),
        },
        checkpoint_every: args.checkpoint_every,
        restart: args.restart.clone(),
        accept_changed_case: args.accept_changed_case,
        stop: Some(stop),
        // Threads per rank: by default the cores shared out over the ranks.
        threads: Some(args.threads.map(usize::from).unwrap_or_else(|| {
            (std::thread::available_parallelism().map_or(1, |n| n.get()) / rank_count).max(1)
        })),
        choose_threads: args.threads.is_none(),
        parallel_from: None,
        last_good_in_memory: None,
        ranks,
    };
    let mut progress = Progress::new(args.quiet);
    let mut flow = FlowReport::default();
    let result = run_case(case, &out, &options, |sim| {
        crate::signals::running();
        progress.update(sim);
        flow.update(sim, &progress);
    });
    progress.finish();
    if let Some(dir) = &scratch {
        let _ = std::fs::remove_dir_all(dir);
    }
    let missed: u64 = flow.books.as_ref().map_or(0, |b| b.missed.iter().sum());
    // A failure of one rank's own (its folder, its files) ends every rank: the others may
    // wait for it in a collective. The engine's refusals and the health check's verdict are
    // every rank's at once, and end each by itself.
    let alone = matches!(&result, Err(e) if !matches!(e, RunError::Engine(_) | RunError::Unhealthy { .. }));
    let fail = |code: u8| -> ExitCode {
        #[cfg(feature = "mpi")]
        if alone && rank_count > 1 {
            mpi.abort(code);
        }
        let _ = alone;
        ExitCode::from(code)
    };
    match result {
        Ok(s) => {
            println!("{}", s.time_step_explanation);
            let (n0, n) = s.particles;
            let count = if n0 == n {
                format!("{n} particles")
            } else {
                format!("{n0} particles at the start, {n} at the end")
            };
            println!(
                "{count}, {} steps of {:.6e} s to t = {:.6e} s; {} outputs (every {} steps) in {}",
                s.steps,
                s.dt,
                s.last.time,
                s.outputs,
                s.output_every,
                out.display()
            );
            println!(
                "kinetic energy {:.6e} J -> {:.6e} J (translational), {:.6e} J -> {:.6e} J (rotational); {} contacts at the end, max overlap/radius {:.3e}",
                s.first.kinetic_translational,
                s.last.kinetic_translational,
                s.first.kinetic_rotational,
                s.last.kinetic_rotational,
                s.last.contacts,
                s.last.max_overlap_ratio
            );
            println!(
                "wall time {:.3} s, {:.3e} particle-steps/s on {} thread{}{}",
                s.wall_seconds,
                s.particle_steps_per_second,
                s.threads,
                if s.threads == 1 { "" } else { "s" },
                if rank_count > 1 { format!(" × {rank_count} ranks") } else { String::new() }
            );
            if s.ranks.0 > 1 {
                let (d, steps) = (s.ranks.1, s.steps.max(1) as f64);
                let st = s.stages;
                println!(
                    "domain: {} ranks; rank 0 sent {:.1} messages and {:.0} B a step, {} particles moved to other ranks, {} ghosts sent at rebuilds; domain stage (with the waits for the other ranks) {:.3} s ({:.0} % of the wall time)",
                    s.ranks.0,
                    d.messages as f64 / steps,
                    d.bytes as f64 / steps,
                    d.migrated,
                    d.ghosts_sent,
                    st.domain,
                    if s.wall_seconds > 0.0 { 100.0 * st.domain / s.wall_seconds } else { 0.0 }
                );
                let timed = d.time_imbalance(s.ranks.0).map_or(String::new(), |t| {
                    format!("; the busiest rank's measured time {t:.3} × the mean")
                });
                println!(
                    "balance: the slowest rank's work {:.3} × the mean over the run (work: particles and their list partners){timed}; boxes cut again {} times; rank 0 spent {:.3} s ({:.0} % of the wall time) in the communicator",
                    d.imbalance(s.ranks.0),
                    d.recuts,
                    d.waited as f64 * 1e-9,
                    if s.wall_seconds > 0.0 { 1e-7 * d.waited as f64 / s.wall_seconds } else { 0.0 }
                );
            }
            if let Some(line) = thread_choice_line(&s.thread_report) {
                println!("{line}");
            }
            println!(
                "neighbour list: {} pairs ({:.2} per particle) at the end, rebuilt {} times in {} steps",
                s.neighbor_pairs,
                s.neighbor_pairs as f64 / n.max(1) as f64,
                s.neighbor_builds,
                s.steps
            );
            let m = s.memory;
            let per = |b: usize| b as f64 / n.max(1) as f64;
            println!(
                "memory: particles {:.0} B, neighbour list and contact history {:.0} B, thread plan {:.0} B per particle (heap, at the end)",
                per(m.particles),
                per(m.neighbors),
                per(m.threads)
            );
            let st = s.stages;
            let pct = |t: f64| if s.wall_seconds > 0.0 { 100.0 * t / s.wall_seconds } else { 0.0 };
            println!(
                "stages: neighbour search {:.3} s ({:.0} %), walls {:.3} s ({:.0} %), pairs {:.3} s ({:.0} %), mesh walls {:.3} s ({:.0} %), integration {:.3} s ({:.0} %), output {:.3} s ({:.0} %)",
                st.neighbor,
                pct(st.neighbor),
                st.walls,
                pct(st.walls),
                st.pairs,
                pct(st.pairs),
                st.meshes,
                pct(st.meshes),
                st.integrate,
                pct(st.integrate),
                s.output_seconds,
                pct(s.output_seconds)
            );
            for line in flow.lines() {
                println!("{line}");
            }
            if missed > 0 {
                eprintln!(
                    "warning: {missed} particles asked of the insertions could not be placed (see the lines above and the time series' `missed` column)"
                );
            }
            if s.threads > 1 && st.threads_slowest > 0.0 {
                let force = st.walls + st.pairs;
                println!(
                    "force stage on {} threads: {:.3} s = {:.3} s working (mean per thread) + {:.3} s waiting for the slowest thread + {:.3} s cutting blocks and handing work over",
                    s.threads,
                    force,
                    st.threads_mean,
                    st.threads_slowest - st.threads_mean,
                    (force - st.threads_slowest).max(0.0)
                );
            }
            if s.interrupted {
                let at = s.checkpoint.as_ref().map_or("(no checkpoint)".into(), |c| c.display().to_string());
                eprintln!(
                    "interrupted at step {}: state saved in {at}; continue with --restart {at}",
                    s.start_step + s.steps
                );
                return ExitCode::from(EXIT_INTERRUPTED);
            }
            ExitCode::SUCCESS
        }
        Err(e @ (RunError::Restart { .. } | RunError::Folder(_) | RunError::TooMuchOutput(_))) => {
            eprintln!("error: {e}");
            fail(EXIT_BAD_INPUT)
        }
        Err(e @ RunError::Unhealthy { .. }) => {
            eprintln!("error: the run went wrong and was stopped: {e}");
            fail(1)
        }
        Err(RunError::Engine(e)) => {
            eprintln!("error: {}: {e}", args.case.display());
            fail(EXIT_BAD_INPUT)
        }
        Err(e @ RunError::Output(_)) => {
            eprintln!("error: {e}");
            fail(1)
        }
    }
}

/// The summary's sentence on the engine's choice of threads, when it chose.
fn thread_choice_line(r: &grainflow::ThreadReport) -> Option<String> {
    if !r.automatic {
        return None;
    }
    let steps = r.steps_on_pool + r.steps_on_one;
    let share = |k: u64| if steps == 0 { 0.0 } else { 100.0 * k as f64 / steps as f64 };
    let measured = match r.last_trial {
        Some((one, pool)) => format!(
            "; last measured {one:.3e} s a step on 1 thread, {pool:.3e} s on {} ({} trial{})",
            r.pool_threads,
            r.trials,
            if r.trials == 1 { "" } else { "s" }
        ),
        None => String::from("; too few steps or particles to measure"),
    };
    Some(format!(
        "threads chosen by measured work (-j N fixes them): {:.0} % of steps on {} threads, {:.0} % on 1{measured}",
        share(r.steps_on_pool),
        r.pool_threads,
        share(r.steps_on_one)
    ))
}
