//! The output folder: outputs survive a crash, a restart continues exactly its own run, two
//! runs never share a folder, and an earlier run's results are never destroyed by accident.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn grainflow() -> Command {
    Command::new(env!("CARGO_BIN_EXE_grainflow"))
}

/// The settling-bed example (486 beads, snapshots and VTK frames every 0.05 s) in `dir`, with
/// `t_stop` changed.
fn settling_bed(dir: &Path, t_stop: &str) -> PathBuf {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/settling-bed");
    let case = std::fs::read_to_string(format!("{root}/case.toml"))
        .expect("example")
        .replace("particles.csv", &format!("{root}/particles.csv"))
        .replace("t_stop = 0.5", &format!("t_stop = {t_stop}"));
    assert!(case.contains(&format!("t_stop = {t_stop}")) && case.contains("vtk_interval"), "example changed");
    let path = dir.join(format!("case-{t_stop}.toml"));
    std::fs::write(&path, case).expect("write case");
    path
}

fn run(args: &[&dyn AsRef<std::ffi::OsStr>]) -> Output {
    let mut cmd = grainflow();
    cmd.arg("run");
    for a in args {
        cmd.arg(a);
    }
    cmd.arg("-q").output().expect("runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Every file below `dir` (relative path → bytes), but for the ones that record when and how
/// the run went (run-info.toml, the manifest, the lock, checkpoints).
fn outputs(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("folder") {
            let path = e.expect("entry").path();
            let rel = path.strip_prefix(dir).expect("below").to_path_buf();
            let name = rel.to_string_lossy();
            if path.is_dir() {
                stack.push(path);
            } else if !["run-info.toml", "manifest.toml", ".grainflow.lock"].contains(&name.as_ref())
                && !name.ends_with(".gfc")
            {
                files.insert(rel, std::fs::read(&path).expect("read"));
            }
        }
    }
    files
}

/// The paths the manifest lists.
fn manifest(dir: &Path) -> Vec<PathBuf> {
    let text = std::fs::read_to_string(dir.join("manifest.toml")).expect("manifest");
    let value: toml::Value = text.parse().expect("the manifest is TOML");
    value["file"]
        .as_array()
        .expect("[[file]] entries")
        .iter()
        .map(|f| PathBuf::from(f["path"].as_str().expect("path")))
        .collect()
}

/// A small deterministic generator of delays (the failure message names the seed).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self, lo: u64, hi: u64) -> u64 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        lo + (self.0 >> 33) % (hi - lo)
    }
}

