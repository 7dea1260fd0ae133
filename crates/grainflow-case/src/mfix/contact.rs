//! The collision keywords: `[contact]`, its defaults tables, the per-pair and per-wall
//! restitution, and whether the model is Hertzian.

use super::deck::show;
use super::keywords::Unit;
use super::*;
use crate::error::CaseError;
use crate::raw::*;
use grainflow::Phase;
use grainflow::contact::limits::{self, Range};

impl Translator<'_> {
    /// `[contact]` and whether the model is Hertzian.
    pub(super) fn contact(&mut self, phases: &mut [Phase]) -> Result<(RawContact, bool), CaseError> {
        let model = match self.word("DES_COLL_MODEL", &[])? {
            None => default_str("DES_COLL_MODEL").to_string(),
            Some(g) if g.v == "LSD" || g.v == "HERTZIAN" => g.v,
            Some(g) => {
                return Err(Self::invalid_word(&g, "must be 'LSD' (linear spring-dashpot) or 'HERTZIAN'"));
            }
        };
        let hertz = model == "HERTZIAN";
        let n = phases.len();
        let pairs: Vec<(usize, usize)> = (0..n).flat_map(|m| (m..n).map(move |l| (m, l))).collect();
        let restitution = |t: &Self,
                           key: &str,
                           lc: usize,
                           what: &str,
                           range: Range|
         -> Result<f64, CaseError> {
            if let Some(g) = t.real(key, &[lc as i64])?
                && g.v == 0.0
                && range == limits::EN
            {
                return Err(CaseError::invalid(
                    g.loc.to_string(),
                    g.key,
                    g.text,
                    "must lie in (0, 1]: MFIX accepts 0 (critical damping) but grainflow's damping needs e > 0; use a small positive value",
                ));
            }
            t.required(key, &[lc as i64], range, what, format!("{what}; {}", order_hint(key, n)))
        };
        let mut en = Vec::new();
        let mut et = Vec::new();
        for (lc, (m, l)) in pairs.iter().enumerate() {
            let what = format!("the normal restitution coefficient of phase pair {}-{}", m + 1, l + 1);
            en.push(restitution(self, "DES_EN_INPUT", lc + 1, &what, limits::EN)?);
            if hertz {
                let what =
                    format!("the tangential restitution coefficient of phase pair {}-{}", m + 1, l + 1);
                et.push(restitution(self, "DES_ET_INPUT", lc + 1, &what, limits::ET)?);
            }
        }
        let mut enw = Vec::new();
        let mut etw = Vec::new();
        for m in 0..n {
            let what = format!("the normal restitution coefficient of phase {} against the walls", m + 1);
            enw.push(restitution(self, "DES_EN_WALL_INPUT", m + 1, &what, limits::EN)?);
            if hertz {
                let what =
                    format!("the tangential restitution coefficient of phase {} against the walls", m + 1);
                etw.push(restitution(self, "DES_ET_WALL_INPUT", m + 1, &what, limits::ET)?);
            }
        }
        for (key, count) in [
            ("DES_EN_INPUT", pairs.len()),
            ("DES_ET_INPUT", pairs.len()),
            ("DES_EN_WALL_INPUT", n),
            ("DES_ET_WALL_INPUT", n),
        ] {
            if let Some(extra) =
                self.deck.indices(key).into_iter().find(|i| i.first().is_some_and(|&k| k > count as i64))
            {
                let loc = self.deck.entry(key, &extra).map(|e| e.loc.to_string()).unwrap_or_default();
                self.note(format!(
                    "{loc}: {} is ignored: MMAX = {n} needs {count} values",
                    show(key, &extra)
                ));
            }
        }
        let mu = self.required(
            "MEW",
            &[],
            limits::MU,
            "the particle-particle friction coefficient",
            "the particle-particle Coulomb friction coefficient (MFIX requires it)".into(),
        )?;
        let mu_w = self.required(
            "MEW_W",
            &[],
            limits::MU,
            "the particle-wall friction coefficient",
            "the particle-wall Coulomb friction coefficient (MFIX requires it)".into(),
        )?;
        let mu_r = self.with_default("MEW_R", &[], limits::MU_ROLL, "the rolling friction (a length)")?;
        let mu_rw =
            self.with_default("MEW_RW", &[], limits::MU_ROLL, "the wall rolling friction (a length)")?;

        let mut particle = RawContactParams { mu: Some(mu), mu_roll: Some(mu_r), ..Default::default() };
        let mut wall = RawContactParams { mu: Some(mu_w), mu_roll: Some(mu_rw), ..Default::default() };
        let unused: &[&str];
        if hertz {
            for m in 0..n {
                let e = self.required(
                    "E_YOUNG",
                    &[m as i64 + 1],
                    limits::YOUNGS,
                    "Young's modulus",
                    format!(
                        "Young's modulus of phase {} ({}), required by DES_COLL_MODEL = 'HERTZIAN'",
                        m + 1,
                        self.unit_name(Unit::Modulus)
                    ),
                )?;
                let nu = self.required(
                    "V_POISSON",
                    &[m as i64 + 1],
                    limits::POISSON,
                    "Poisson's ratio",
                    format!("Poisson's ratio of phase {}, required by DES_COLL_MODEL = 'HERTZIAN'", m + 1),
                )?;
                phases[m].youngs_modulus = Some(e);
                phases[m].poisson_ratio = Some(nu);
            }
            unused = &["KN", "KN_W", "KT_FAC", "KT_W_FAC", "DES_ETAT_FAC", "DES_ETAT_W_FAC"];
        } else {
            let unit = self.unit_name(Unit::Stiffness);
            particle.kn = Some(self.required("KN", &[], limits::KN, "the normal spring constant", format!("the particle-particle normal spring constant ({unit}), required by DES_COLL_MODEL = 'LSD'"))?);
            wall.kn = Some(self.required(
                "KN_W",
                &[],
                limits::KN,
                "the normal spring constant",
                format!(
                    "the particle-wall normal spring constant ({unit}), required by DES_COLL_MODEL = 'LSD'"
                ),
            )?);
            particle.kt_fac = Some(self.with_default(
                "KT_FAC",
                &[],
                limits::KT_FAC,
                "the tangential to normal stiffness ratio",
            )?);
            wall.kt_fac = Some(self.with_default(
                "KT_W_FAC",
                &[],
                limits::KT_FAC,
                "the tangential to normal stiffness ratio",
            )?);
            particle.etat_fac = Some(self.with_default(
                "DES_ETAT_FAC",
                &[],
                limits::ETAT_FAC,
                "the tangential to normal damping ratio",
            )?);
            wall.etat_fac = Some(self.with_default(
                "DES_ETAT_W_FAC",
                &[],
                limits::ETAT_FAC,
                "the tangential to normal damping ratio",
            )?);
            unused = &["DES_ET_INPUT", "DES_ET_WALL_INPUT", "E_YOUNG", "V_POISSON", "EW_YOUNG", "VW_POISSON"];
        }
        let given: Vec<&str> = unused.iter().copied().filter(|k| self.deck.has(k)).collect();
        if !given.is_empty() {
            self.note(format!(
                "{}: not used by DES_COLL_MODEL = '{model}' (MFIX ignores them too): {}",
                self.origin,
                given.join(", ")
            ));
        }
        // Restitution: in the defaults table when uniform, else per pair / per phase.
        let uniform = |v: &[f64]| v.windows(2).all(|w| w[0] == w[1]);
        let mut pair_tables = Vec::new();
        let (en_uniform, et_uniform) = (uniform(&en), uniform(&et));
        if en_uniform {
            particle.en = en.first().copied();
        }
        if et_uniform {
            particle.et = et.first().copied();
        }
        if !en_uniform || !et_uniform {
            for (lc, (m, l)) in pairs.iter().enumerate() {
                pair_tables.push(RawContactParams {
                    phases: Some([phases[*m].name.clone(), phases[*l].name.clone()]),
                    en: (!en_uniform).then(|| en[lc]),
                    et: (!et_uniform).then(|| et.get(lc).copied()).flatten(),
                    ..Default::default()
                });
            }
        }
        let mut wall_tables = Vec::new();
        let (enw_uniform, etw_uniform) = (uniform(&enw), uniform(&etw));
        if enw_uniform {
            wall.en = enw.first().copied();
        }
        if etw_uniform {
            wall.et = etw.first().copied();
        }
        if !enw_uniform || !etw_uniform {
            for (m, p) in phases.iter().enumerate() {
                wall_tables.push(RawContactParams {
                    phase: Some(p.name.clone()),
                    en: (!enw_uniform).then(|| enw[m]),
                    et: (!etw_uniform).then(|| etw.get(m).copied()).flatten(),
                    ..Default::default()
                });
            }
        }
        let contact = RawContact {
            model: Some(if hertz { "hertz" } else { "lsd" }.into()),
            tangential: None,
            history: None,
            lever_arm: None,
            damping: None,
            clip_attraction: None,
            coulomb: None,
            sizes: Some("phase".into()),
            particle,
            wall,
            pairs: pair_tables,
            walls: wall_tables,
        };
        Ok((contact, hertz))
    }
}
