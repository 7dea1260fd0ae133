//! The LAMMPS parameterisations reproduce LAMMPS: from the same LAMMPS state, grainflow's
//! kinetic energy after 1 000 steps agrees with LAMMPS's to 4 significant digits (relative
//! difference below 5e-4) on the three yardstick cases of the peers (box bed with the
//! Hertz–Mindlin and the linear law, chute-like flow). LAMMPS writes the states with the peers'
//! own inputs (shortened settling), kept in `bench/lammps/`. Needs `lmp` (Debian package
//! `lammps`), so it is ignored by default; `.ci/run` installs LAMMPS and runs it:
//! `cargo test --release -p grainflow-cli --test lammps_match -- --ignored`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn lmp() -> PathBuf {
    let out = Command::new("sh").args(["-c", "command -v lmp"]).output().expect("sh runs");
    assert!(out.status.success(), "lmp not found: install LAMMPS (Debian: apt-get install lammps)");
    PathBuf::from(String::from_utf8_lossy(&out.stdout).trim())
}

fn run_lmp(lmp: &Path, dir: &Path, args: &[&str]) {
    let out =
        Command::new(lmp).current_dir(dir).args(args).args(["-screen", "none"]).output().expect("lmp runs");
    assert!(out.status.success(), "lmp {args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
}

/// Translational kinetic energy at step 1000 from a LAMMPS log (thermo: Step Atoms KinEng …).
fn lammps_ke(log: &Path) -> f64 {
    let text = std::fs::read_to_string(log).expect("log");
    let mut in_thermo = false;
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.first() == Some(&"Step") {
            in_thermo = true;
        } else if in_thermo && f.first() == Some(&"1000") {
            return f[2].parse().expect("KinEng");
        }
    }
    panic!("no step 1000 in {}", log.display());
}

fn grainflow_ke(case: &Path, data: &Path, dir: &Path, name: &str) -> f64 {
    let text = std::fs::read_to_string(case).expect("case");
    let file = data.file_name().expect("name").to_string_lossy().into_owned();
    let text = text.replace(&format!("file = \"data/{file}\""), &format!("file = \"{}\"", data.display()));
    assert!(text.contains(&data.display().to_string()), "{}: particle file line not found", case.display());
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).expect("write");
    let out = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(dir.join(name))
        .arg("-q")
        .output()
        .expect("runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let ts = std::fs::read_to_string(dir.join(name).join("timeseries.csv")).expect("time series");
    ts.lines()
        .find_map(|l| l.strip_prefix("1000,"))
        .and_then(|r| r.split(',').nth(1))
        .and_then(|v| v.parse().ok())
        .expect("row of step 1000")
}

#[test]
#[ignore = "needs LAMMPS (lmp, Debian package lammps) and --release: see README"]
fn kinetic_energy_after_1000_steps_matches_lammps_to_4_digits() {
    let lmp = lmp();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let peers = root.join("bench/lammps");
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let p = |f: &str| peers.join(f).display().to_string();
    // States: the peers' inputs with shortened settling (12 000 steps for the beds, which are
    // then resting; 20 000 for the chute, which is then flowing steadily). From a bed still in
    // its collisional fall the runs part after ~500 steps, as two runs of one code would with
    // a different summation order: collisions amplify the last bit.
    let settle = |model: &str| {
        let (input, var, steps) = match model {
            "chute" => ("in.chute_like.lmp", "neq", "20000"),
            _ => ("in.box_walls.lmp", "nsettle", "12000"),
        };
        let input = p(input);
        let mut args = vec!["-in", input.as_str(), "-var", var, steps, "-var", "nrun", "0", "-log", "none"];
        if model != "chute" {
            args.extend(["-var", "model", model]);
        }
        run_lmp(&lmp, d, &args);
    };
    for m in ["hm", "lsd", "chute"] {
        settle(m);
    }
    let cases = [
        ("box_hm", "box_hm_settled.data", vec!["-in", "in.box_walls_run.lmp", "-var", "model", "hm"]),
        ("box_lsd", "box_lsd_settled.data", vec!["-in", "in.box_walls_run.lmp", "-var", "model", "lsd"]),
        ("chute", "chute_eq.data", vec!["-in", "in.chute_like_run.lmp"]),
    ];
    let mut report = Vec::new();
    for (name, data, args) in cases {
        let data = d.join(data);
        let mut args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        args[1] = p(&args[1]);
        let log = d.join(format!("{name}.log"));
        args.extend(["-var", "nrun", "1000", "-var", "data"].map(String::from));
        args.push(data.display().to_string());
        args.extend(["-log".to_string(), log.display().to_string()]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        run_lmp(&lmp, d, &args);
        let ke_l = lammps_ke(&log);
        let ke_g = grainflow_ke(&root.join(format!("bench/cases/{name}.toml")), &data, d, name);
        let rel = ((ke_g - ke_l) / ke_l).abs();
        report
            .push(format!("{name}: LAMMPS {ke_l:.7e}, grainflow {ke_g:.7e}, relative difference {rel:.2e}"));
        assert!(ke_l > 0.0 && rel < 5e-4, "{}", report.join("\n"));
    }
    eprintln!("{}", report.join("\n"));
}
