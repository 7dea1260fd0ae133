//! Any text as MFIX's particle_input.dat: parsed or refused with a line number, never a panic.
#![no_main]

use grainflow::Phase;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let phases = [
        Phase { name: "a".into(), diameter: 0.005, density: 4000.0, youngs_modulus: None, poisson_ratio: None },
        Phase { name: "b".into(), diameter: 0.005, density: 5000.0, youngs_modulus: None, poisson_ratio: None },
    ];
    let _ = grainflow_case::particles::read_mfix(&text, "particle_input.dat", &phases);
});
