//! Any text as a LIGGGHTS input script (with a fixed data file; an include of itself):
//! translated and validated, or refused with a message naming the line, never a panic or a
//! hang.
#![no_main]

use libfuzzer_sys::fuzz_target;

const DATA: &str = "LIGGGHTS data\n\n2 atoms\n1 atom types\n\n0 0.04 xlo xhi\n0 0.04 ylo yhi\n0 0.02 zlo zhi\n\nAtoms\n\n1 1 0.002 2500 0.01 0.01 0.001\n2 1 0.002 2500 0.02 0.01 0.001\n";

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let read = |name: &str| -> Result<String, grainflow_case::CaseError> {
        match name {
            "bed.data" => Ok(DATA.into()),
            "in.self" => Ok("include in.self\n".into()),
            _ => Err(grainflow_case::CaseError::Syntax(format!("{name}: not in the fuzz set"))),
        }
    };
    let open = grainflow_case::input::open_text(&read);
    let _ = grainflow_case::liggghts::translate(&text, "in.fuzz", &[], &read, &open);
});
