//! Bad MFIX decks give a message naming the deck and line, the keyword, the value and what
//! would be valid — never a panic. The corpus is tests/mfix_decks/bad/: each deck is
//! `base.txt` (a valid deck) with one defect, and its `! expect:` lines list what its message
//! must contain.

use std::path::Path;

fn bad_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mfix_decks/bad")
}

#[test]
fn the_base_of_the_corpus_is_valid() {
    let d =
        grainflow_case::mfix::load(&bad_dir().join("base.txt"), &[], None).expect("base.txt must be valid");
    assert_eq!(d.case.particles.len(), 1);
}

#[test]
fn each_bad_deck_gives_its_message_never_a_panic() {
    let mut files: Vec<_> = std::fs::read_dir(bad_dir())
        .expect("tests/mfix_decks/bad")
        .map(|e| e.expect("entry").path())
        .filter(|p| {
            let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            grainflow_case::mfix::is_deck(p) && name != "particle_input.dat"
        })
        .collect();
    files.sort();
    assert!(files.len() >= 15, "only {} bad decks", files.len());
    let mut failures = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).expect("readable");
        let expected: Vec<&str> = text.lines().filter_map(|l| l.strip_prefix("! expect: ")).collect();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if expected.is_empty() {
            failures.push(format!("{name}: no `! expect:` line"));
            continue;
        }
        let msg = match std::panic::catch_unwind(|| grainflow_case::mfix::load(path, &[], None)) {
            Err(_) => {
                failures.push(format!("{name}: panicked"));
                continue;
            }
            Ok(Ok(_)) => {
                failures.push(format!("{name}: accepted"));
                continue;
            }
            Ok(Err(e)) => e.to_string(),
        };
        // Every message names the deck, and a line unless it reports a missing keyword.
        if !msg.contains(&name) {
            failures.push(format!("{name}: message does not name the deck:\n    {msg}"));
        }
        if !msg.contains(", line ") && !msg.contains("missing required key") {
            failures.push(format!("{name}: message names no line:\n    {msg}"));
        }
        for want in expected {
            if !msg.contains(want) {
                failures.push(format!("{name}: message lacks '{want}':\n    {msg}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} problems in {} bad decks:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
}

#[test]
fn bad_motion_files_and_particle_files_are_reported_with_their_names() {
    let dir = tempfile::tempdir().expect("temp dir");
    let base = std::fs::read_to_string(bad_dir().join("base.txt")).expect("base");
    let deck = dir.path().join("mfix.dat");
    std::fs::write(&deck, format!("{base}CALL_USR = .T.\n")).expect("write");
    std::fs::write(dir.path().join("particle_input.dat"), "0.5 0.5 0.5 0.05 1000.0 0 0\n").expect("write");
    let motion = dir.path().join("motion.toml");
    std::fs::write(&motion, "[[motion]]\nparticles = 1\nrule = \"hold\"\n").expect("write");
    let e = grainflow_case::mfix::load(&deck, &[], Some(&motion)).expect_err("7 numbers").to_string();
    assert!(e.contains("particle_input.dat, line 1") && e.contains("expected 8 numbers"), "{e}");
    std::fs::write(dir.path().join("particle_input.dat"), "Version 2.0\n").expect("write");
    let e = grainflow_case::mfix::load(&deck, &[], Some(&motion)).expect_err("version 2").to_string();
    assert!(e.contains("version 2.0") && e.contains("header of 34 lines"), "{e}");
    std::fs::write(dir.path().join("particle_input.dat"), "0.5 0.5 0.5 0.05 1000.0 0 0 0\n").expect("write");
    grainflow_case::mfix::load(&deck, &[], Some(&motion)).expect("valid with its motion file");
    std::fs::write(&motion, "[[motion]]\nparticle = 1\n").expect("write");
    let e = grainflow_case::mfix::load(&deck, &[], Some(&motion)).expect_err("bad motion").to_string();
    assert!(e.contains("motion.toml") && e.contains("unknown field `particle`"), "{e}");
    std::fs::write(&motion, "[[motion]]\nparticles = 7\nrule = \"hold\"\n").expect("write");
    let e = grainflow_case::mfix::load(&deck, &[], Some(&motion)).expect_err("no particle 7").to_string();
    assert!(e.contains("[[motion]] #1") && e.contains("no particle has this id"), "{e}");
    // Two tables for one wall: the second would silently replace the first (issue 38).
    std::fs::write(
        &motion,
        "[[walls]]\nis = 2\n[walls.surface]\nvelocity = [1.0, 0.0, 0.0]\n\n[[walls]]\nis = 2\n[walls.surface]\nvelocity = [-1.0, 0.0, 0.0]\n",
    )
    .expect("write");
    let e = grainflow_case::mfix::load(&deck, &[], Some(&motion)).expect_err("is twice").to_string();
    assert!(
        e.contains("[[walls]] #2") && e.contains("`is` = 2") && e.contains("[[walls]] #1 already gives"),
        "{e}"
    );
    let e = grainflow_case::mfix::load(&dir.path().join("nothere.dat"), &[], None)
        .expect_err("missing")
        .to_string();
    assert!(e.contains("cannot read") && e.contains("nothere.dat"), "{e}");
}
