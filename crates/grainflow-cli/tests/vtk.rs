//! The VTK files, read back by VTK's own XML reader (Python wheel `vtk`), match what the
//! engine wrote, and an off-screen rendering of the settled bed shows it at the bottom of its
//! box. Needs a Python with `vtk` and `numpy`, named by `GRAINFLOW_VTK_PYTHON=/path/to/python`,
//! so it is ignored by default; `.ci/run` makes one in target/vtk-venv and runs it:
//! `cargo test --release -p grainflow-cli --test vtk -- --ignored`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn vtk_python() -> PathBuf {
    let python = std::env::var_os("GRAINFLOW_VTK_PYTHON")
        .map(PathBuf::from)
        .expect("GRAINFLOW_VTK_PYTHON must name a Python with vtk and numpy (see README)");
    assert!(python.exists(), "GRAINFLOW_VTK_PYTHON = {} does not exist", python.display());
    python
}

#[test]
#[ignore = "needs a Python with vtk and numpy in GRAINFLOW_VTK_PYTHON: see README"]
fn vtk_series_reads_back_in_vtk_and_renders_the_bed() {
    let python = vtk_python();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = tempfile::tempdir().expect("temp dir");
    // The settling-bed example, shortened to 0.2 s: the beads have landed by 0.09 s.
    let case = std::fs::read_to_string(root.join("examples/settling-bed/case.toml")).expect("example");
    let case = case
        .replace("t_stop = 0.5", "t_stop = 0.2")
        .replace("particles.csv", &root.join("examples/settling-bed/particles.csv").display().to_string());
    assert!(
        case.contains("t_stop = 0.2") && case.contains("vtk_interval"),
        "the example changed: update this test"
    );
    let case_path = dir.path().join("case.toml");
    std::fs::write(&case_path, case).expect("write case");
    let out = dir.path().join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .arg("run")
        .arg(&case_path)
        .arg("--out")
        .arg(&out)
        .arg("--quiet")
        .output()
        .expect("runs");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let png = dir.path().join("bed.png");
    let render = Command::new(&python)
        .arg(root.join("tests/vtk/render_snapshot.py"))
        .arg(out.join("vtk"))
        .arg(&png)
        .output()
        .expect("python runs");
    assert!(
        render.status.success() && png.exists(),
        "render failed: {}",
        String::from_utf8_lossy(&render.stderr)
    );
    let check = Command::new(&python)
        .arg(root.join("tests/vtk/check_vtk.py"))
        .arg(&out)
        .args(["0", "0", "0", "0.05", "0.2", "0.05"])
        .arg(&png)
        .output()
        .expect("python runs");
    let stdout = String::from_utf8_lossy(&check.stdout);
    assert!(check.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&check.stderr));
    assert!(stdout.contains("OK:"), "{stdout}");
}