/// SIGKILL at random moments, three times over: after each kill the time series holds the
/// uninterrupted run's rows up to where it stopped (none lost but the row being written, none
/// changed) and the manifest names every file in the folder; each restart continues from the
/// last checkpoint in the checkpoint's own folder (no --out), on 2 threads where the reference
/// ran on 1; the final outputs equal the uninterrupted run's byte for byte.
#[test]
fn runs_killed_at_random_steps_restart_to_the_same_bytes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = settling_bed(dir.path(), "0.5");
    let full = dir.path().join("full");
    let r = run(&[&case, &"--out", &full, &"-j", &"1"]);
    assert!(r.status.success(), "{}", stderr(&r));
    let reference = outputs(&full);
    let reference_rows = String::from_utf8(reference[Path::new("timeseries.csv")].clone()).expect("utf-8");
    let part = dir.path().join("part");
    let ckpt = part.join("checkpoint.gfc");
    let seed = 20_261_201;
    let mut rng = Lcg(seed);
    let mut kills = 0;
    for round in 0..3 {
        let mut cmd = grainflow();
        cmd.arg("run").arg(&case).args(["-q", "-j", "2", "--checkpoint-every", "1500"]);
        if round == 0 {
            cmd.arg("--out").arg(&part);
        } else {
            cmd.arg("--restart").arg(&ckpt);
        }
        let mut child = cmd.stdout(Stdio::null()).stderr(Stdio::null()).spawn().expect("spawns");
        // The first round waits for its first checkpoint, so that there is one to restart from.
        let t0 = Instant::now();
        while round == 0 && !ckpt.exists() && t0.elapsed() < Duration::from_secs(60) {
            std::thread::sleep(Duration::from_millis(2));
        }
        std::thread::sleep(Duration::from_millis(rng.next(50, 600)));
        child.kill().expect("SIGKILL");
        let status = child.wait().expect("waits");
        if status.success() {
            break; // it finished first: the last round's outputs are checked below
        }
        kills += 1;
        let rows = std::fs::read_to_string(part.join("timeseries.csv")).expect("the time series survives");
        let whole = rows.rfind('\n').map_or("", |k| &rows[..=k]);
        assert!(
            reference_rows.starts_with(whole) && whole.lines().count() >= 2,
            "round {round} (seed {seed}): the rows written before the kill are not the uninterrupted run's:\n{whole}"
        );
        // Every file but the temporary ones of atomic writes (removed by the next run).
        let listed = manifest(&part);
        for f in outputs(&part).keys().filter(|f| !f.to_string_lossy().contains(".partial-")) {
            assert!(listed.contains(f), "round {round}: {} is not in the manifest", f.display());
        }
    }
    assert!(kills >= 2, "only {kills} of 3 runs were killed mid-way (seed {seed}): make the case longer");
    let last = run(&[&case, &"--restart", &ckpt]);
    assert!(last.status.success(), "{}", stderr(&last));
    let resumed = outputs(&part);
    assert_eq!(
        reference.keys().collect::<Vec<_>>(),
        resumed.keys().collect::<Vec<_>>(),
        "the two folders hold different files"
    );
    for (name, bytes) in &reference {
        assert!(
            bytes == &resumed[name],
            "{} differs from the uninterrupted run's (seed {seed})",
            name.display()
        );
    }
    let info = std::fs::read_to_string(part.join("run-info.toml")).expect("run info");
    assert!(info.contains("status = \"completed\"") && info.contains("threads = 2\n"), "{info}");
}

/// A second run into a folder that a run is writing into is refused with exit 2, naming the
/// first run, and changes nothing there.
#[test]
fn a_second_run_into_a_busy_folder_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = settling_bed(dir.path(), "2.0");
    let out = dir.path().join("out");
    let mut first = grainflow()
        .arg("run")
        .arg(&case)
        .arg("--out")
        .arg(&out)
        .args(["-q", "-j", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawns");
    let info = out.join("run-info.toml");
    let t0 = Instant::now();
    while !info.exists() && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(2));
    }
    let second = run(&[&case, &"--out", &out, &"--overwrite"]);
    let still_running = first.try_wait().expect("status").is_none();
    first.kill().expect("kill");
    let _ = first.wait();
    assert!(still_running, "the first run ended before the second started: make it longer");
    assert_eq!(second.status.code(), Some(2), "{}", stderr(&second));
    let msg = stderr(&second);
    assert!(
        msg.contains("in use by another grainflow run") && msg.contains(&format!("pid {}", first.id())),
        "{msg}"
    );
}

