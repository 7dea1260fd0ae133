//! Any text as a LAMMPS data file: parsed or refused with a line number, never a panic.
#![no_main]

use grainflow::Phase;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let phases = [
        Phase { name: "a".into(), diameter: 0.002, density: 2500.0, youngs_modulus: None, poisson_ratio: None },
        Phase { name: "b".into(), diameter: 1.0, density: 1.909859, youngs_modulus: None, poisson_ratio: None },
    ];
    let _ = grainflow_case::lammps::read_data(&text, "x.data", &phases);
    let _ = grainflow_case::lammps::box_bounds(&text);
});
