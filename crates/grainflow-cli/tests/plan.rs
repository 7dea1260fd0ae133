//! `grainflow check`, `--set`, `--memory-limit` and signals during the set-up, run as a user
//! would (grainflow issue 38, items 16, 17, 20 and 25).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn grainflow() -> Command {
    Command::new(env!("CARGO_BIN_EXE_grainflow"))
}

/// The hostile corpus's base case: one glass bead in a 0.1 m box, 0.01 s (778 steps of
/// MFIX's rule).
fn base_case() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/hostile/case.toml"))
        .expect("base case")
}

fn pour_bed() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/pour-bed/case.toml")).to_path_buf()
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p
}

fn text(o: &Output) -> (String, String) {
    (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// The number after `prefix` in `text`'s first line holding it (up to a space or comma).
fn number_after(text: &str, prefix: &str) -> f64 {
    let at = text.find(prefix).unwrap_or_else(|| panic!("no '{prefix}' in:\n{text}")) + prefix.len();
    let rest = &text[at..];
    let end = rest.find([' ', ',', ')']).unwrap_or(rest.len());
    rest[..end].parse().unwrap_or_else(|_| panic!("'{}' after '{prefix}' is no number", &rest[..end]))
}

/// A run with `--set time.t_stop=0.002` is the run of the file that says t_stop = 0.002: the
/// same time series to the byte, and the same step count (0.002 s of MFIX's step).
#[test]
fn set_runs_the_case_as_if_the_file_said_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = write(dir.path(), "case.toml", &base_case());
    let edited =
        write(dir.path(), "edited.toml", &base_case().replacen("t_stop = 0.01", "t_stop = 0.002", 1));
    let run = |case: &Path, out: &str, set: &[&str]| {
        let mut c = grainflow();
        c.arg("run").arg(case).arg("--out").arg(dir.path().join(out)).args(["-q", "-j", "1"]);
        for s in set {
            c.args(["--set", s]);
        }
        let o = c.output().expect("runs");
        assert!(o.status.success(), "{:?}", text(&o));
        std::fs::read(dir.path().join(out).join("timeseries.csv")).expect("time series")
    };
    let with_set = run(&case, "set", &["time.t_stop=0.002"]);
    let with_file = run(&edited, "file", &[]);
    assert_eq!(with_set, with_file, "--set and the edited file must give the same time series");
    let full = run(&case, "full", &[]);
    assert!(with_set.len() < full.len(), "the shortened run must have fewer rows");
    // `check` reports the shortened run's steps: ceil(0.002/dt), dt from MFIX's rule.
    let o = grainflow().arg("check").arg(&case).args(["--set", "time.t_stop=0.002"]).output().expect("runs");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    let dt = number_after(&out, "steps of ");
    let steps: u64 = out
        .lines()
        .find_map(|l| l.split_once(" steps of ").map(|(n, _)| n.parse().expect("steps")))
        .expect("the steps line");
    assert_eq!(steps, (0.002 / dt).ceil() as u64, "{out}");
}

/// Keys by dotted path: an array-of-tables entry by position or by name, a phase of an
/// insertion by its phase, a component of a vector; each shows in the plan as set.
#[test]
fn set_reaches_entries_by_position_and_by_name() {
    let check = |sets: &[&str]| {
        let mut c = grainflow();
        c.arg("check").arg(pour_bed());
        for s in sets {
            c.args(["--set", s]);
        }
        let o = c.output().expect("runs");
        let (out, err) = text(&o);
        assert!(o.status.success(), "{sets:?}: {err}");
        out
    };
    // 0.8 s of pouring at 2000 beads/s in 0.02 s batches, mass-limited at 0.0125 kg: the same
    // insertion named by its position and by its name.
    for key in ["insertions.0.rate", "insertions.pour.rate"] {
        let out = check(&[&format!("{key}=2000")]);
        assert!(out.contains("insertion 'pour': at 2000 particles/s"), "{key}: {out}");
    }
    // The steel's fraction by its phase, the glass's by position: still 1 in all.
    let out = check(&["insertions.pour.phases.steel.fraction=0.5", "insertions.pour.phases.0.fraction=0.5"]);
    assert!(out.contains("insertion 'pour'"), "{out}");
    // A new table: VTK frames every 0.1 s of the 0.8 s run are 9 (t = 0, 0.1, …, 0.8).
    let out = check(&["output.vtk_interval=0.1"]);
    assert!(out.contains(", 9 VTK frames"), "{out}");
    // A bare word is a string: "euler" is a valid integrator.
    check(&["time.integrator=euler"]);
}

/// A bad `--set` gives a message naming the key and the value, exit 2, no panic, nothing run.
#[test]
fn bad_sets_are_refused_naming_key_and_value() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = write(dir.path(), "case.toml", &base_case());
    let deck = write(dir.path(), "mfix.dat", "RUN_NAME = 'T'\n");
    let cases: &[(&Path, &str, &[&str])] = &[
        (&case, "time.t_sotp=0.1", &["t_sotp", "did you mean `t_stop`?"]),
        (&case, "time.t_stop=-1", &["[time]", "`t_stop` = -1 is invalid"]),
        (&case, "time.t_stop=\"soon\"", &["time.t_stop", "expected f64"]),
        (&case, "time.t_stop=0.1s", &["`0.1s` is not a TOML value"]),
        (&case, "time.t_stop", &["give KEY=VALUE"]),
        (&case, "time..t_stop=1", &["is not a key path"]),
        (&case, "phases.3.density=1000", &["`phases` has 1 entry (0 to 0), not an entry 3"]),
        (&case, "phases.sand.density=1000", &["no entry of `phases` is named `sand`", "`glass`"]),
        (&case, "insertions.0.count=5", &["the case has no `insertions` entries"]),
        (&case, "time.t_stop.x=1", &["`time.t_stop` is a value (float)"]),
        (&case, "phases.0=1", &["`phases.0` is a table"]),
        (&case, "phases.glass.diameter=-0.004", &["[[phases]] 'glass'", "`diameter` = -0.004"]),
        (&deck, "time.t_stop=0.1", &["--set applies to TOML case files", "TSTOP=0.1"]),
    ];
    for (file, set, want) in cases {
        for cmd in ["check", "run"] {
            let mut c = grainflow();
            c.arg(cmd).arg(file).args(["--set", set]);
            if cmd == "run" {
                c.arg("--out").arg(dir.path().join("out"));
            }
            let o = c.output().expect("runs");
            let (_, err) = text(&o);
            assert_eq!(o.status.code(), Some(2), "{cmd} --set {set}: {err}");
            for w in *want {
                assert!(err.contains(w), "{cmd} --set {set}: message lacks '{w}': {err}");
            }
            assert!(!err.contains("panicked"), "{err}");
        }
    }
    assert!(!dir.path().join("out").exists(), "a refused run wrote its folder");
}

