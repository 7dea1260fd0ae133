//! Bad case files give a message naming the table, the key, the value and what is valid —
//! never a panic. Each case below is a valid base case with one defect.

use grainflow_case::{CaseError, parse};

const BASE: &str = r#"
version = 1
[domain]
min = [0.0, 0.0, 0.0]
max = [0.1, 0.1, 0.1]
[[phases]]
name = "glass"
diameter = 0.004
density = 2500.0
youngs_modulus = 6.0e10
poisson_ratio = 0.25
[[wall_materials]]
name = "steel"
youngs_modulus = 2.0e11
poisson_ratio = 0.3
[contact]
model = "lsd"
[contact.particle]
kn = 1000.0
en = 0.9
mu = 0.3
[contact.wall]
kn = 1000.0
en = 0.9
mu = 0.3
[time]
t_stop = 0.01
[[particles.list]]
phase = "glass"
position = [0.05, 0.05, 0.05]
"#;

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

#[test]
fn each_bad_input_names_table_key_value_and_what_is_valid() {
    let cases: Vec<(&str, String, &[&str])> = vec![
        ("syntax error", edit("t_stop = 0.01", "t_stop = = 0.01"), &["case.toml", "line"]),
        (
            "unknown key",
            edit("mu = 0.3\n[contact.wall]", "mu = 0.3\nfriction = 0.3\n[contact.wall]"),
            &["unknown field `friction`", "expected one of"],
        ),
        ("unknown table", format!("{BASE}\n[solver]\nx = 1\n"), &["unknown field `solver`"]),
        (
            "misspelt key",
            edit("t_stop = 0.01", "t_stpo = 0.01"),
            &["unknown field `t_stpo`", "did you mean `t_stop`?"],
        ),
        (
            "misspelt table",
            edit("[contact.particle]", "[contact.particles]"),
            &["unknown field `particles`", "did you mean `particle`?"],
        ),
        ("wrong type", edit("t_stop = 0.01", "t_stop = \"soon\""), &["t_stop", "invalid type"]),
        ("missing version", edit("version = 1", ""), &["top level", "version"]),
        ("wrong version", edit("version = 1", "version = 7"), &["version", "= 7", "version 1"]),
        ("missing t_stop", edit("t_stop = 0.01", ""), &["[time]", "t_stop"]),
        ("missing [time]", edit("[time]\nt_stop = 0.01", ""), &["[time]", "missing"]),
        ("missing domain max", edit("max = [0.1, 0.1, 0.1]", ""), &["[domain]", "max"]),
        (
            "inverted domain",
            edit("max = [0.1, 0.1, 0.1]", "max = [0.1, -0.1, 0.1]"),
            &["[domain]", "max", "exceed min"],
        ),
        (
            "negative diameter",
            edit("diameter = 0.004", "diameter = -0.004"),
            &["[[phases]] 'glass'", "diameter", "-0.004", "positive"],
        ),
        (
            "zero density",
            edit("density = 2500.0", "density = 0.0"),
            &["[[phases]] 'glass'", "density", "= 0", "positive"],
        ),
        (
            "en above 1",
            edit("en = 0.9\nmu = 0.3\n[contact.wall]", "en = 1.5\nmu = 0.3\n[contact.wall]"),
            &["[contact.particle]", "`en` = 1.5", "(0, 1]"],
        ),
        (
            "en zero",
            edit("en = 0.9\nmu = 0.3\n[time]", "en = 0.0\nmu = 0.3\n[time]"),
            &["[contact.wall]", "`en` = 0", "(0, 1]"],
        ),
        (
            "poisson too high",
            edit("poisson_ratio = 0.25", "poisson_ratio = 0.5"),
            &["[[phases]] 'glass'", "poisson_ratio", "0.5", "(-1, 0.5)"],
        ),
        (
            "wall poisson too low",
            edit("poisson_ratio = 0.3", "poisson_ratio = -1.0"),
            &["[[wall_materials]] 'steel'", "poisson_ratio", "-1", "(-1, 0.5)"],
        ),
        (
            "kt_fac above 1",
            edit(
                "kn = 1000.0\nen = 0.9\nmu = 0.3\n[contact.wall]",
                "kn = 1000.0\nkt_fac = 1.2\nen = 0.9\nmu = 0.3\n[contact.wall]",
            ),
            &["[contact.particle]", "kt_fac", "1.2", "[0, 1]"],
        ),
        (
            "negative mu",
            edit("mu = 0.3\n[time]", "mu = -0.1\n[time]"),
            &["[contact.wall]", "`mu` = -0.1", ">= 0"],
        ),
        (
            "negative kn",
            edit("kn = 1000.0\nen = 0.9\nmu = 0.3\n[time]", "kn = -5.0\nen = 0.9\nmu = 0.3\n[time]"),
            &["[contact.wall]", "`kn` = -5", "positive"],
        ),
        (
            "LSD without kn",
            edit("kn = 1000.0\nen = 0.9\nmu = 0.3\n[contact.wall]", "en = 0.9\nmu = 0.3\n[contact.wall]"),
            &["[contact.particle]", "kn", "N/m"],
        ),
        (
            "Hertz without et",
            edit("model = \"lsd\"", "model = \"hertz\""),
            &["[contact.particle]", "et", "hertz"],
        ),
        (
            "unknown model",
            edit("model = \"lsd\"", "model = \"hooke\""),
            &["[contact]", "model", "\"hooke\"", "\"lsd\", \"hertz\""],
        ),
        (
            "unknown integrator",
            edit("t_stop = 0.01", "t_stop = 0.01\nintegrator = \"rk4\""),
            &["[time]", "integrator", "\"rk4\"", "\"euler\""],
        ),
        (
            "dt and factor",
            edit("t_stop = 0.01", "t_stop = 0.01\ndt = 1e-6\ndtsolid_factor = 50"),
            &["[time]", "dtsolid_factor", "not both"],
        ),
        (
            "factor below 10",
            edit("t_stop = 0.01", "t_stop = 0.01\ndtsolid_factor = 5"),
            &["[time]", "dtsolid_factor", "5", "at least 10"],
        ),
        ("negative dt", edit("t_stop = 0.01", "t_stop = 0.01\ndt = -1e-6"), &["[time]", "dt", "positive"]),
        (
            "t_stop before start",
            edit("t_stop = 0.01", "t_stop = 0.01\nt_start = 0.02"),
            &["[time]", "t_stop", "after t_start"],
        ),
        (
            "unknown phase of a particle",
            edit("phase = \"glass\"\nposition", "phase = \"sand\"\nposition"),
            &["[[particles.list]] #1", "phase", "\"sand\"", "\"glass\""],
        ),
        (
            "particle without position",
            edit("position = [0.05, 0.05, 0.05]", ""),
            &["[[particles.list]] #1", "position"],
        ),
        (
            "no particles",
            edit("[[particles.list]]\nphase = \"glass\"\nposition = [0.05, 0.05, 0.05]", "[particles]"),
            &["[particles]", "at least one particle"],
        ),
        (
            "duplicate phase",
            edit(
                "[[wall_materials]]",
                "[[phases]]\nname = \"glass\"\ndiameter = 0.002\ndensity = 1000.0\n[[wall_materials]]",
            ),
            &["[[phases]] 'glass'", "name", "unique"],
        ),
        (
            "pair override with unknown phase",
            format!("{BASE}\n[[contact.pairs]]\nphases = [\"glass\", \"sand\"]\nen = 0.5\n"),
            &["[[contact.pairs]]", "phases", "\"sand\""],
        ),
        (
            "selector in the wrong table",
            edit(
                "kn = 1000.0\nen = 0.9\nmu = 0.3\n[contact.wall]",
                "phase = \"glass\"\nkn = 1000.0\nen = 0.9\nmu = 0.3\n[contact.wall]",
            ),
            &["[contact.particle]", "phase", "[[contact.walls]]"],
        ),
        (
            "missing particle file",
            edit(
                "[[particles.list]]\nphase = \"glass\"\nposition = [0.05, 0.05, 0.05]",
                "[particles]\nfile = \"nowhere.dat\"",
            ),
            &["cannot read", "nowhere.dat"],
        ),
        (
            "mfix file with an unknown phase",
            edit(
                "[[particles.list]]\nphase = \"glass\"\nposition = [0.05, 0.05, 0.05]",
                "[particles]\nfile = \"bad.dat\"",
            ),
            &["bad.dat, line 2", "no phase has diameter", "9999"],
        ),
        (
            "mfix file with 7 columns",
            edit(
                "[[particles.list]]\nphase = \"glass\"\nposition = [0.05, 0.05, 0.05]",
                "[particles]\nfile = \"short.dat\"",
            ),
            &["short.dat, line 1", "expected 8 numbers", "found 7"],
        ),
        (
            "csv with an unknown column",
            edit(
                "[[particles.list]]\nphase = \"glass\"\nposition = [0.05, 0.05, 0.05]",
                "[particles]\nfile = \"bad.csv\"",
            ),
            &["bad.csv, line 1", "unknown column 'colour'"],
        ),
        (
            "csv with text for a number",
            edit(
                "[[particles.list]]\nphase = \"glass\"\nposition = [0.05, 0.05, 0.05]",
                "[particles]\nfile = \"text.csv\"",
            ),
            &["text.csv, line 2", "y = 'abc'", "not a number"],
        ),
        (
            "follow without a leader",
            format!("{BASE}\n[[motion]]\nparticles = 1\nrule = \"follow\"\naxes = [\"x\"]\n"),
            &["[[motion]] #1", "leader"],
        ),
        (
            "follow a missing particle",
            format!("{BASE}\n[[motion]]\nparticles = 1\nrule = \"follow\"\nleader = 5\naxes = [\"x\"]\n"),
            &["[[motion]] #1", "`leader` = 5", "which no particle has"],
        ),
        (
            "hold a missing particle",
            format!("{BASE}\n[[motion]]\nparticles = [1, 3]\nrule = \"hold\"\n"),
            &["[[motion]] #1", "`particles` = 2", "no particle has this id"],
        ),
        (
            "bad axis",
            format!("{BASE}\n[[motion]]\nparticles = 1\nrule = \"follow\"\nleader = 1\naxes = [\"w\"]\n"),
            &["[[motion]] #1", "axes", "\"w\""],
        ),
    ];
    let mut failures = Vec::new();
    for (name, text, expected) in &cases {
        let outcome = std::panic::catch_unwind(|| parse_text(text));
        let msg = match outcome {
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
        for want in *expected {
            if !msg.contains(want) {
                failures.push(format!("{name}: message lacks '{want}':\n    {msg}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} bad inputs misreported:\n{}",
        failures.len(),
        cases.len(),
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
