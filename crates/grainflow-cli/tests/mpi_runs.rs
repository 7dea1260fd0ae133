//! `mpirun -np N grainflow run` writes the bytes one process writes: the time series, the
//! snapshots and the VTK series of a settling bed (the shipped example: Euler, walls), the
//! shipped drum (a turning mesh whose torque is in the time series), a walled Hertz–Mindlin
//! bed (velocity Verlet) and a chute periodic in x and y on a held base (Adams–Bashforth)
//! equal those of a run without MPI, on 1, 2, 3 and 4 ranks (oversubscribed) × 1 and 2 threads.
//! That the comparison has teeth: a 10⁻¹⁰ change of one particle's initial velocity changes
//! the files. A run interrupted on 2 ranks (SIGINT to mpirun) and continued on 3, and a run
//! whose rank was killed (SIGKILL) continued from its last checkpoint in one process, write
//! the bytes of one process that never stopped. A bad case on 2 ranks is refused once and
//! every rank exits 2, within seconds, and so does a failure of rank 0 alone.
//!
//! These need OpenMPI's `mpirun` and a build with `--features mpi` (`.ci/run` installs and
//! runs them): `cargo test --release -p grainflow-cli --features mpi --test mpi_runs -- --ignored`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn grainflow() -> &'static str {
    env!("CARGO_BIN_EXE_grainflow")
}

/// `grainflow run CASE --out OUT -j J -q`, on `ranks` MPI ranks (None: without mpirun).
fn run(case: &Path, out: &Path, ranks: Option<usize>, threads: usize) -> Output {
    command(case, out, ranks, threads, &[]).output().expect("mpirun (OpenMPI) is installed")
}

/// The command of [`run`], with `extra` arguments.
fn command(case: &Path, out: &Path, ranks: Option<usize>, threads: usize, extra: &[&str]) -> Command {
    if !cfg!(feature = "mpi") {
        panic!("build with --features mpi: without it mpirun starts unrelated processes");
    }
    let args = ["run".into(), case.display().to_string(), "--out".into(), out.display().to_string()];
    let more = ["-j".to_string(), threads.to_string(), "-q".into()];
    let mut cmd = match ranks {
        None => Command::new(grainflow()),
        Some(n) => {
            let mut c = Command::new("mpirun");
            c.args(["--oversubscribe", "--allow-run-as-root", "-np", &n.to_string(), grainflow()]);
            c
        }
    };
    cmd.args(args).args(more).args(extra);
    cmd
}

/// The time series and every snapshot, by name.
fn outputs(out: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files =
        vec![("timeseries.csv".to_string(), std::fs::read(out.join("timeseries.csv")).expect("series"))];
    let mut snaps: Vec<PathBuf> = std::fs::read_dir(out.join("snapshots"))
        .expect("snapshots")
        .map(|e| e.expect("entry").path())
        .collect();
    if let Ok(vtk) = std::fs::read_dir(out.join("vtk")) {
        snaps.extend(vtk.map(|e| e.expect("entry").path()));
    }
    snaps.sort();
    for s in snaps {
        files.push((
            s.file_name().unwrap().to_string_lossy().into_owned(),
            std::fs::read(&s).expect("snapshot"),
        ));
    }
    files
}

