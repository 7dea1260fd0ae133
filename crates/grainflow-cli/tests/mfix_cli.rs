//! `grainflow run` and `grainflow convert` on MFIX decks, as a user would run them: the DEM05
//! decks reproduce the native DEM05 outputs byte for byte, a converted case reproduces its
//! deck, overrides work, and bad input exits 2 with a message.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn grainflow() -> Command {
    Command::new(env!("CARGO_BIN_EXE_grainflow"))
}

fn decks() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../grainflow-case/tests/mfix_decks")
}

fn native(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../grainflow-verify/cases").join(rel)
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    let out = grainflow().args(args).output().expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    out
}

fn ok(out: &Output) -> String {
    assert!(out.status.success(), "exit {:?}: {}", out.status.code(), String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Every output file that both runs write (time series, snapshots) is byte for byte the same.
fn same_outputs(a: &Path, b: &Path) {
    let ts = |d: &Path| std::fs::read(d.join("timeseries.csv")).expect("timeseries.csv");
    assert!(ts(a) == ts(b), "timeseries.csv differs between {} and {}", a.display(), b.display());
    let mut n = 0;
    for e in std::fs::read_dir(b.join("snapshots")).expect("snapshots") {
        let name = e.expect("entry").file_name();
        let (x, y) =
            (std::fs::read(a.join("snapshots").join(&name)), std::fs::read(b.join("snapshots").join(&name)));
        assert!(x.expect("snapshot in the deck run") == y.expect("snapshot"), "{name:?} differs");
        n += 1;
    }
    assert!(n >= 2, "only {n} snapshots");
}

fn dem05(deck: &str, toml: &str) {
    let dir = tempfile::tempdir().expect("temp dir");
    let (a, b) = (dir.path().join("deck"), dir.path().join("native"));
    let out = run(&[
        "run".as_ref(),
        decks().join("dem05").join(deck).as_os_str(),
        "--motion".as_ref(),
        decks().join("dem05/motion.toml").as_os_str(),
        "--quiet".as_ref(),
        "--out".as_ref(),
        a.as_os_str(),
    ]);
    ok(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("CALL_USR") && stderr.contains("ignored"), "{stderr}");
    ok(&run(&[
        "run".as_ref(),
        native(toml).as_os_str(),
        "--quiet".as_ref(),
        "--out".as_ref(),
        b.as_os_str(),
    ]));
    same_outputs(&a, &b);
    let info = std::fs::read_to_string(a.join("run-info.toml")).expect("run-info");
    assert!(info.contains("motion_file") && info.contains(deck), "{info}");
}

#[test]
fn dem05_lsd_deck_reproduces_the_native_run_exactly() {
    dem05("lsd.dat", "dem05/lsd.toml");
}

#[test]
fn dem05_hertz_mfx_reproduces_the_native_run_exactly() {
    dem05("hertz.mfx", "dem05/hertz.toml");
}

#[test]
fn a_converted_deck_runs_to_the_same_outputs_as_the_deck() {
    let dir = tempfile::tempdir().expect("temp dir");
    let deck = decks().join("dem05/hertz.mfx");
    let motion = decks().join("dem05/motion.toml");
    let out = run(&["convert".as_ref(), deck.as_os_str(), "--motion".as_ref(), motion.as_os_str()]);
    let toml = ok(&out);
    assert!(toml.starts_with("# grainflow case translated from the MFIX deck"), "{toml}");
    assert!(toml.contains("[[motion]]") && toml.contains("model = \"hertz\""), "{toml}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning: "), "notes go to standard error");
    // The case names particle_input.dat beside itself.
    std::fs::copy(decks().join("dem05/particle_input.dat"), dir.path().join("particle_input.dat"))
        .expect("copy");
    let case = dir.path().join("case.toml");
    std::fs::write(&case, &toml).expect("write");
    let (a, b) = (dir.path().join("deck"), dir.path().join("toml"));
    ok(&run(&[
        "run".as_ref(),
        deck.as_os_str(),
        "--motion".as_ref(),
        motion.as_os_str(),
        "-q".as_ref(),
        "--out".as_ref(),
        a.as_os_str(),
    ]));
    ok(&run(&["run".as_ref(), case.as_os_str(), "-q".as_ref(), "--out".as_ref(), b.as_os_str()]));
    same_outputs(&a, &b);
}

#[test]
fn overrides_change_the_deck_and_are_recorded() {
    let dir = tempfile::tempdir().expect("temp dir");
    let deck = decks().join("dem01/mfix.dat");
    let out = run(&[
        "run".as_ref(),
        deck.as_os_str(),
        "TSTOP=0.1".as_ref(),
        "DES_INTG_METHOD='ADAMS_BASHFORTH'".as_ref(),
        "-q".as_ref(),
        "--out".as_ref(),
        dir.path().as_os_str(),
    ]);
    let stdout = ok(&out);
    // DTSOLID 1.4670332e-3 s: 0.1 s takes ceil(68.16) = 69 steps.
    assert!(stdout.contains("69 steps"), "{stdout}");
    let info = std::fs::read_to_string(dir.path().join("run-info.toml")).expect("run-info");
    assert!(
        info.contains("mfix_overrides = [\"TSTOP=0.1\", \"DES_INTG_METHOD='ADAMS_BASHFORTH'\"]"),
        "{info}"
    );
    // The override lands in the translated case.
    let toml = ok(&run(&["convert".as_ref(), deck.as_os_str(), "DES_INTG_METHOD=ADAMS_BASHFORTH".as_ref()]));
    assert!(toml.contains("integrator = \"adams_bashforth\""), "{toml}");
}

#[test]
fn bad_decks_and_misused_options_exit_2_with_a_message() {
    let check = |args: &[&std::ffi::OsStr], wants: &[&str]| {
        let out = run(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        for w in wants {
            assert!(stderr.contains(w), "{args:?}: lacks '{w}': {stderr}");
        }
    };
    let bad = decks().join("bad/09-restitution-above-1.dat");
    check(&["run".as_ref(), bad.as_os_str()], &["error: ", "line 20", "`DES_EN_INPUT(1)` = 1.5", "(0, 1]"]);
    check(&["convert".as_ref(), bad.as_os_str()], &["line 20", "`DES_EN_INPUT(1)` = 1.5"]);
    let deck = decks().join("dem01/mfix.dat");
    check(
        &["run".as_ref(), deck.as_os_str(), "KN=abc".as_ref()],
        &["command-line override `KN=abc`", "not a number"],
    );
    check(&["run".as_ref(), deck.as_os_str(), "KN".as_ref()], &["expected KEYWORD=VALUE"]);
    let toml = native("dem01/dem01.toml");
    check(&["run".as_ref(), toml.as_os_str(), "KN=1".as_ref()], &["apply to MFIX decks", "TOML case file"]);
    check(
        &["run".as_ref(), toml.as_os_str(), "--motion".as_ref(), "m.toml".as_ref()],
        &["--motion applies to MFIX decks"],
    );
    // A user-function deck without its motion file.
    check(
        &["run".as_ref(), decks().join("dem05/lsd.dat").as_os_str()],
        &["`CALL_USR` = .TRUE.", "--motion FILE"],
    );
    // A deck without its particle file.
    let dir = tempfile::tempdir().expect("temp dir");
    let lone = dir.path().join("mfix.dat");
    std::fs::copy(&deck, &lone).expect("copy");
    check(&["run".as_ref(), lone.as_os_str()], &["cannot read", "particle_input.dat"]);
    check(&["convert".as_ref(), "no/such/mfix.dat".as_ref()], &["cannot read no/such/mfix.dat"]);
}
