//! Bad case files give a message naming the table, the key, the value and what is valid —
//! never a panic. Each case below is a valid base case with one defect.

use grainflow_case::{CaseError, parse};

mod common;
use common::BASE;

fn parse_text(text: &str) -> Result<grainflow_case::Case, CaseError> {
    parse(text, "case.toml", &|name: &str| match name {
        "bad.dat" => Ok("0.05 0.05 0.05 0.002 2500 0 0 0\n0.01 0.02 0.03 0.002 9999 0 0 0\n".into()),
        "short.dat" => Ok("0.05 0.05 0.05 0.002 2500 0 0\n".into()),
        "bad.csv" => Ok("x,y,z,phase,colour\n0.05,0.05,0.05,glass,red\n".into()),
        "text.csv" => Ok("x,y,z,phase\n0.05,abc,0.05,glass\n".into()),
        other => Err(CaseError::Read {
            path: other.into(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "No such file or directory"),
        }),
    })
}

/// Replaces `from` with `to` in the base case (the text must occur).
fn edit(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "test bug: '{from}' not in the base case");
    BASE.replacen(from, to, 1)
}

#[test]
fn base_case_is_valid() {
    let case = parse_text(BASE).expect("the base case must be valid");
    assert_eq!(case.particles.len(), 1);
    assert!(case.warnings.is_empty());
}

/// The corpus in `tests/bad_cases/`: each file is a case with one defect and, in its
/// `# expect:` lines, the pieces its message must contain (table, key, value, what is valid).
/// Particle files named by the cases live beside them.
#[test]
fn each_bad_case_file_gives_its_message_never_a_panic() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad_cases");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("tests/bad_cases")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 30, "only {} bad cases", files.len());
    let mut failures = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).expect("readable");
        let expected: Vec<&str> = text.lines().filter_map(|l| l.strip_prefix("# expect: ")).collect();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if expected.is_empty() {
            failures.push(format!("{name}: no `# expect:` line"));
            continue;
        }
        let msg = match std::panic::catch_unwind(|| grainflow_case::load(path)) {
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
        for want in expected {
            if !msg.contains(want) {
                failures.push(format!("{name}: message lacks '{want}':\n    {msg}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} problems in {} bad cases:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
}

#[test]
fn forced_dt_runs_with_a_warning_and_looser_overlap_limit_accepts() {
    let case =
        parse_text(&edit("t_stop = 0.01", "t_stop = 0.01\ndt = 1e-3\nforce_dt = true")).expect("forced");
    assert!(case.warnings.iter().any(|w| w.contains("running anyway")), "{:?}", case.warnings);
    let text = edit("position = [0.05, 0.05, 0.05]", "position = [0.05, 0.0015, 0.05]")
        .replace("[[particles.list]]", "[particles]\nmax_initial_overlap = 0.3\n[[particles.list]]");
    parse_text(&text).expect("a 25 % wall overlap is allowed under a 30 % limit");
}

#[test]
fn unused_parameters_are_warned_about() {
    let case = parse_text(&edit(
        "en = 0.9\nmu = 0.3\n[contact.wall]",
        "en = 0.9\net = 0.5\nmu = 0.3\n[contact.wall]",
    ))
    .expect("valid");
    assert_eq!(case.warnings.len(), 1, "{:?}", case.warnings);
    assert!(case.warnings[0].contains("`et` is not used by the lsd model"));
}