/// A deterministic stream in [0, 1) (a 64-bit LCG: the test needs only variety, not quality).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A particle CSV of a jittered lattice of `n` spheres of diameter ≈ `d` in [0, lx] × [0, ly],
/// layer above layer from z = d/2 + `z0`, with random velocities of `speed`; with `nudge`, the
/// last particle's x-velocity 10⁻¹⁰ larger, relative.
fn lattice(n: usize, lx: f64, ly: f64, d: f64, z0: f64, speed: f64, nudge: bool, seed: u64) -> String {
    let mut rng = Lcg(seed);
    let (nx, ny) = ((lx / d).floor() as usize, (ly / d).floor() as usize);
    let mut s = String::from("id,phase,x,y,z,diameter,u,v,w\n");
    for k in 0..n {
        let (i, j, l) = (k % nx, (k / nx) % ny, k / (nx * ny));
        let mut j3 = || 0.05 * d * (2.0 * rng.next() - 1.0);
        let (x, y, z) =
            ((i as f64 + 0.5) * d + j3(), (j as f64 + 0.5) * d + j3(), z0 + (l as f64 + 0.5) * d + j3());
        let dia = d * (0.97 + 0.03 * rng.next());
        let mut u = speed * (2.0 * rng.next() - 1.0);
        let (v, w) = (speed * (2.0 * rng.next() - 1.0), speed * (2.0 * rng.next() - 1.0));
        if nudge && k + 1 == n {
            u += 1e-10 * u.abs().max(1e-3);
        }
        s.push_str(&format!(
            "{},1,{x:.17e},{y:.17e},{z:.17e},{dia:.17e},{u:.17e},{v:.17e},{w:.17e}\n",
            k + 1
        ));
    }
    s
}

/// The three cases, written into `dir` (with `nudge`, each with one particle nudged).
/// A shipped example written to `dir/name`, its case's lines that start with a key replaced,
/// and with `nudge` the first particle's x velocity changed by 1e-10 of itself.
fn example(dir: &Path, name: &str, edits: &[(&str, &str)], nudge: bool) -> PathBuf {
    let at = dir.join(name);
    let made = Command::new(grainflow()).args(["example", name, "--dir"]).arg(&at).output().expect("runs");
    assert!(made.status.success(), "{}", String::from_utf8_lossy(&made.stderr));
    let text = std::fs::read_to_string(at.join("case.toml")).expect("case");
    let text: String = text
        .lines()
        .map(|l| edits.iter().find(|(key, _)| l.starts_with(key)).map_or(l, |(_, line)| line))
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(at.join("case.toml"), text).expect("case");
    if nudge {
        let p = std::fs::read_to_string(at.join("particles.csv")).expect("particles");
        let mut lines: Vec<String> = p.lines().map(String::from).collect();
        let mut f: Vec<String> = lines[1].split(',').map(String::from).collect();
        let u: f64 = f[6].parse().expect("u");
        f[6] = format!("{:.17e}", u + 1e-10 * u.abs().max(1e-3));
        lines[1] = f.join(",");
        std::fs::write(at.join("particles.csv"), lines.join("\n") + "\n").expect("particles");
    }
    at.join("case.toml")
}

