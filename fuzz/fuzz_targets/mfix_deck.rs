//! Any text as an MFIX keyword deck (with a fixed particle_input.dat): translated and validated,
//! or refused with a message naming the line, never a panic or a hang.
#![no_main]

use libfuzzer_sys::fuzz_target;

const PARTICLES: &str = "0.05 0.05 0.05 0.0025 4000 0 0 0\n";

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let read = |name: &str| -> Result<String, grainflow_case::CaseError> {
        if name == "particle_input.dat" {
            Ok(PARTICLES.into())
        } else {
            Err(grainflow_case::CaseError::Read { path: name.into(), source: std::io::Error::other("not in the fuzz set") })
        }
    };
    let _ = grainflow_case::mfix::parse(&text, "mfix.dat", &[], None, &read);
});