/// A finished run's folder is kept: a second run into it, or a bad case, is refused with exit
/// 2 and changes no file; `--overwrite` replaces only grainflow's files.
#[test]
fn a_finished_run_is_never_overwritten_by_accident() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = settling_bed(dir.path(), "0.1");
    let out = dir.path().join("out");
    assert!(run(&[&case, &"--out", &out]).status.success());
    std::fs::write(out.join("notes.txt"), "my notes").expect("write");
    let before = outputs(&out);
    let again = run(&[&case, &"--out", &out]);
    assert_eq!(again.status.code(), Some(2), "{}", stderr(&again));
    assert!(
        stderr(&again).contains("holds the results of an earlier run")
            && stderr(&again).contains("--overwrite")
    );
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, std::fs::read_to_string(&case).unwrap().replace("kn = 1000.0", "kn = -1.0"))
        .unwrap();
    assert_eq!(run(&[&bad, &"--out", &out, &"--overwrite"]).status.code(), Some(2));
    assert!(before == outputs(&out), "a refused run changed the folder");
    // A shorter run over it leaves what it leaves in an empty folder, and the user's file.
    let short = settling_bed(dir.path(), "0.05");
    let over = run(&[&short, &"--out", &out, &"--overwrite"]);
    assert!(over.status.success(), "{}", stderr(&over));
    let fresh = dir.path().join("fresh");
    assert!(run(&[&short, &"--out", &fresh]).status.success());
    let mut after = outputs(&out);
    assert_eq!(after.remove(Path::new("notes.txt")).as_deref(), Some(&b"my notes"[..]));
    assert!(after == outputs(&fresh), "files of the earlier run left: {:?}", after.keys());
    let listed = manifest(&out);
    assert!(after.keys().all(|f| listed.contains(f)), "{listed:?}");
}

/// A restart into a folder that holds another run's results (another case's, copied there)
/// is refused: their rows are never spliced in front of this run's.
#[test]
fn a_restart_never_splices_another_runs_rows() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = settling_bed(dir.path(), "0.1");
    let other = settling_bed(dir.path(), "0.05");
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    assert!(run(&[&case, &"--out", &a, &"--checkpoint-every", &"2000"]).status.success());
    assert!(run(&[&other, &"--out", &b]).status.success());
    let before = outputs(&b);
    let r = run(&[&case, &"--restart", &a.join("checkpoint.gfc"), &"--out", &b]);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    assert!(stderr(&r).contains("belongs to another run"), "{}", stderr(&r));
    assert!(before == outputs(&b));
    // Into an empty folder the series starts at the checkpoint, with the uninterrupted run's rows.
    let c = dir.path().join("c");
    let r = run(&[&case, &"--restart", &a.join("checkpoint.gfc"), &"--out", &c]);
    assert!(r.status.success(), "{}", stderr(&r));
    let rows = std::fs::read_to_string(c.join("timeseries.csv")).unwrap();
    let full = std::fs::read_to_string(a.join("timeseries.csv")).unwrap();
    assert!(rows.lines().count() >= 2 && rows.lines().skip(1).all(|l| full.contains(l)), "{rows}");
    assert!(rows.lines().nth(1).unwrap().split(',').next().unwrap().parse::<u64>().unwrap() >= 6000);
}

/// `--accept-changed-case` accepts changed settings, not other particles.
#[test]
fn a_changed_case_must_keep_its_particles() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = settling_bed(dir.path(), "0.1");
    let out = dir.path().join("out");
    assert!(run(&[&case, &"--out", &out, &"--checkpoint-every", &"3000"]).status.success());
    let text = std::fs::read_to_string(&case).unwrap();
    let four = dir.path().join("four.toml");
    let list = "[particles]\n[[particles.list]]\nphase = \"glass\"\nposition = [0.01, 0.01, 0.01]\n";
    let cut = text.find("[particles]").expect("particles table");
    std::fs::write(&four, format!("{}{list}", &text[..cut])).unwrap();
    let r = run(&[
        &four,
        &"--restart",
        &out.join("checkpoint.gfc"),
        &"--accept-changed-case",
        &"--out",
        &dir.path().join("x"),
    ]);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    assert!(stderr(&r).contains("the checkpoint holds 486 particles and the case 1"), "{}", stderr(&r));
}

/// A run whose planned output no disk holds is refused before it starts.
#[test]
fn absurd_output_volumes_are_refused_before_the_run() {
    let dir = tempfile::tempdir().expect("temp dir");
    let text = std::fs::read_to_string(settling_bed(dir.path(), "1000.0")).unwrap();
    let case = dir.path().join("flood.toml");
    std::fs::write(&case, text.replace("vtk_interval = 0.05", "vtk_interval = 1e-9")).unwrap();
    let out = dir.path().join("out");
    let r = run(&[&case, &"--out", &out]);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    assert!(stderr(&r).contains("the run would write about"), "{}", stderr(&r));
    assert!(!out.exists(), "a refused run created its folder");
}