fn cases(dir: &Path, nudge: bool) -> Vec<PathBuf> {
    std::fs::create_dir_all(dir).expect("case dir");
    let mut out = Vec::new();
    // The shipped settling bed, shortened, with its VTK series (particles, contacts, walls).
    out.push(example(
        dir,
        "settling-bed",
        &[
            ("t_stop", "t_stop = 0.06"),
            ("vtk_interval", "vtk_interval = 0.01"),
            ("interval", "interval = 0.01"),
        ],
        nudge,
    ));
    // The shipped drum, a turning mesh, shortened and turning from the start.
    out.push(example(
        dir,
        "rotating-drum",
        &[
            ("t_stop", "t_stop = 0.04"),
            ("ramp", "ramp = 0.0"),
            ("rpm", "rpm = 30.0"),
            ("vtk_interval", "vtk_interval = 0.01"),
            ("interval", "interval = 0.01"),
        ],
        nudge,
    ));
    // The shipped hopper, filled by an insertion behind a gate that opens, drained through
    // an outlet: shortened to 600 beads, the gate open at 0.15 s, a quarter of them out by
    // the end. (No particle file: the nudge is in the insertion's velocity.)
    let v = if nudge { "velocity = [0.0, 0.0, -0.50000000005]" } else { "velocity = [0.0, 0.0, -0.5]" };
    out.push(example(
        dir,
        "hopper-fill-discharge",
        &[
            ("count = 3000", "count = 600"),
            ("t_stop", "t_stop = 0.35"),
            ("start = 0.6", "start = 0.15"),
            ("stop = 0.7", "stop = 0.25"),
            ("velocity = [0.0, 0.0, -0.5]", v),
        ],
        false,
    ));
    // MFIX 21.3.2's mass-inflow hopper tutorial (vendored unchanged by the case crate's
    // tests): GENER_PART_CONFIG's bed in an STL hopper, a mass inlet and a pressure outlet,
    // shortened to 3 ms (645 steps) with a frame every 1 ms. The nudge: gravity by 1e-11.
    let decks = Path::new(env!("CARGO_MANIFEST_DIR")).join("../grainflow-case/tests/mfix_decks/hopper");
    let mfix = dir.join("mfix-hopper");
    std::fs::create_dir_all(&mfix).expect("deck dir");
    for f in ["hopper.stl", "bimodal_psd.txt"] {
        std::fs::copy(decks.join(f), mfix.join(f)).expect("vendored deck");
    }
    let deck = std::fs::read_to_string(decks.join("hopper_mass_inflow.mfx")).expect("vendored deck");
    let g = if nudge { "gravity_y = -9.8066500001" } else { "gravity_y = -9.80665" };
    let edited = deck
        .replace("tstop    = 0.5", "tstop    = 0.003")
        .replace("vtk_dt(1)       = 0.01", "vtk_dt(1)       = 0.001")
        .replace("gravity_y = -9.80665", g);
    assert_eq!(edited.matches("0.003").count(), deck.matches("0.003").count() + 1, "the deck's TSTOP line");
    std::fs::write(mfix.join("hopper_mass_inflow.mfx"), edited).expect("deck");
    out.push(mfix.join("hopper_mass_inflow.mfx"));
    // A walled Hertz–Mindlin bed, velocity Verlet.
    std::fs::write(dir.join("hertz.csv"), lattice(2000, 0.03, 0.03, 0.002, 0.0, 0.3, nudge, 11))
        .expect("csv");
    std::fs::write(
        dir.join("hertz.toml"),
        r#"version = 1
[domain]
min = [0.0, 0.0, 0.0]
max = [0.03, 0.03, 0.06]
[physics]
gravity = [0.0, 0.0, -9.81]
[[phases]]
name = "glass"
diameter = 0.002
density = 2500.0
youngs_modulus = 5.0e6
poisson_ratio = 0.3
[[wall_materials]]
name = "wall"
youngs_modulus = 5.0e6
poisson_ratio = 0.3
[contact]
model = "hertz"
history = "rotate"
lever_arm = "lammps_granular"
damping = "tsuji"
coulomb = "lammps"
[contact.particle]
en = 0.9
etat_fac = 1.0
mu = 0.5
[contact.wall]
en = 0.9
etat_fac = 1.0
mu = 0.5
[time]
t_stop = 0.008
dt = 2e-5
integrator = "velocity_verlet"
[output]
interval = 0.002
[particles]
file = "hertz.csv"
max_initial_overlap = 0.2
"#,
    )
    .expect("case");
    out.push(dir.join("hertz.toml"));
    // A chute periodic in x and y on a held base, Adams–Bashforth.
    std::fs::write(dir.join("chute.csv"), lattice(2400, 0.03, 0.03, 0.002, 0.0, 0.3, nudge, 12))
        .expect("csv");
    std::fs::write(
        dir.join("chute.toml"),
        r#"version = 1
[domain]
min = [0.0, 0.0, 0.0]
max = [0.03, 0.03, 0.06]
periodic = ["x", "y"]
walls = ["z_min", "z_max"]
[physics]
gravity = [4.3, 0.0, -8.8]
[[phases]]
name = "glass"
diameter = 0.002
density = 2500.0
[contact]
model = "lsd"
history = "project"
lever_arm = "radius"
damping = "mass_velocity"
coulomb = "lammps"
[contact.particle]
kn = 2000.0
gamma_n = 1314.0
gamma_t = 657.0
mu = 0.5
[contact.wall]
kn = 2000.0
gamma_n = 1314.0
gamma_t = 657.0
mu = 0.5
[time]
t_stop = 0.008
dt = 2e-5
integrator = "adams_bashforth"
[output]
interval = 0.002
[particles]
file = "chute.csv"
max_initial_overlap = 0.2
[[motion]]
particles = [1, 225]
rule = "hold"
"#,
    )
    .expect("case");
    out.push(dir.join("chute.toml"));
    out
}

