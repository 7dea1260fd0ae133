//! LIGGGHTS scripts: a corpus of good and bad scripts, and any script made of the commands and
//! words scripts use, in any order. The corpus is tests/liggghts_scripts/: `in.base` is a
//! valid Hertz box script over `bed.data`; each script in `bad/` is the base with one defect,
//! and its `# expect:` lines list what its message must contain (the line, the command or the
//! value). A bad script gives a message naming the script, never a panic.

use grainflow_case::liggghts;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/liggghts_scripts")
}

#[test]
fn the_base_of_the_corpus_is_valid() {
    let s = liggghts::load(&corpus().join("in.base"), &[]).expect("in.base must be valid");
    assert_eq!(s.case.particles.len(), 3, "the three spheres of bed.data");
    // Without `timestep` and `neighbor`, LIGGGHTS's defaults in SI units (its update.cpp):
    // 1e-8 s and a skin of 1 mm.
    let base = std::fs::read_to_string(corpus().join("in.base")).expect("in.base");
    let bare = base.replace("timestep 2.0e-5\n", "").replace("neighbor 0.0002 bin\n", "");
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::copy(corpus().join("bed.data"), dir.path().join("bed.data")).expect("copy");
    std::fs::write(dir.path().join("in.bare"), bare).expect("write");
    let s = liggghts::load(&dir.path().join("in.bare"), &[]).expect("valid without timestep and neighbor");
    let (time, neighbor) = (s.raw.time.as_ref().expect("[time]"), &s.raw.neighbor);
    assert_eq!((time.dt, time.t_stop), (Some(1e-8), Some(2000.0 * 1e-8)));
    assert_eq!(neighbor.skin, Some(0.001));
    assert!(s.notes.iter().any(|n| n.contains("no `timestep`")), "{:?}", s.notes);
}

#[test]
fn each_bad_script_gives_its_message_never_a_panic() {
    let mut files: Vec<_> = std::fs::read_dir(corpus().join("bad"))
        .expect("tests/liggghts_scripts/bad")
        .map(|e| e.expect("entry").path())
        .filter(|p| liggghts::is_script(p))
        .collect();
    files.sort();
    assert!(files.len() >= 20, "only {} bad scripts", files.len());
    let mut failures = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).expect("readable");
        let expected: Vec<&str> = text.lines().filter_map(|l| l.strip_prefix("# expect: ")).collect();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if expected.is_empty() {
            failures.push(format!("{name}: no `# expect:` line"));
            continue;
        }
        // Beside the base's data file: the scripts name `bed.data` as the base does.
        let dir = tempfile::tempdir().expect("temp dir");
        for f in ["bed.data", "in.loop"] {
            std::fs::copy(corpus().join(f), dir.path().join(f)).expect("copy");
        }
        let script = dir.path().join(&name);
        std::fs::write(&script, &text).expect("write");
        let msg = match std::panic::catch_unwind(|| liggghts::load(&script, &[])) {
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
        if !msg.contains(&name) {
            failures.push(format!("{name}: message does not name the script:\n    {msg}"));
        }
        for want in expected {
            if !msg.contains(want) {
                failures.push(format!("{name}: message lacks '{want}':\n    {msg}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The words scripts are made of: commands, styles, keywords, numbers, variables and the
/// characters the reader treats specially (`&`, `#`, quotes, `$`).
const WORDS: &[&str] = &[
    "units",
    "si",
    "lj",
    "atom_style",
    "granular",
    "sphere",
    "boundary",
    "f",
    "p",
    "fm",
    "s",
    "m",
    "read_data",
    "bed.data",
    "missing.data",
    "region",
    "block",
    "create_box",
    "neighbor",
    "0.0002",
    "bin",
    "neigh_modify",
    "delay",
    "0",
    "exclude",
    "group",
    "all",
    "fix",
    "unfix",
    "property/global",
    "youngsModulus",
    "poissonsRatio",
    "coefficientRestitution",
    "coefficientFriction",
    "peratomtype",
    "peratomtypepair",
    "1",
    "2",
    "3",
    "-1",
    "0.5",
    "5e6",
    "1e400",
    "nan",
    "pair_style",
    "gran",
    "model",
    "hertz",
    "hooke",
    "hooke/stiffness",
    "tangential",
    "history",
    "no_history",
    "tangential_damping",
    "on",
    "off",
    "limitForce",
    "pair_coeff",
    "*",
    "wall/gran",
    "primitive",
    "type",
    "zplane",
    "xplane",
    "yplane",
    "zcylinder",
    "gravity",
    "9.81",
    "vector",
    "freeze",
    "nve/sphere",
    "subtract",
    "timestep",
    "2e-5",
    "thermo",
    "thermo_modify",
    "lost",
    "ignore",
    "run",
    "100",
    "upto",
    "variable",
    "x",
    "index",
    "equal",
    "string",
    "v_x",
    "${x}",
    "$x",
    "$(1+2)",
    "(",
    ")",
    "+",
    "*",
    "/",
    "^",
    "&",
    "#",
    "\"",
    "'",
    "include",
    "in.self",
    "mesh/surface",
    "insert/pack",
    "create_atoms",
    "\u{feff}",
    "é",
];

/// Lines of random words from [`WORDS`], sometimes joined without a space.
fn any_script() -> impl Strategy<Value = String> {
    let line = prop::collection::vec((0..WORDS.len(), any::<bool>()), 0..9).prop_map(|ws| {
        let mut s = String::new();
        for (w, glued) in ws {
            if !glued && !s.is_empty() {
                s.push(' ');
            }
            s.push_str(WORDS[w]);
        }
        s
    });
    prop::collection::vec(line, 0..30).prop_map(|lines| lines.join("\n"))
}

/// The base script with random lines put in at random places.
fn base_with_lines() -> impl Strategy<Value = String> {
    let base = std::fs::read_to_string(corpus().join("in.base")).expect("in.base");
    (any_script(), any::<u64>()).prop_map(move |(extra, seed)| {
        let mut lines: Vec<&str> = base.lines().collect();
        for (k, l) in extra.lines().enumerate() {
            let at = (seed.wrapping_mul(k as u64 * 2 + 1) % (lines.len() as u64 + 1)) as usize;
            lines.insert(at, l);
        }
        lines.join("\n")
    })
}

fn translate(text: &str) -> Result<liggghts::ScriptCase, grainflow_case::CaseError> {
    let data = std::fs::read_to_string(corpus().join("bed.data")).expect("bed.data");
    let read = move |name: &str| -> Result<String, grainflow_case::CaseError> {
        match name {
            "bed.data" => Ok(data.clone()),
            // A script that includes itself: the reader's depth cap must end it.
            "in.self" => Ok("include in.self\n".into()),
            _ => Err(grainflow_case::CaseError::Syntax(format!("{name}: no such file"))),
        }
    };
    let open = grainflow_case::input::open_text(&read);
    liggghts::translate(text, "in.fuzz", &[("x".into(), "2".into())], &read, &open)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    /// Any script of script words: a case, or a message naming the script, never a panic.
    #[test]
    fn any_script_gives_a_case_or_a_message(text in any_script()) {
        if let Err(e) = translate(&text) {
            prop_assert!(e.to_string().contains("in.fuzz"), "message without the script: {e}");
        }
    }

    /// The valid base with random lines among its own.
    #[test]
    fn the_base_with_random_lines_gives_a_case_or_a_message(text in base_with_lines()) {
        if let Err(e) = translate(&text) {
            prop_assert!(e.to_string().contains("in.fuzz"), "message without the script: {e}");
        }
    }
}