/// The hopper-fill-discharge example in `dir`, shortened (600 beads; the gate opens at 0.1 s;
/// 0.5 s in all): beads are inserted up to step 816 and leave through the outlet from about
/// step 4 000 to the end (10 214 steps).
fn short_hopper(dir: &Path) -> PathBuf {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/hopper-fill-discharge");
    let mut case = std::fs::read_to_string(format!("{root}/case.toml")).expect("example");
    for (from, to) in [
        ("t_stop = 3.5 ", "t_stop = 0.5 "),
        ("count = 3000 ", "count = 600 "),
        ("start = 0.6 ", "start = 0.1 "),
        ("stop = 0.7 ", "stop = 0.2 "),
        ("\"hopper.obj\"", &format!("\"{root}/hopper.obj\"")),
        ("\"gate.obj\"", &format!("\"{root}/gate.obj\"")),
    ] {
        assert!(case.contains(from), "example changed: {from}");
        case = case.replacen(from, to, 1);
    }
    let path = dir.join("hopper.toml");
    std::fs::write(&path, case).expect("write case");
    path
}

/// SIGTERM and SIGKILL at random moments while the hopper fills and while it discharges, each
/// run continued from the last checkpoint: the final files equal the uninterrupted run's byte
/// for byte, and the books close in the time series (Σ inserted − Σ removed = the beads of the
/// last snapshot, an exact count; none at the start).
#[test]
fn runs_killed_during_insertion_and_discharge_restart_to_the_same_bytes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = short_hopper(dir.path());
    let full = dir.path().join("full");
    let r = run(&[&case, &"--out", &full, &"-j", &"1"]);
    assert!(r.status.success(), "{}", stderr(&r));
    let reference = outputs(&full);
    let part = dir.path().join("part");
    let ckpt = part.join("checkpoint.gfc");
    let seed = 20_261_203;
    let mut rng = Lcg(seed);
    let mut stops = Vec::new();
    for round in 0..6 {
        let mut cmd = grainflow();
        cmd.arg("run").arg(&case).args(["-q", "-j", "1", "--checkpoint-every", "500"]);
        if round == 0 {
            cmd.arg("--out").arg(&part);
        } else {
            cmd.arg("--restart").arg(&ckpt);
        }
        let mut child = cmd.stdout(Stdio::null()).stderr(Stdio::null()).spawn().expect("spawns");
        let t0 = Instant::now();
        while round == 0 && !ckpt.exists() && t0.elapsed() < Duration::from_secs(60) {
            std::thread::sleep(Duration::from_millis(1));
        }
        std::thread::sleep(Duration::from_millis(rng.next(20, 150)));
        let signal = if round % 2 == 0 { "-TERM" } else { "-KILL" };
        let sent = Command::new("kill").arg(signal).arg(child.id().to_string()).status().expect("kill");
        let status = child.wait().expect("waits");
        if sent.success() && !status.success() {
            stops.push(signal);
        }
    }
    assert!(stops.len() >= 3, "only {stops:?} of 6 runs were stopped mid-way (seed {seed})");
    let last = run(&[&case, &"--restart", &ckpt]);
    assert!(last.status.success(), "{}", stderr(&last));
    let resumed = outputs(&part);
    let (a, b): (Vec<_>, Vec<_>) = (reference.keys().collect(), resumed.keys().collect());
    let only = |x: &[&PathBuf], y: &[&PathBuf]| {
        x.iter().filter(|f| !y.contains(f)).cloned().cloned().collect::<Vec<_>>()
    };
    assert!(
        a == b,
        "other files after {stops:?} (seed {seed}): only in the uninterrupted run's {:?}, only in the continued {:?}",
        only(&a, &b),
        only(&b, &a)
    );
    for (name, bytes) in &reference {
        assert!(bytes == &resumed[name], "{} differs after {stops:?} (seed {seed})", name.display());
    }
    let series = String::from_utf8(resumed[Path::new("timeseries.csv")].clone()).expect("utf-8");
    let mut lines = series.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|c| *c == name).expect("column");
    let (ins, rem) = (col("inserted"), col("removed"));
    let (mut inserted, mut removed) = (0i64, 0i64);
    for l in lines {
        let v: Vec<&str> = l.split(',').collect();
        inserted += v[ins].parse::<i64>().expect("an integer count");
        removed += v[rem].parse::<i64>().expect("an integer count");
    }
    let snapshot = resumed.iter().rfind(|(p, _)| p.starts_with("snapshots")).expect("a snapshot").1;
    let present = String::from_utf8_lossy(snapshot).lines().count() as i64 - 1;
    assert!(removed > 0 && inserted == 600, "inserted {inserted}, removed {removed}");
    assert_eq!(inserted - removed, present, "the books do not close");
}