#[test]
#[ignore = "needs MPI (OpenMPI's mpirun, a build with --features mpi)"]
fn outputs_on_any_rank_and_thread_count_equal_one_process() {
    let dir = tempfile::tempdir().expect("temp dir");
    let plain = cases(&dir.path().join("plain"), false);
    let nudged = cases(&dir.path().join("nudged"), true);
    for (case, nudged) in plain.iter().zip(&nudged) {
        let name = case.display().to_string();
        let one = dir.path().join("one");
        let r = run(case, &one, None, 1);
        assert!(r.status.success(), "{name}: {}", String::from_utf8_lossy(&r.stderr));
        let want = outputs(&one);
        assert!(want.len() > 2, "{name}: only {} output files", want.len());
        std::fs::remove_dir_all(&one).expect("clean");
        for ranks in [1, 2, 3, 4] {
            for threads in [1, 2] {
                let out = dir.path().join(format!("r{ranks}j{threads}"));
                let r = run(case, &out, Some(ranks), threads);
                assert!(
                    r.status.success(),
                    "{name} on {ranks} ranks: {}",
                    String::from_utf8_lossy(&r.stderr)
                );
                let got = outputs(&out);
                let names: Vec<&str> = got.iter().map(|f| f.0.as_str()).collect();
                assert_eq!(names, want.iter().map(|f| f.0.as_str()).collect::<Vec<_>>(), "{name}");
                for (a, b) in want.iter().zip(&got) {
                    assert!(a.1 == b.1, "{name}: {} differs on {ranks} ranks × {threads} threads", a.0);
                }
                let info = std::fs::read_to_string(out.join("run-info.toml")).expect("run info");
                assert!(info.contains(&format!("ranks = {ranks}\n")), "{info}");
                std::fs::remove_dir_all(&out).expect("clean");
            }
        }
        // The teeth: the nudged case writes other bytes on 2 ranks.
        let out = dir.path().join("nudged-out");
        let r = run(nudged, &out, Some(2), 1);
        assert!(r.status.success(), "{name} nudged: {}", String::from_utf8_lossy(&r.stderr));
        let differ = want.iter().zip(outputs(&out)).filter(|(a, b)| a.1 != b.1).count();
        assert!(differ >= 2, "{name}: a 1e-10 nudge changed only {differ} files");
        std::fs::remove_dir_all(&out).expect("clean");
    }
}

