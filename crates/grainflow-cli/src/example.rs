//! `grainflow example [NAME] [--dir DIR]`: writes a ready-to-run example case.

use crate::EXIT_BAD_INPUT;
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Debug, Args)]
pub struct ExampleArgs {
    /// The example to write; without it, the examples are listed.
    name: Option<String>,
    /// Folder to write it into (default: a new folder named after the example, in the
    /// current directory). Existing files are never overwritten.
    #[arg(long)]
    dir: Option<PathBuf>,
}

/// An example: name, one line, and its files (name, contents).
struct Example {
    name: &'static str,
    summary: &'static str,
    files: &'static [(&'static str, &'static str)],
}

const EXAMPLES: &[Example] = &[
    Example {
        name: "settling-bed",
        summary: "486 glass beads settling in a box (linear spring-dashpot), with VTK output for ParaView",
        files: &[
            ("case.toml", include_str!("../../../examples/settling-bed/case.toml")),
            ("particles.csv", include_str!("../../../examples/settling-bed/particles.csv")),
        ],
    },
    Example {
        name: "rotating-drum",
        summary: "1 267 glass beads in a drum (triangle mesh) turning at 10 rpm: the rolling regime, the drive torque in the time series",
        files: &[
            ("case.toml", include_str!("../../../examples/rotating-drum/case.toml")),
            ("drum.obj", include_str!("../../../examples/rotating-drum/drum.obj")),
            ("particles.csv", include_str!("../../../examples/rotating-drum/particles.csv")),
        ],
    },
    Example {
        name: "conical-hopper",
        summary: "3 396 glass beads discharging from a conical hopper (triangle mesh) into a bin",
        files: &[
            ("case.toml", include_str!("../../../examples/conical-hopper/case.toml")),
            ("hopper.obj", include_str!("../../../examples/conical-hopper/hopper.obj")),
            ("particles.csv", include_str!("../../../examples/conical-hopper/particles.csv")),
        ],
    },
    Example {
        name: "hopper-fill-discharge",
        summary: "the conical hopper filled by an insertion behind a slide gate (a mesh with a start time), then opened: 3 000 beads discharged through an outlet, counted",
        files: &[
            ("case.toml", include_str!("../../../examples/hopper-fill-discharge/case.toml")),
            ("hopper.obj", include_str!("../../../examples/hopper-fill-discharge/hopper.obj")),
            ("gate.obj", include_str!("../../../examples/hopper-fill-discharge/gate.obj")),
        ],
    },
    Example {
        name: "pour-bed",
        summary: "a bed of glass beads (1.6–2.4 mm) and steel shot poured into a box by an insertion: no particle file",
        files: &[("case.toml", include_str!("../../../examples/pour-bed/case.toml"))],
    },
    Example {
        name: "bouncing-ball",
        summary: "one ball dropped on the floor (MFIX DEM02 set-up, e_n = 0.9)",
        files: &[("case.toml", include_str!("../../../examples/bouncing-ball/case.toml"))],
    },
    Example {
        name: "dem05-lsd",
        summary: "MFIX DEM05 oblique collisions, linear spring-dashpot (93 particles, anvils held by prescribed motion)",
        files: &[
            ("case.toml", include_str!("../../grainflow-verify/cases/dem05/lsd.toml")),
            ("particle_input.dat", include_str!("../../grainflow-verify/cases/dem05/particle_input.dat")),
        ],
    },
    Example {
        name: "dem05-hertz",
        summary: "MFIX DEM05 oblique collisions, Hertzian model",
        files: &[
            ("case.toml", include_str!("../../grainflow-verify/cases/dem05/hertz.toml")),
            ("particle_input.dat", include_str!("../../grainflow-verify/cases/dem05/particle_input.dat")),
        ],
    },
];

pub fn main(args: ExampleArgs) -> ExitCode {
    let Some(name) = args.name else {
        let width = EXAMPLES.iter().map(|e| e.name.len()).max().unwrap_or(0);
        for e in EXAMPLES {
            println!("{:<width$} {}", e.name, e.summary);
        }
        return ExitCode::SUCCESS;
    };
    let Some(example) = EXAMPLES.iter().find(|e| e.name == name) else {
        let names: Vec<&str> = EXAMPLES.iter().map(|e| e.name).collect();
        eprintln!("error: no example named '{name}'; the examples are {}", names.join(", "));
        return ExitCode::from(EXIT_BAD_INPUT);
    };
    let dir = args.dir.unwrap_or_else(|| PathBuf::from(example.name));
    match write(example, &dir) {
        Ok(()) => {
            println!("wrote {} into {}", example.name, dir.display());
            println!(
                "run it with:  grainflow run {} --out {}",
                dir.join("case.toml").display(),
                dir.join("out").display()
            );
            ExitCode::SUCCESS
        }
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::from(EXIT_BAD_INPUT)
        }
    }
}

fn write(example: &Example, dir: &Path) -> Result<(), String> {
    for (file, _) in example.files {
        let path = dir.join(file);
        if path.exists() {
            return Err(format!(
                "{} exists already; choose another folder with --dir (nothing was written)",
                path.display()
            ));
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    for (file, text) in example.files {
        let path = dir.join(file);
        grainflow_run::output::write_atomic(&path, text.as_bytes())
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    Ok(())
}