/// `check` prints the plan without running or writing anything, and its figures are the
/// run's: the steps, the time-series rows and snapshots, and the particles the insertion
/// brings.
#[test]
fn check_plans_what_the_run_then_does() {
    let dir = tempfile::tempdir().expect("temp dir");
    let o = grainflow()
        .current_dir(dir.path())
        .arg("check")
        .arg(pour_bed())
        .args(["--set", "time.t_stop=0.6"])
        .output()
        .expect("runs");
    let (plan, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(plan.contains("nothing was run"), "{plan}");
    assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 0, "check wrote something");
    let steps: u64 = plan
        .lines()
        .find_map(|l| l.split_once(" steps of ").map(|(n, _)| n.parse().expect("steps")))
        .expect("the steps line");
    let rows = number_after(&plan, "outputs: ") as usize;
    let snapshots = number_after(&plan, "steps), ") as usize;
    let planned = number_after(&plan, "in the run, about ");
    let out = dir.path().join("out");
    let o = grainflow()
        .arg("run")
        .arg(pour_bed())
        .args(["--set", "time.t_stop=0.6", "--set", "output.vtk_interval=1.0", "-q", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    let (summary, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(summary.contains(&format!(", {steps} steps of ")), "check planned {steps} steps:\n{summary}");
    let ts = std::fs::read_to_string(out.join("timeseries.csv")).expect("time series");
    assert_eq!(ts.lines().count() - 1, rows, "time-series rows");
    assert_eq!(std::fs::read_dir(out.join("snapshots")).expect("snapshots").count(), snapshots);
    // Nothing leaves the box: the particles at the end are all the insertion brought. It stops
    // at 0.0125 kg, drawn from the mixture: the count is the mass over the mean mass, within
    // the spread of a sum of ~1100 draws (the masses' coefficient of variation is below 0.5,
    // so one standard deviation is under 0.5/√1100 = 1.5 %; 5 % is over three) and the one
    // particle that takes the total past the mass.
    let end = number_after(&summary, " at the start, ");
    assert!((end - planned).abs() <= 0.05 * planned + 1.0, "planned {planned}, inserted {end}");
}

/// The output of `c`, killed after 20 s (a guard against the hangs these tests are about).
fn guarded(mut c: Command) -> Output {
    let mut child = c.spawn().expect("starts");
    let start = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if start.elapsed() > Duration::from_secs(20) {
            let _ = child.kill();
            let o = child.wait_with_output().expect("output");
            panic!("still running after 20 s (killed): {:?}", text(&o));
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.wait_with_output().expect("output")
}

/// Item 16: an insertion's `every` far below the step, and an MFIX inflow of 10⁹ kg/s, hung
/// the run (killed at 65 s); both are refused before the run starts, naming the key.
#[test]
fn batches_faster_than_the_steps_and_absurd_inflows_are_refused_at_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let pour = std::fs::read_to_string(pour_bed()).expect("pour bed");
    let fast = write(dir.path(), "fast.toml", &pour.replacen("every = 0.02 ", "every = 1e-12 ", 1));
    let deck = write(
        dir.path(),
        "mfix.dat",
        "RUN_NAME = 'T'\nUNITS = 'SI'\nRUN_TYPE = 'NEW'\nTSTOP = 1.0\nCOORDINATES = 'CARTESIAN'\n\
         IMAX = 4  JMAX = 4  KMAX = 4\nRO_G0 = 0.0\nKN = 1.0e4\nKN_W = 1.0e4\nMEW = 0.3\nMEW_W = 0.3\n\
         MMAX = 1\nSOLIDS_MODEL(1) = 'DEM'\nD_P0(1) = 0.1\nRO_S0(1) = 1000.0\nDES_EN_INPUT(1) = 0.9\n\
         DES_EN_WALL_INPUT(1) = 0.9\nXLENGTH = 1.0  YLENGTH = 2.0  ZLENGTH = 1.0\nPARTICLES = 0\nGRAVITY = 9.81\n\
         BC_TYPE(1) = 'MI'\nBC_X_W(1) = 0.2  BC_X_E(1) = 0.8  BC_Y_S(1) = 2.0  BC_Y_N(1) = 2.0  BC_Z_B(1) = 0.2  BC_Z_T(1) = 0.8\n\
         BC_EP_S(1,1) = 0.2\nBC_MASSFLOW_S(1,1) = 1e9\n",
    );
    let cases: [(&Path, &[&str]); 2] = [
        (&fast, &["[[insertions]] 'pour'", "`every` = 1e-12 is invalid", "give every >= dt"]),
        // 10⁹ kg/s of 0.1 m beads of 1000 kg/m³ (0.524 kg) for 1 s: 1.9e9 beads at least.
        (&deck, &["line 24", "`BC_MASSFLOW_S(1,1)` = 1e9", "1.9099e9 particles at least", "of memory"]),
    ];
    for (file, want) in cases {
        for cmd in ["check", "run"] {
            let started = Instant::now();
            let mut c = grainflow();
            c.arg(cmd).arg(file).stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped());
            if cmd == "run" {
                c.arg("--out").arg(dir.path().join("out"));
            }
            let o = guarded(c);
            let (_, err) = text(&o);
            assert_eq!(o.status.code(), Some(2), "{cmd} {}: {err}", file.display());
            for w in want {
                assert!(err.contains(w), "{cmd}: message lacks '{w}': {err}");
            }
            // A refusal, not a run: well under a second on any machine.
            assert!(started.elapsed() < Duration::from_secs(10), "{cmd} took {:?}", started.elapsed());
        }
    }
    assert!(!dir.path().join("out").exists());
}

/// Runs `args` under a virtual-memory cap of `cap_kib` (as the hostile corpus does).
fn capped(cap_kib: u64, args: &[&str]) -> Output {
    let mut line = format!("ulimit -v {cap_kib} && exec '{}'", env!("CARGO_BIN_EXE_grainflow"));
    for a in args {
        line.push_str(&format!(" '{a}'"));
    }
    Command::new("sh").args(["-c", &line]).output().expect("sh runs")
}

/// Item 17: a run whose estimate exceeds the limit is refused with the figures, before the
/// allocation: under a 512 MiB address-space cap, 2·10⁷ beads inserted at once (about 10 GiB)
/// and an MFIX deck seeding 1.9·10⁷ sites are refused with exit 2 and the figures, not killed
/// by a failed allocation (which aborts with 134). The limit given with --memory-limit is
/// the one held to; raised, the same case plans.
#[test]
fn runs_past_the_memory_limit_are_refused_before_allocating() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = base_case().replacen("max = [0.1, 0.1, 0.1]", "max = [2.0, 2.0, 2.0]", 1).replacen(
        "[[particles.list]]",
        "[[particles.list]]\nid = 1",
        1,
    ) + "[[insertions]]\nname = \"lots\"\ncount = 20000000\n[insertions.region]\nkind = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [2.0, 2.0, 2.0]\n[[insertions.phases]]\nphase = \"glass\"\n";
    let case = write(dir.path(), "case.toml", &case);
    let out = dir.path().join("out");
    let (case_s, out_s) = (case.to_str().expect("utf-8"), out.to_str().expect("utf-8"));
    for cmd in ["check", "run"] {
        let args: &[&str] = if cmd == "run" { &["--out", out_s] } else { &[] };
        let o = capped(524_288, &[&[cmd, case_s, "--memory-limit", "400MB"], args].concat());
        let (_, err) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{cmd}: {err}");
        // 2e7 beads at 544 bytes each (Euler: state 152, neighbour list 88, 7 pairs of 43.5)
        // plus the 64 MiB base: 1.0947e10 bytes, 10.20 GiB.
        for w in [
            "[[insertions]] 'lots'",
            "`count` = 20000000",
            "2.0000e7 particles",
            "544 bytes each",
            "10.20 GiB",
            "381.5 MiB (--memory-limit)",
        ] {
            assert!(err.contains(w), "{cmd}: message lacks '{w}': {err}");
        }
    }
    assert!(!out.exists(), "a refused run wrote its folder");
    // Raised, the limit lets `check` plan it (without allocating anything).
    let o = capped(524_288, &["check", case_s, "--memory-limit", "20GB"]);
    assert!(o.status.success(), "{:?}", text(&o));
    assert!(text(&o).0.contains("memory: about 10.20 GiB at the peak"), "{:?}", text(&o));
    // An MFIX deck's lattice: ε_s = 0.5 of a 1 m³ region in 4 mm beads: ⌊0.5/(π/6·0.004³)⌋ =
    // 14 920 775 sites.
    let deck = write(
        dir.path(),
        "mfix.dat",
        "RUN_NAME = 'T'\nUNITS = 'SI'\nRUN_TYPE = 'NEW'\nTSTOP = 0.01\nCOORDINATES = 'CARTESIAN'\n\
         IMAX = 4  JMAX = 4  KMAX = 4\nRO_G0 = 0.0\nKN = 1.0e4\nKN_W = 1.0e4\nMEW = 0.3\nMEW_W = 0.3\n\
         MMAX = 1\nSOLIDS_MODEL(1) = 'DEM'\nD_P0(1) = 0.004\nRO_S0(1) = 1000.0\nDES_EN_INPUT(1) = 0.9\n\
         DES_EN_WALL_INPUT(1) = 0.9\nXLENGTH = 1.0  YLENGTH = 1.0  ZLENGTH = 1.0\nGENER_PART_CONFIG = .T.\n\
         IC_X_W(1) = 0.0  IC_X_E(1) = 1.0  IC_Y_S(1) = 0.0  IC_Y_N(1) = 1.0  IC_Z_B(1) = 0.0  IC_Z_T(1) = 1.0\n\
         IC_EP_S(1,1) = 0.5\n",
    );
    let o = capped(524_288, &["check", deck.to_str().expect("utf-8"), "--memory-limit", "1GB"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    for w in ["`IC_EP_S(1,1)` = 0.5", "seeding 1.4920775e7 particles", "more than the limit 953.7 MiB"] {
        assert!(err.contains(w), "message lacks '{w}': {err}");
    }
}

/// Item 25: SIGTERM during a long set-up (2.5·10⁶ beads placed at the start: several seconds
/// of placement) ends the program within a few seconds, with a message and exit 130, and
/// nothing written. Before, the signal waited for the set-up to end (and the hangs of item
/// 16 could not be stopped at all).
#[test]
fn sigterm_ends_a_long_set_up_at_once_writing_nothing() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = base_case().replacen("max = [0.1, 0.1, 0.1]", "max = [1.0, 1.0, 1.0]", 1).replacen(
        "[[particles.list]]",
        "[[particles.list]]\nid = 1",
        1,
    ) + "[output]\nsnapshots = false\n[[insertions]]\nname = \"lots\"\ncount = 2500000\n[insertions.region]\nkind = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]\n[[insertions.phases]]\nphase = \"glass\"\n";
    let case = write(dir.path(), "case.toml", &case);
    let out = dir.path().join("out");
    let mut child = grainflow()
        .arg("run")
        .arg(&case)
        .arg("--out")
        .arg(&out)
        .args(["-q", "-j", "1"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starts");
    // Inside the placement (which takes about 7 s on the 2-core development machine).
    std::thread::sleep(Duration::from_millis(1500));
    assert!(child.try_wait().expect("wait").is_none(), "the set-up ended before the signal");
    let sent = Instant::now();
    let kill = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().expect("kill");
    assert!(kill.success());
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if sent.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("still running 30 s after SIGTERM");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let waited = sent.elapsed();
    let o = child.wait_with_output().expect("output");
    let (_, err) = text(&o);
    // A bound, not a timing: the handler ends the process as soon as it runs (milliseconds).
    assert!(waited < Duration::from_secs(3), "ended {waited:?} after SIGTERM: {err}");
    assert_eq!(status.code(), Some(130), "{err}");
    assert!(
        err.contains("interrupted during the set-up, before the run started: nothing was written"),
        "{err}"
    );
    assert!(!out.exists(), "the interrupted set-up wrote {}", out.display());
}