/// The shipped settling bed with beads of its lowest layer that follow others of that layer
/// in height: ids 1–9 (at x = 3 mm) copy the y of 73–81 (at x = 47 mm, on another rank when
/// the cut is across x), 10 follows 1 (whose rule comes first, so 10 copies where that rule
/// put 1), and 19 follows 20, whose rule comes after (so 19 copies where 20 was): MFIX's
/// "follow" hook. On 2 and 3 ranks the files are one process's, byte for byte.
#[test]
#[ignore = "needs MPI (OpenMPI's mpirun, a build with --features mpi)"]
fn beads_following_leaders_on_other_ranks_write_one_process_bytes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rule = |who: &str, leader: &str| {
        format!("\n[[motion]]\nparticles = {who}\nrule = \"follow\"\n{leader}\naxes = [\"y\"]\n")
    };
    let follow = rule("[1, 9]", "leader_offset = 72")
        + &rule("10", "leader = 1")
        + &rule("19", "leader = 20")
        + &rule("20", "leader = 80");
    let case = |nudge: bool| {
        let at = dir.path().join(if nudge { "nudged" } else { "plain" });
        std::fs::create_dir_all(&at).expect("case dir");
        let edits = [
            ("t_stop", "t_stop = 0.1"),
            ("vtk_interval", "vtk_interval = 0.05"),
            ("interval", "interval = 0.02"),
        ];
        let bed = example(&at, "settling-bed", &edits, nudge);
        let text = std::fs::read_to_string(&bed).expect("case");
        std::fs::write(&bed, text + &follow).expect("case");
        bed
    };
    let bed = case(false);
    let one = dir.path().join("one");
    let r = run(&bed, &one, None, 1);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let want = outputs(&one);
    for ranks in [2, 3] {
        let out = dir.path().join(format!("r{ranks}"));
        let r = run(&bed, &out, Some(ranks), 1);
        assert!(r.status.success(), "{ranks} ranks: {}", String::from_utf8_lossy(&r.stderr));
        for (a, b) in want.iter().zip(&outputs(&out)) {
            assert!(a.0 == b.0 && a.1 == b.1, "{} differs on {ranks} ranks", a.0);
        }
    }
    let out = dir.path().join("nudged-out");
    assert!(run(&case(true), &out, Some(2), 1).status.success());
    let differ = want.iter().zip(outputs(&out)).filter(|(a, b)| a.1 != b.1).count();
    assert!(differ >= 2, "a 1e-10 nudge changed only {differ} files");
}

#[test]
#[ignore = "needs MPI (OpenMPI's mpirun, a build with --features mpi)"]
fn a_bad_case_on_two_ranks_exits_2_at_once_with_one_message() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = dir.path().join("case.toml");
    std::fs::write(&case, "version = 1\n[domain]\nmin = [0,0,0]\nmax = [1,1,1]\n[[phases]]\nname = \"a\"\ndiameter = -0.1\ndensity = 1000.0\n").expect("write");
    let start = Instant::now();
    let r = run(&case, &dir.path().join("out"), Some(2), 1);
    // Every rank reads and refuses the case before any message between them: none waits.
    assert!(start.elapsed() < Duration::from_secs(30), "took {:?}", start.elapsed());
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.matches("diameter").count(), 1, "the message once, from rank 0: {stderr}");
    // The files a case names are read by rank 0 alone and passed on: one it cannot open
    // ends every rank the same way.
    let drum = example(dir.path(), "rotating-drum", &[], false);
    std::fs::remove_file(drum.with_file_name("drum.obj")).expect("remove the mesh");
    let start = Instant::now();
    let r = run(&drum, &dir.path().join("no-mesh"), Some(2), 1);
    assert!(start.elapsed() < Duration::from_secs(30), "took {:?}", start.elapsed());
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.matches("drum.obj").count(), 1, "the message once, from rank 0: {stderr}");
    std::fs::remove_dir_all(drum.parent().expect("folder")).expect("clean");
    // A failure of rank 0 alone (its output folder holds another run's results, which the
    // other ranks' scratch folders do not) ends every rank: none waits for it in a collective.
    let drum = example(dir.path(), "rotating-drum", &[("t_stop", "t_stop = 0.01")], false);
    let taken = dir.path().join("taken");
    assert!(run(&drum, &taken, None, 1).status.success());
    let start = Instant::now();
    let r = run(&drum, &taken, Some(2), 1);
    assert!(start.elapsed() < Duration::from_secs(30), "took {:?}", start.elapsed());
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.matches("holds the results of an earlier run").count(), 1, "{stderr}");
}

/// The shipped drum turning at 30 rpm from the start for 1 s (20 000 steps), long enough to
/// be caught mid-way, with its outputs every 0.1 s.
fn long_drum(dir: &Path) -> PathBuf {
    example(
        dir,
        "rotating-drum",
        &[
            ("t_stop", "t_stop = 1.0"),
            ("ramp", "ramp = 0.0"),
            ("rpm", "rpm = 30.0"),
            ("vtk_interval", "vtk_interval = 0.1"),
            ("interval", "interval = 0.1"),
        ],
        false,
    )
}

