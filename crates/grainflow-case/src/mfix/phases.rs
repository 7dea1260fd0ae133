//! The solids phases 1..MMAX: diameter, density and elastic constants.

use super::deck::show;
use super::keywords::Unit;
use super::*;
use crate::error::CaseError;
use grainflow::Phase;
use grainflow::contact::limits::{self};
use std::collections::BTreeMap;

impl Translator<'_> {
    pub(super) fn phases(&mut self, mmax: usize) -> Result<Vec<Phase>, CaseError> {
        let mut names: BTreeMap<i64, String> = BTreeMap::new();
        for (key, value, _) in &self.lexed.gui {
            if let Some(m) = key.strip_prefix("solids_phase_name(").and_then(|r| r.strip_suffix(')'))
                && let Ok(m) = m.trim().parse::<i64>()
            {
                names.insert(m, value.trim_matches(|c| c == '\'' || c == '"').trim().to_string());
            }
        }
        let mut phases: Vec<Phase> = Vec::new();
        for m in 1..=mmax as i64 {
            let unit = self.unit_name(Unit::Length);
            let diameter = self.required(
                "D_P0",
                &[m],
                limits::DIAMETER,
                "the particle diameter",
                format!("the diameter of solids phase {m} ({unit})"),
            )?;
            let density = self.required(
                "RO_S0",
                &[m],
                limits::DENSITY,
                "the solids density",
                format!(
                    "the density of solids phase {m} ({}); variable densities (RO_XS0) are not supported",
                    self.unit_name(Unit::Density)
                ),
            )?;
            let name = names
                .get(&m)
                .filter(|n| !n.is_empty() && !phases.iter().any(|p| &p.name == *n))
                .cloned()
                .unwrap_or_else(|| format!("solids_{m}"));
            phases.push(Phase { name, diameter, density, youngs_modulus: None, poisson_ratio: None });
        }
        for key in [
            "D_P0",
            "RO_S0",
            "SOLIDS_MODEL",
            "E_YOUNG",
            "V_POISSON",
            "DES_EN_WALL_INPUT",
            "DES_ET_WALL_INPUT",
        ] {
            if let Some(extra) =
                self.deck.indices(key).into_iter().find(|i| i.first().is_some_and(|&m| m > mmax as i64))
            {
                let loc = self.deck.entry(key, &extra).map(|e| e.loc.to_string()).unwrap_or_default();
                self.note(format!("{loc}: {} is ignored: MMAX = {mmax}", show(key, &extra)));
            }
        }
        Ok(phases)
    }
}