/// `--overwrite` removes the earlier run's files and nothing of the user's in `snapshots/` and
/// `vtk/`; over a symlinked `snapshots/` holding the earlier run's snapshots it is refused
/// (exit 2, naming the link) and the link's target keeps every file.
#[test]
fn overwrite_keeps_the_users_files_and_follows_no_link() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = settling_bed(dir.path(), "0.05");
    let out = dir.path().join("out");
    assert!(run(&[&case, &"--out", &out]).status.success());
    std::fs::write(out.join("snapshots/my-plot-data.csv"), "t,h\n0,1\n").unwrap();
    std::fs::write(out.join("vtk/my-state.pvsm"), "<ServerManagerState/>").unwrap();
    let again = run(&[&case, &"--out", &out, &"--overwrite"]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert_eq!(std::fs::read_to_string(out.join("snapshots/my-plot-data.csv")).unwrap(), "t,h\n0,1\n");
    assert_eq!(std::fs::read_to_string(out.join("vtk/my-state.pvsm")).unwrap(), "<ServerManagerState/>");
    // The snapshots moved to another disk, linked back.
    let elsewhere = dir.path().join("elsewhere");
    std::fs::rename(out.join("snapshots"), &elsewhere).unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("snapshots")).unwrap();
    let there: Vec<_> = std::fs::read_dir(&elsewhere).unwrap().map(|e| e.unwrap().file_name()).collect();
    let linked = run(&[&case, &"--out", &out, &"--overwrite"]);
    assert_eq!(linked.status.code(), Some(2), "{}", stderr(&linked));
    assert!(stderr(&linked).contains("snapshots is a symbolic link"), "{}", stderr(&linked));
    let still: Vec<_> = std::fs::read_dir(&elsewhere).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(there, still, "files removed through the link");
    assert!(out.join("timeseries.csv").exists(), "a refused run removed the earlier run's files");
}

/// A folder holding only the user's own `snapshots/` is no earlier run: the run writes beside
/// the user's file (which the manifest does not list) and succeeds.
#[test]
fn a_folder_of_the_users_own_snapshots_is_no_earlier_run() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = settling_bed(dir.path(), "0.05");
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("snapshots")).unwrap();
    std::fs::write(out.join("snapshots/my-plot-data.csv"), "mine").unwrap();
    let r = run(&[&case, &"--out", &out]);
    assert!(r.status.success(), "{}", stderr(&r));
    assert_eq!(std::fs::read_to_string(out.join("snapshots/my-plot-data.csv")).unwrap(), "mine");
    assert!(!manifest(&out).contains(&PathBuf::from("snapshots/my-plot-data.csv")));
    assert!(out.join("snapshots/particles_000000000.csv").exists());
}