/// Starts `cmd` and waits for `file` to appear (the run's first checkpoint).
fn start_until(mut cmd: Command, file: &Path) -> std::process::Child {
    let child =
        cmd.stdout(Stdio::null()).stderr(Stdio::piped()).spawn().expect("mpirun (OpenMPI) is installed");
    let t0 = Instant::now();
    while !file.exists() {
        assert!(t0.elapsed() < Duration::from_secs(120), "no {} after 2 minutes", file.display());
        std::thread::sleep(Duration::from_millis(5));
    }
    child
}

/// Waits at most `limit` for `child` to end; its output.
fn wait_at_most(mut child: std::process::Child, limit: Duration) -> Output {
    let t0 = Instant::now();
    while child.try_wait().expect("waits").is_none() {
        if t0.elapsed() > limit {
            let _ = child.kill();
            panic!("still running {limit:?} after the signal");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("waits")
}

/// A SIGINT to mpirun saves one checkpoint of the whole run (gathered on rank 0); that run,
/// continued on 3 ranks, writes the bytes of one process that never stopped: the time
/// series, the snapshots and the VTK series with the drum.
#[test]
#[ignore = "needs MPI (OpenMPI's mpirun, a build with --features mpi)"]
fn interrupted_on_two_ranks_and_continued_on_three_a_run_writes_one_process_bytes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = long_drum(dir.path());
    let r = run(&case, &dir.path().join("one"), None, 1);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let want = outputs(&dir.path().join("one"));
    let part = dir.path().join("part");
    let ckpt = part.join("checkpoint.gfc");
    let child = start_until(command(&case, &part, Some(2), 1, &["--checkpoint-every", "500"]), &ckpt);
    let killed = Command::new("kill").arg("-INT").arg(child.id().to_string()).status().expect("kill");
    assert!(killed.success());
    let out = wait_at_most(child, Duration::from_secs(60));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "the run ended before the signal: make it longer. {stderr}");
    assert!(stderr.contains("interrupted at step") && stderr.contains("--restart"), "{stderr}");
    let info = std::fs::read_to_string(part.join("run-info.toml")).expect("run info");
    assert!(info.contains("status = \"interrupted\""), "{info}");
    let resumed = command(&case, &part, Some(3), 1, &["--restart", ckpt.to_str().expect("utf-8")])
        .output()
        .expect("runs");
    assert!(resumed.status.success(), "{}", String::from_utf8_lossy(&resumed.stderr));
    let got = outputs(&part);
    let names = |f: &[(String, Vec<u8>)]| f.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&got), names(&want));
    for (a, b) in want.iter().zip(&got) {
        assert!(a.1 == b.1, "{} differs after the restart on 3 ranks", a.0);
    }
}

/// The processes mpirun started (its children), by pid.
fn children(pid: u32) -> Vec<u32> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir("/proc").expect("/proc").flatten() {
        let Ok(stat) = std::fs::read_to_string(entry.path().join("stat")) else { continue };
        // pid (comm) state ppid …: the name may hold spaces, so read after its ')'.
        let after = &stat[stat.rfind(')').map_or(0, |k| k + 1)..];
        let ppid = after.split_whitespace().nth(1).and_then(|p| p.parse::<u32>().ok());
        if ppid == Some(pid)
            && let Ok(child) = entry.file_name().to_string_lossy().parse()
        {
            found.push(child);
        }
    }
    found
}

