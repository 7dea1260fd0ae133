//! The box (X_MIN/X_MAX/XLENGTH and y, z) and gravity, by MFIX's rules.

use super::keywords::Unit;
use super::*;
use crate::error::CaseError;
use grainflow::Vec3;
use grainflow::contact::limits::Range;

impl Translator<'_> {
    /// The box from X_MIN/X_MAX/XLENGTH (and y, z), by MFIX's rules.
    pub(super) fn domain(&self) -> Result<(Vec3, Vec3), CaseError> {
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        let no_k = self.flag("NO_K")?;
        for (a, ax) in ["X", "Y", "Z"].iter().enumerate() {
            if a == 2 && no_k {
                // 2-D: the particles lie in z = 0; the box's depth is set from their size.
                continue;
            }
            let (kmin, kmax, klen) = (format!("{ax}_MIN"), format!("{ax}_MAX"), format!("{ax}LENGTH"));
            let (vmin, vmax, vlen) = (self.real(&kmin, &[])?, self.real(&kmax, &[])?, self.real(&klen, &[])?);
            for g in [&vmin, &vmax, &vlen].into_iter().flatten() {
                if !g.v.is_finite() {
                    return Err(CaseError::invalid(
                        g.loc.to_string(),
                        g.key.clone(),
                        g.text.clone(),
                        "must be a finite length",
                    ));
                }
            }
            if let Some(l) = &vlen
                && l.v <= 0.0
            {
                return Err(CaseError::invalid(
                    l.loc.to_string(),
                    l.key.clone(),
                    l.text.clone(),
                    "the domain length must be positive",
                ));
            }
            let (x0, x1) = match (&vmin, &vmax, &vlen) {
                (Some(a), Some(b), Some(l)) => {
                    if ((b.v - a.v) - l.v).abs() > 1e-9 * l.v.abs() {
                        return Err(CaseError::invalid(
                            l.loc.to_string(),
                            l.key.clone(),
                            l.text.clone(),
                            format!(
                                "{klen} must equal {kmax} − {kmin} = {} − {} (or give only two of the three)",
                                b.text, a.text
                            ),
                        ));
                    }
                    (a.v, b.v)
                }
                (Some(a), Some(b), None) => (a.v, b.v),
                (Some(a), None, Some(l)) => (a.v, a.v + l.v),
                (None, Some(b), Some(l)) => (b.v - l.v, b.v),
                (None, None, Some(l)) => (0.0, l.v),
                (None, Some(b), None) => (0.0, b.v),
                (_, None, None) => {
                    return Err(CaseError::missing(
                        self.origin,
                        klen.clone(),
                        format!(
                            "the domain length in {ax} ({}): give {klen}, or {kmin} and {kmax}",
                            self.unit_name(Unit::Length)
                        ),
                    ));
                }
            };
            if x1 <= x0 {
                let g = vmax.as_ref().or(vmin.as_ref()).or(vlen.as_ref());
                let (loc, key, text) = g
                    .map_or((self.origin.to_string(), kmax.clone(), x1.to_string()), |g| {
                        (g.loc.to_string(), g.key.clone(), g.text.clone())
                    });
                return Err(CaseError::invalid(
                    loc,
                    key,
                    text,
                    format!("{kmax} must exceed {kmin} (the box is empty)"),
                ));
            }
            lo[a] = x0;
            hi[a] = x1;
        }
        Ok((Vec3::from_array(lo), Vec3::from_array(hi)))
    }

    /// MFIX's rule: components default to 0; all three 0 means GRAVITY along −y.
    pub(super) fn gravity(&mut self) -> Result<[f64; 3], CaseError> {
        let finite = Range {
            lo: f64::MIN,
            lo_open: false,
            hi: f64::MAX,
            hi_open: false,
            valid: "must be a finite number",
        };
        let g = self
            .ranged("GRAVITY", &[], finite, "the gravitational acceleration")?
            .map_or(MFIX_GRAVITY, |n| n.v);
        let mut c = [0.0; 3];
        for (k, key) in ["GRAVITY_X", "GRAVITY_Y", "GRAVITY_Z"].iter().enumerate() {
            c[k] = self.ranged(key, &[], finite, "a gravity component")?.map_or(0.0, |n| n.v);
        }
        let any_component = ["GRAVITY_X", "GRAVITY_Y", "GRAVITY_Z"].iter().any(|k| self.deck.has(k));
        if c == [0.0; 3] {
            if any_component && !self.deck.has("GRAVITY") {
                self.note(format!(
                    "{}: GRAVITY_X, GRAVITY_Y and GRAVITY_Z are all zero: MFIX then applies its default gravity, {MFIX_GRAVITY} m/s² along −y, and so does grainflow (write GRAVITY = 0.0 for a run without gravity)",
                    self.origin
                ));
            }
            Ok(if g == 0.0 { [0.0; 3] } else { [0.0, -g, 0.0] })
        } else {
            if let Some(gg) = self.deck.real("GRAVITY", &[])? {
                self.note(format!("{}: GRAVITY is not used: the components GRAVITY_X/Y/Z give the gravity vector (MFIX's rule)", gg.loc));
            }
            Ok(c)
        }
    }
}
