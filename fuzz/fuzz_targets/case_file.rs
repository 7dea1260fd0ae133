//! Any text as a case file: validation either accepts it or returns an error, never panics
//! or hangs; an accepted case is set up and stepped a little.
#![no_main]

use libfuzzer_sys::fuzz_target;

const PARTICLES: &str = "0.05 0.05 0.05 0.002 2500 0 0 0\n0.05 0.06 0.05 0.002 2500 0 -1 0\n";
const CSV: &str = "x,y,z,phase\n0.05,0.05,0.05,1\n0.05,0.06,0.05,1\n";

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let read = |name: &str| -> Result<String, grainflow_case::CaseError> {
        match name {
            "particle_input.dat" => Ok(PARTICLES.into()),
            "particles.csv" => Ok(CSV.into()),
            _ => Err(grainflow_case::CaseError::Read { path: name.into(), source: std::io::Error::other("not in the fuzz set") }),
        }
    };
    if let Ok(case) = grainflow_case::parse(&text, "fuzz.toml", &read) {
        // Keep each input cheap: small particle counts only.
        if case.particles.len() <= 64 {
            if let Ok(mut sim) = grainflow::Simulation::new(case.config, case.particles) {
                for _ in 0..20 {
                    if sim.finished() {
                        break;
                    }
                    sim.step();
                }
                let _ = sim.diagnostics();
                let _ = sim.contacts();
            }
        }
    }
});