/// A rank killed with SIGKILL ends the run within seconds with mpirun's message naming the
/// signal, and the last checkpoint stays whole: continued in one process, the run writes the
/// bytes of one that never stopped.
#[test]
#[ignore = "needs MPI (OpenMPI's mpirun, a build with --features mpi)"]
fn a_rank_killed_ends_the_run_and_its_last_checkpoint_goes_on() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = long_drum(dir.path());
    let r = run(&case, &dir.path().join("one"), None, 1);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let want = outputs(&dir.path().join("one"));
    let part = dir.path().join("part");
    let ckpt = part.join("checkpoint.gfc");
    let child = start_until(command(&case, &part, Some(2), 1, &["--checkpoint-every", "500"]), &ckpt);
    let ranks = children(child.id());
    assert_eq!(ranks.len(), 2, "mpirun's children: {ranks:?}");
    let killed = Command::new("kill").arg("-KILL").arg(ranks[1].to_string()).status().expect("kill");
    assert!(killed.success());
    let out = wait_at_most(child, Duration::from_secs(30));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "the run ended before the signal: make it longer. {stderr}");
    assert!(stderr.contains("signal 9"), "{stderr}");
    let resumed =
        command(&case, &part, None, 1, &["--restart", ckpt.to_str().expect("utf-8")]).output().expect("runs");
    assert!(resumed.status.success(), "{}", String::from_utf8_lossy(&resumed.stderr));
    let got = outputs(&part);
    assert_eq!(got.len(), want.len());
    for (a, b) in want.iter().zip(&got) {
        assert!(a.0 == b.0 && a.1 == b.1, "{} differs after the restart", a.0);
    }
}

/// A run on 2 ranks that fails its health check (a forced time step far beyond the stable
/// one) exits 1 with the diagnosis once and saves the last good state of the whole run; that
/// state, continued in one process with the case fixed, writes the bytes the last good state
/// of the same run in one process does.
#[test]
#[ignore = "needs MPI (OpenMPI's mpirun, a build with --features mpi)"]
fn a_failed_health_check_on_two_ranks_saves_the_whole_last_good_state() {
    let dir = tempfile::tempdir().expect("temp dir");
    let good = example(dir.path(), "settling-bed", &[("t_stop", "t_stop = 0.05")], false);
    let text = std::fs::read_to_string(&good).expect("case");
    let bad = good.with_file_name("bad.toml");
    let broken = text.replace("integrator = \"euler\"", "integrator = \"euler\"\ndt = 4e-4\nforce_dt = true");
    assert_ne!(text, broken);
    std::fs::write(&bad, broken).expect("case");
    let mut resumed = Vec::new();
    for (name, ranks) in [("one", None), ("two", Some(2))] {
        let out = dir.path().join(name);
        let r = run(&bad, &out, ranks, 1);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{name}: {stderr}");
        assert_eq!(stderr.matches("Likely cause").count(), 1, "{name}: {stderr}");
        let saved = out.join("checkpoint-last-good.gfc");
        let again = dir.path().join(format!("{name}-resumed"));
        let saved = saved.to_str().expect("utf-8");
        let r = command(&good, &again, None, 1, &["--accept-changed-case", "--restart", saved])
            .output()
            .expect("runs");
        assert!(r.status.success(), "{name}: {}", String::from_utf8_lossy(&r.stderr));
        resumed.push(outputs(&again));
    }
    assert!(resumed[0].len() > 1 && resumed[0] == resumed[1], "the two last good states go on differently");
}

