//! Any text as a CSV particle file: parsed or refused with a line number, never a panic.
#![no_main]

use grainflow::Phase;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let phases = [Phase { name: "glass".into(), diameter: 0.004, density: 2500.0, youngs_modulus: None, poisson_ratio: None }];
    let _ = grainflow_case::particles::read_csv(&text, "particles.csv", &phases);
});
