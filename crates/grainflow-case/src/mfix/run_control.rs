//! Run control and output: `[time]` from TSTOP, TIME, DTSOLID_FACTOR and DES_INTG_METHOD;
//! `[output]` from the particle VTK regions.

use super::*;
use crate::error::CaseError;
use crate::raw::*;
use grainflow::contact::limits::Range;

impl Translator<'_> {
    pub(super) fn time(&mut self) -> Result<RawTime, CaseError> {
        let finite = Range {
            lo: 0.0,
            lo_open: false,
            hi: f64::MAX,
            hi_open: false,
            valid: "must be a time >= 0 in s",
        };
        let t0 = self.ranged("TIME", &[], finite, "the start time")?.map(|n| n.v);
        let t_stop =
            self.required("TSTOP", &[], finite, "the stop time", "the end time of the run, s".into())?;
        if t_stop <= t0.unwrap_or(0.0) {
            let g = self.real("TSTOP", &[])?;
            let (loc, text) =
                g.map_or((self.origin.to_string(), t_stop.to_string()), |g| (g.loc.to_string(), g.text));
            return Err(CaseError::invalid(
                loc,
                "TSTOP",
                text,
                format!("must be after TIME = {} s", t0.unwrap_or(0.0)),
            ));
        }
        match self.real("DT", &[])? {
            Some(g) if g.v < 0.0 => {
                return Err(CaseError::invalid(g.loc.to_string(), g.key, g.text, "must be a positive time step in s (it does not set the DEM step: MFIX's DTSOLID does)"));
            }
            Some(g) if g.v > 0.0 => {}
            _ => self.note(format!(
                "{}: DT is not given (or 0): MFIX would take the run as steady-state; in a pure granular run DT does not set the step (MFIX replaces it by DTSOLID), so grainflow runs the DEM as usual",
                self.origin
            )),
        }
        let factor = self.with_default(
            "DTSOLID_FACTOR",
            &[],
            Range {
                lo: 10.0,
                lo_open: false,
                hi: f64::MAX,
                hi_open: false,
                valid: "must be at least 10 (MFIX rejects smaller values)",
            },
            "the collision time to DEM time step ratio",
        )?;
        let method = self.word("DES_INTG_METHOD", &[])?;
        let integrator = match method.as_ref().map_or(default_str("DES_INTG_METHOD"), |g| g.v.as_str()) {
            "EULER" => "euler",
            "ADAMS_BASHFORTH" => "adams_bashforth",
            _ => {
                let valid = "must be 'EULER' (MFIX's default) or 'ADAMS_BASHFORTH'";
                return Err(method.as_ref().map_or_else(
                    || CaseError::missing(self.origin, "DES_INTG_METHOD", valid),
                    |g| Self::invalid_word(g, valid),
                ));
            }
        };
        Ok(RawTime {
            t_stop: Some(t_stop),
            t_start: t0,
            dt: None,
            dtsolid_factor: Some(factor),
            integrator: Some(integrator.into()),
            force_dt: None,
        })
    }

    /// Particle VTK output: the interval of the VTK regions holding particle data.
    pub(super) fn output(&mut self) -> Result<RawOutput, CaseError> {
        let positive = Range {
            lo: 0.0,
            lo_open: true,
            hi: f64::MAX,
            hi_open: false,
            valid: "must be a positive time in s",
        };
        let mut interval: Option<f64> = None;
        for idx in self.deck.indices("VTK_DT") {
            let data = self.word("VTK_DATA", &idx)?.map_or(default_str("VTK_DATA").to_string(), |g| g.v);
            if data != "P" {
                continue;
            }
            if let Some(n) = self.ranged("VTK_DT", &idx, positive, "the VTK output interval")? {
                interval = Some(interval.map_or(n.v, |i: f64| i.min(n.v)));
            }
        }
        let on = self.flag("WRITE_VTK_FILES")?;
        match interval {
            Some(dt) if on => Ok(RawOutput { interval: Some(dt), snapshots: None, vtk_interval: Some(dt) }),
            Some(_) => {
                self.note(format!("{}: VTK_DT for particle data is given but WRITE_VTK_FILES is .FALSE.: no VTK output, outputs at grainflow's default interval", self.origin));
                Ok(RawOutput::default())
            }
            None => Ok(RawOutput::default()),
        }
    }
}