/// The hopper filled, opened and half-drained on 2 ranks, its last checkpoint (with the
/// particles caught and not yet removed, and the outlet's books) continued to the end on 3
/// ranks: the bytes of one process that ran it through.
#[test]
#[ignore = "needs MPI (OpenMPI's mpirun, a build with --features mpi)"]
fn a_hopper_drained_on_two_ranks_and_continued_on_three_writes_one_process_bytes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = cases(&dir.path().join("cases"), false).remove(2);
    assert!(case.ends_with("hopper-fill-discharge/case.toml"));
    let r = run(&case, &dir.path().join("one"), None, 1);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let want = outputs(&dir.path().join("one"));
    let part = dir.path().join("part");
    // To 0.3 s, 6 126 steps: a row of the schedule (every 1 021 steps), beads on their way out.
    let r = command(&case, &part, Some(2), 1, &["--set", "time.t_stop=0.3", "--checkpoint-every", "100000"])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(!stdout.contains("outlet 'below': 0 removed"), "nothing left by 0.3 s: {stdout}");
    let ckpt = part.join("checkpoint.gfc");
    let ckpt = ckpt.to_str().expect("utf-8");
    let r = command(&case, &part, Some(3), 1, &["--restart", ckpt, "--accept-changed-case"])
        .output()
        .expect("runs");
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // The first run's last frames (at its last step, off the schedule) stay beside the rest.
    let mut got = outputs(&part);
    let extra: Vec<String> =
        got.iter().map(|f| f.0.clone()).filter(|n| !want.iter().any(|w| &w.0 == n)).collect();
    let step = |n: &str| n.rsplit('_').next().and_then(|s| s.split('.').next()).unwrap_or("").to_string();
    assert!(extra.len() == 4 && extra.iter().all(|n| step(n) == step(&extra[0])), "{extra:?}");
    got.retain(|f| !extra.contains(&f.0));
    let names = |f: &[(String, Vec<u8>)]| f.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&got), names(&want));
    for (a, b) in want.iter().zip(&got) {
        assert!(a.1 == b.1, "{} differs after the restart on 3 ranks", a.0);
    }
}

/// The shipped hopper, filled and drained dry (3 000 beads, 3.5 s), on 3 ranks without
/// rebalancing: the first cut of the empty domain leaves one rank half of the beads and the
/// other two a quarter each, and every rank loses its last particle to the outlet, some
/// while the others still hold theirs and the meshes are still in the step. The outputs are
/// one process's; with rebalancing by counted work the slowest rank's work over the run is
/// nearer the mean than without (the figures on `balance:` lines of the summaries).
#[test]
#[ignore = "needs MPI (OpenMPI's mpirun, a build with --features mpi)"]
fn a_hopper_drained_dry_on_three_ranks_equals_one_process_and_rebalancing_evens_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = example(dir.path(), "hopper-fill-discharge", &[], false);
    let text = std::fs::read_to_string(&case).expect("case");
    let fixed = case.with_file_name("fixed.toml");
    std::fs::write(&fixed, format!("{text}\n[parallel]\nrebalance = false\n")).expect("case");
    // Weighed by counted work, whose re-cuts are the same on every run (by measured time, the
    // default, they follow the processors' speeds).
    let counted = case.with_file_name("counted.toml");
    std::fs::write(&counted, format!("{text}\n[parallel]\nweigh = \"work\"\n")).expect("case");
    let r = run(&case, &dir.path().join("one"), None, 1);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let want = outputs(&dir.path().join("one"));
    let balance = |stdout: &str| -> f64 {
        let line = stdout.lines().find(|l| l.starts_with("balance:")).expect("a balance line");
        line.split_whitespace().nth(5).and_then(|w| w.parse().ok()).expect("slowest ÷ mean")
    };
    let mut slowest = Vec::new();
    for (name, c) in [("without rebalancing", &fixed), ("with rebalancing", &counted)] {
        let out = dir.path().join(name.replace(' ', "-"));
        let r = command(c, &out, Some(3), 1, &[]).output().expect("runs");
        let stdout = String::from_utf8_lossy(&r.stdout).to_string();
        assert!(r.status.success(), "{name}: {}", String::from_utf8_lossy(&r.stderr));
        assert!(stdout.contains("= 0 present + 3000 removed"), "{name}: not drained dry: {stdout}");
        let got = outputs(&out);
        assert_eq!(got.len(), want.len(), "{name}");
        for (a, b) in want.iter().zip(&got) {
            assert!(a.1 == b.1, "{name}: {} differs from one process's", a.0);
        }
        slowest.push(balance(&stdout));
    }
    assert!(slowest[0] > 1.1 && slowest[1] < slowest[0], "slowest ÷ mean without, with: {slowest:?}");
}
