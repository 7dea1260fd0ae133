//! The program's exit codes and messages, run as a user would.

use std::process::Command;

fn grainflow() -> Command {
    Command::new(env!("CARGO_BIN_EXE_grainflow"))
}

#[test]
fn bad_case_file_exits_2_with_a_message_and_no_panic() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = dir.path().join("case.toml");
    std::fs::write(&case, "version = 1\n[domain]\nmin = [0,0,0]\nmax = [1,1,1]\n[[phases]]\nname = \"a\"\ndiameter = -0.1\ndensity = 1000.0\n").expect("write");
    let out =
        grainflow().arg("run").arg(&case).arg("--out").arg(dir.path().join("out")).output().expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(
        stderr.contains("[[phases]] 'a'") && stderr.contains("diameter") && stderr.contains("-0.1"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn missing_case_file_exits_2() {
    let out = grainflow().args(["run", "no/such/case.toml"]).output().expect("runs");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read no/such/case.toml"));
}

#[test]
fn unknown_subcommand_exits_2() {
    let out = grainflow().arg("frobnicate").output().expect("runs");
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn examples_run_and_write_their_outputs() {
    // The bouncing ball falls 0.4 m before touching the floor: t = sqrt(2·0.4/g) = 0.2856 s,
    // so its first output rows must follow free fall exactly (Adams–Bashforth is exact for
    // constant acceleration): y(t) = 0.5 − g t²/2, checked through the potential energy.
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = grainflow()
        .args(["run", &format!("{root}/bouncing-ball/case.toml"), "--out"])
        .arg(dir.path())
        .output()
        .expect("runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let ts = std::fs::read_to_string(dir.path().join("timeseries.csv")).expect("time series");
    let rows: Vec<Vec<f64>> =
        ts.lines().skip(1).map(|l| l.split(',').map(|f| f.parse().expect("number")).collect()).collect();
    let m = 4.0 / 3.0 * std::f64::consts::PI * 0.1f64.powi(3) * 2600.0;
    let g = 9.80665;
    let mut checked = 0;
    for r in rows.iter().filter(|r| r[1] < 0.28) {
        let (t, potential) = (r[1], r[4]);
        let y = 0.5 - 0.5 * g * t * t;
        // Relative 1e-9: only rounding separates AB2 from the exact parabola.
        assert!((potential - m * g * y).abs() <= 1e-9 * m * g * 0.5, "t = {t}: {potential} vs {}", m * g * y);
        checked += 1;
    }
    assert!(checked > 20, "only {checked} free-fall rows");
}

#[test]
fn progress_is_plain_lines_off_a_terminal_and_silent_with_quiet() {
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/bouncing-ball/case.toml");
    let dir = tempfile::tempdir().expect("temp dir");
    let run = |quiet: bool| {
        let mut cmd = grainflow();
        cmd.args(["run", case, "--out"]).arg(dir.path().join(if quiet { "quiet" } else { "loud" }));
        if quiet {
            cmd.arg("--quiet");
        }
        let out = cmd.output().expect("runs");
        assert!(out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let loud = run(false);
    // Output captured by a pipe is not a terminal: one line per 10 % of the run (this run
    // takes well under the minute after which a line is due anyway); the last one, at the
    // end, with the run's speed and no time left.
    let lines: Vec<&str> = loud.lines().filter(|l| l.contains("%  step ")).collect();
    assert_eq!(lines.len(), 10, "{loud}");
    assert!(lines[9].trim_start().starts_with("100.0%  step 3051/3051"), "{loud}");
    assert!(lines[9].contains("particle-steps/s  ETA 0 s"), "{loud}");
    assert!(run(true).lines().all(|l| !l.contains("particle-steps/s")));
}

#[test]
fn example_writes_a_runnable_case_and_never_overwrites() {
    let dir = tempfile::tempdir().expect("temp dir");
    let target = dir.path().join("ball");
    let write =
        || grainflow().args(["example", "bouncing-ball", "--dir"]).arg(&target).output().expect("runs");
    assert!(write().status.success());
    let case = target.join("case.toml");
    std::fs::write(&case, std::fs::read_to_string(&case).expect("case") + "\n# my edit\n").expect("edit");
    let again = write();
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("exists already"));
    assert!(
        std::fs::read_to_string(&case).expect("case").ends_with("# my edit\n"),
        "the user's file was overwritten"
    );
    let run = grainflow()
        .arg("run")
        .arg(&case)
        .arg("--out")
        .arg(target.join("out"))
        .arg("-q")
        .output()
        .expect("runs");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let unknown = grainflow().args(["example", "no-such-example"]).output().expect("runs");
    assert_eq!(unknown.status.code(), Some(2));
}

/// SIGINT mid-run: the step finishes, a checkpoint is written, the exit code is 130; the
/// restarted run ends bit-identical to an uninterrupted one (time series and last snapshot).
#[test]
fn interrupted_run_restarts_bit_identically() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/settling-bed");
    let dir = tempfile::tempdir().expect("temp dir");
    let case = std::fs::read_to_string(format!("{root}/case.toml")).expect("example");
    let case = case
        .replace("particles.csv", &format!("{root}/particles.csv"))
        .replace("t_stop = 0.5", "t_stop = 0.3");
    let case_path = dir.path().join("case.toml");
    std::fs::write(&case_path, case).expect("write");
    let run = |out: &str, extra: &[&str]| {
        grainflow()
            .arg("run")
            .arg(&case_path)
            .arg("--out")
            .arg(dir.path().join(out))
            .arg("-q")
            .args(extra)
            .output()
            .expect("runs")
    };
    assert!(run("full", &[]).status.success());
    // Interrupt as soon as the first periodic checkpoint exists (the run is then mid-way).
    let child = grainflow()
        .arg("run")
        .arg(&case_path)
        .arg("--out")
        .arg(dir.path().join("part"))
        .args(["-q", "--checkpoint-every", "2000"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawns");
    let ckpt = dir.path().join("part/checkpoint.gfc");
    let t0 = std::time::Instant::now();
    while !ckpt.exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let killed = Command::new("kill").arg("-INT").arg(child.id().to_string()).status().expect("kill");
    assert!(killed.success());
    let out = child.wait_with_output().expect("waits");
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.code() == Some(0) {
        // The run ended before the signal arrived: nothing to restart, the test is moot.
        panic!("the run finished before it could be interrupted; make it longer: {stderr}");
    }
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("--restart"), "{stderr}");
    let info = std::fs::read_to_string(dir.path().join("part/run-info.toml")).expect("run info");
    assert!(info.contains("status = \"interrupted\"") && info.contains("case_sha256 = \""), "{info}");
    let resumed = run("part", &["--restart", ckpt.to_str().expect("utf-8 path")]);
    assert!(resumed.status.success(), "{}", String::from_utf8_lossy(&resumed.stderr));
    let read = |p: &str| std::fs::read(dir.path().join(p)).expect("file");
    assert_eq!(read("full/timeseries.csv"), read("part/timeseries.csv"), "time series differ after restart");
    let last = |d: &str| {
        let mut v: Vec<_> = std::fs::read_dir(dir.path().join(d).join("snapshots"))
            .expect("dir")
            .map(|e| e.expect("entry").file_name())
            .collect();
        v.sort();
        v.pop().expect("a snapshot")
    };
    let name = last("full");
    assert_eq!(name, last("part"));
    assert_eq!(
        read(&format!("full/snapshots/{}", name.to_string_lossy())),
        read(&format!("part/snapshots/{}", name.to_string_lossy()))
    );
}

/// A run that blows up (forced time step 30× the safe one) stops with a message naming the
/// particle, the step, the cause and a fix, exits 1 (never success), saves the last good
/// state, and that state restarts once the case is fixed.
#[test]
fn unstable_run_stops_with_a_diagnosis_and_saves_the_last_good_state() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/settling-bed");
    let dir = tempfile::tempdir().expect("temp dir");
    let good = std::fs::read_to_string(format!("{root}/case.toml"))
        .expect("example")
        .replace("particles.csv", &format!("{root}/particles.csv"))
        .replace("t_stop = 0.5", "t_stop = 0.05");
    let bad = good.replace("integrator = \"euler\"", "integrator = \"euler\"\ndt = 4e-4\nforce_dt = true");
    assert_ne!(good, bad);
    let (good_path, bad_path) = (dir.path().join("good.toml"), dir.path().join("bad.toml"));
    std::fs::write(&good_path, good).expect("write");
    std::fs::write(&bad_path, bad).expect("write");
    let out = dir.path().join("out");
    let run = grainflow().arg("run").arg(&bad_path).arg("--out").arg(&out).arg("-q").output().expect("runs");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    for want in ["step ", "particle ", "Likely cause", "Fix:", "checkpoint-last-good.gfc"] {
        assert!(stderr.contains(want), "missing '{want}': {stderr}");
    }
    let info = std::fs::read_to_string(out.join("run-info.toml")).expect("run info");
    assert!(info.contains("status = \"failed: numerical health check\""), "{info}");
    let saved = out.join("checkpoint-last-good.gfc");
    let resumed = grainflow()
        .arg("run")
        .arg(&good_path)
        .arg("--out")
        .arg(dir.path().join("resumed"))
        .args(["-q", "--accept-changed-case", "--restart"])
        .arg(&saved)
        .output()
        .expect("runs");
    assert!(resumed.status.success(), "{}", String::from_utf8_lossy(&resumed.stderr));
}

/// The same case run twice gives byte-identical outputs.
#[test]
fn runs_are_reproducible_to_the_byte() {
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/bouncing-ball/case.toml");
    let dir = tempfile::tempdir().expect("temp dir");
    // On 1 and on 2 threads: the same bytes, and run-info.toml records the threads used.
    for (out, threads) in [("a", "1"), ("b", "2")] {
        let r = grainflow()
            .args(["run", case, "-q", "-j", threads, "--out"])
            .arg(dir.path().join(out))
            .output()
            .expect("runs");
        assert!(r.status.success());
        let info = std::fs::read_to_string(dir.path().join(out).join("run-info.toml")).expect("run info");
        assert!(
            info.contains(&format!("threads = {threads}\n"))
                && info.contains("grainflow_version")
                && info.contains("case_sha256 = \"")
                && info.contains("status = \"completed\""),
            "{info}"
        );
    }
    let read = |p: &str| std::fs::read(dir.path().join(p)).expect("file");
    assert_eq!(read("a/timeseries.csv"), read("b/timeseries.csv"));
}

/// Issue 38, item 10: particles an insertion could not place are reported while the run goes
/// (a warning naming the insertion) and in the summary (asked, inserted, not placed). The box
/// region, 7 × 2.4 × 2.4 mm, holds at most three 2 mm beads of the 100 asked.
#[test]
fn unplaced_particles_are_warned_of_and_summed_up() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = dir.path().join("case.toml");
    std::fs::write(
        &case,
        "version = 1\n[domain]\nmin = [0.0, 0.0, 0.0]\nmax = [0.04, 0.04, 0.04]\n\
         [physics]\ngravity = [0.0, 0.0, 0.0]\n\
         [[phases]]\nname = \"glass\"\ndiameter = 0.002\ndensity = 2500.0\n\
         [contact.particle]\nkn = 1.0e3\nen = 0.9\n[contact.wall]\nkn = 1.0e3\nen = 0.9\n\
         [time]\nt_stop = 0.001\ndt = 1.0e-5\n\
         [[insertions]]\nname = \"crowd\"\ncount = 100\n\
         [insertions.region]\nkind = \"box\"\nmin = [0.01, 0.01, 0.01]\nmax = [0.017, 0.0124, 0.0124]\n\
         [[insertions.phases]]\nphase = \"glass\"\n",
    )
    .expect("write");
    let out = grainflow()
        .arg("run")
        .arg(&case)
        .arg("--out")
        .arg(dir.path().join("out"))
        .arg("--quiet")
        .output()
        .expect("runs");
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let line = stdout.lines().find(|l| l.starts_with("insertion 'crowd': 100 asked, ")).expect(&stdout);
    // "… N inserted (…), M not placed" with N + M = 100 and N at most 3.
    let count = |what: &str| -> u64 {
        let before = line.split(what).next().expect("field");
        before.trim_end().rsplit([' ', ',']).next().expect("number").parse().expect("a count")
    };
    let (inserted, missed) = (count(" inserted"), count(" not placed"));
    assert_eq!(inserted + missed, 100, "{line}");
    assert!(inserted <= 3, "{line}");
    assert!(stderr.contains("warning: insertion 'crowd' at t = 0.000000e0 s:"), "{stderr}");
    assert!(stdout.contains("books: 0 at the start + "), "{stdout}");
}
