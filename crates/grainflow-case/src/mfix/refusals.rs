//! The keywords that would change the result in a way grainflow cannot reproduce, and the
//! number of solids phases.

use super::deck::show;
use super::keywords::{Allow, Role};
use super::*;
use crate::error::CaseError;

impl Translator<'_> {
    /// Keywords that would change the result in a way grainflow cannot reproduce.
    pub(super) fn refusals(&mut self, have_motion: bool) -> Result<(), CaseError> {
        let d = self.deck;
        for key in &d.order {
            let g = &d.given[key];
            let Some(spec) = g.spec else { continue };
            let Role::Refused(allow, why) = spec.role else { continue };
            for (idx, e) in &g.entries {
                let ok = match allow {
                    Allow::False => d.bool(key, idx)?.is_none_or(|b| !b.v),
                    Allow::Zero => d.real(key, idx)?.is_none_or(|r| r.v == 0.0),
                    Allow::Never => false,
                };
                if !ok {
                    let written = e.value.as_ref().map_or(String::new(), |v| v.written());
                    let only = match allow {
                        Allow::False => " (only .FALSE., MFIX's default, can be run)",
                        Allow::Zero => " (only 0, MFIX's default, can be run)",
                        Allow::Never => "",
                    };
                    self.block(CaseError::invalid(
                        e.loc.to_string(),
                        show(key, idx),
                        written,
                        format!("grainflow cannot run this: {why}{only}"),
                    ));
                }
            }
        }
        if let Some(loc) = &self.lexed.reactions {
            self.block(CaseError::invalid(
                loc.to_string(),
                "@(RXNS)",
                "(a chemical reaction block)",
                "grainflow cannot run this: chemical reactions change particle mass and size and grainflow has no chemistry; remove the block",
            ));
        }
        if let Some(loc) = &self.lexed.thermo_data {
            self.note(format!("{loc}: the THERMO DATA section (thermochemical data) is ignored: it does not act on the particle motion"));
        }
        match self.word("RUN_TYPE", &[])? {
            Some(g) if g.v == "NEW" => {}
            Some(g) if g.v == "RESTART_1" || g.v == "RESTART_2" => {
                self.block(Self::invalid_word(
                    &g,
                    "grainflow cannot run this: MFIX restart files cannot be read; use RUN_TYPE = 'NEW' (grainflow restarts from its own checkpoints: grainflow run --restart)",
                ));
            }
            Some(g) => {
                self.block(Self::invalid_word(
                    &g,
                    "must be 'NEW' (or MFIX's 'RESTART_1', 'RESTART_2', which grainflow cannot read)",
                ));
            }
            None => {}
        }
        match self.word("COORDINATES", &[])? {
            Some(g) if g.v == "CARTESIAN" => {}
            Some(g) if g.v == "CYLINDRICAL" => {
                self.block(Self::invalid_word(
                    &g,
                    "grainflow cannot run this: only COORDINATES = 'CARTESIAN' is supported",
                ));
            }
            Some(g) => {
                self.block(Self::invalid_word(
                    &g,
                    "must be 'CARTESIAN' (or 'CYLINDRICAL', which grainflow cannot run)",
                ));
            }
            None => {}
        }
        match self.real("RO_G0", &[])? {
            Some(g) if g.v == 0.0 => {}
            Some(g) => {
                // The drag on a particle grows with the gas viscosity, not its density: a deck
                // with a vanishing gas density (MFIX's poly_dem_inlet_outlet, 1.3d-30) still
                // drags its particles through the gas.
                let drag = d.string("DRAG_TYPE", &[], true)?;
                let (drag_name, drag_at) =
                    drag.as_ref().map_or(("SYAM_OBRIEN".to_string(), "MFIX's default".to_string()), |t| {
                        (t.v.clone(), t.loc.to_string())
                    });
                let mu = d
                    .real("MU_G0", &[])?
                    .map_or("MU_G0 not given: MFIX's Sutherland air viscosity".to_string(), |m| {
                        format!("MU_G0 = {} ({})", m.text, m.loc)
                    });
                let what = if g.v.abs() < 1e-6 {
                    format!(
                        "grainflow cannot run this: the gas density is vanishingly small, but the gas still drags the particles: DRAG_TYPE = '{drag_name}' ({drag_at}) with {mu}, and the deck's gas velocities; grainflow has no gas phase and no drag. A pure granular run has RO_G0 = 0.0 (then MFIX computes no drag either)"
                    )
                } else {
                    format!(
                        "grainflow cannot run this: a gas density couples gas and particles (drag: DRAG_TYPE = '{drag_name}' ({drag_at}) with {mu}; buoyancy) and grainflow has no gas phase; a pure granular run has RO_G0 = 0.0"
                    )
                };
                self.block(CaseError::invalid(g.loc.to_string(), g.key, g.text, what));
            }
            None => {
                self.block(CaseError::missing(
                    self.origin,
                    "RO_G0",
                    "a pure granular (DEM-only) run needs RO_G0 = 0.0; without it MFIX computes a gas density from the ideal-gas law and couples gas and particles, which grainflow cannot",
                ));
            }
        }
        if let Some(g) = d.bool("CALL_USR", &[])? {
            if g.v && !have_motion {
                self.block(CaseError::invalid(
                    g.loc.to_string(),
                    g.key,
                    g.text,
                    "grainflow cannot run user-defined Fortran functions (usr0.f, usr1_des.f, …), which can change any result. If they only write output, run without them: grainflow run DECK CALL_USR=.F. (the deck stays as it is). If they prescribe motion — particles held or moved (MFIX's DEM05), a drum or a belt turned by a key-frame table (data_kf_NNNN.txt) — say the same in a motion file of [[motion]] and [[walls]] tables and run grainflow run DECK --motion FILE (docs/mfix-decks.md, \"User-defined functions\")",
                ));
            }
            if g.v {
                self.note(format!(
                    "{}: CALL_USR = .TRUE.: the deck's user-defined functions are replaced by the rules of the --motion file",
                    g.loc
                ));
            }
        }
        Ok(())
    }

    pub(super) fn phases_count(&self) -> Result<usize, CaseError> {
        let d = self.deck;
        let mmax = match d.int("MMAX", &[])? {
            Some(g) if (1..=10).contains(&g.v) => g.v as usize,
            Some(g) => {
                return Err(CaseError::invalid(
                    g.loc.to_string(),
                    g.key,
                    g.text,
                    "must be a number of solids phases from 1 to 10 (MFIX's DIM_M); a DEM run needs at least one phase",
                ));
            }
            None => default_int("MMAX") as usize,
        };
        for m in 1..=mmax as i64 {
            match self.word("SOLIDS_MODEL", &[m])? {
                Some(g) if g.v == "DEM" => {}
                Some(g) => {
                    return Err(Self::invalid_word(
                        &g,
                        format!(
                            "grainflow cannot run this: it runs discrete particles only; every solids phase must be SOLIDS_MODEL({m}) = 'DEM' ('TFM' continuum, 'PIC' parcels and 'CGP' coarse grains are not supported)"
                        ),
                    ));
                }
                None => {
                    return Err(CaseError::missing(
                        self.origin,
                        show("SOLIDS_MODEL", &[m]),
                        format!(
                            "MFIX's default is 'TFM' (continuum solids), which grainflow cannot run: set SOLIDS_MODEL({m}) = 'DEM'"
                        ),
                    ));
                }
            }
        }
        Ok(mmax)
    }
}
