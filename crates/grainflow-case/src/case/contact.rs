//! `[contact]`: the contact law, its default tables and the per-pair and per-wall overrides.

use super::fields::{check, choose, require};
use super::materials::{material_index, phase_index};
use crate::error::CaseError;
use crate::raw::{RawContact, RawContactParams};
use grainflow::contact::limits::{self, Range};
use grainflow::contact::{
    ContactLaw, ContactParams, ContactSizes, CoulombCap, HistoryFrame, LeverArm, NormalDamping, NormalModel,
    TangentialModel,
};
use grainflow::{Phase, WallMaterial};

/// The law and its parameters for every phase pair and every phase against every wall
/// material.
pub(super) struct Tables {
    pub law: ContactLaw,
    pub pair_params: Vec<ContactParams>,
    pub wall_params: Vec<ContactParams>,
}

/// `[contact]` against the phases and wall materials; `has_walls` says whether any plane or
/// mesh wall exists (without one, no wall tables are built and the wall materials are
/// cleared).
pub(super) fn contact(
    raw: Option<RawContact>,
    phases: &[Phase],
    wall_materials: &mut Vec<WallMaterial>,
    has_walls: bool,
    warnings: &mut Vec<String>,
) -> Result<Tables, CaseError> {
    let contact = require(raw, "top level", "[contact]", "the contact model and its parameters")?;
    let normal = choose(
        "[contact]",
        "model",
        contact.model.as_deref(),
        NormalModel::LinearSpringDashpot,
        NormalModel::CHOICES,
    )?;
    let tangential = choose(
        "[contact]",
        "tangential",
        contact.tangential.as_deref(),
        TangentialModel::MfixTotal,
        TangentialModel::CHOICES,
    )?;
    let history = choose(
        "[contact]",
        "history",
        contact.history.as_deref(),
        HistoryFrame::Mfix,
        &[
            ("mfix", HistoryFrame::Mfix),
            ("project", HistoryFrame::Project),
            ("rotate", HistoryFrame::Rotate),
            ("liggghts", HistoryFrame::Liggghts),
        ],
    )?;
    let lever = choose(
        "[contact]",
        "lever_arm",
        contact.lever_arm.as_deref(),
        LeverArm::RadicalPlane,
        &[
            ("mfix", LeverArm::RadicalPlane),
            ("radius", LeverArm::Radius),
            ("lammps_granular", LeverArm::LammpsGranular),
            ("liggghts", LeverArm::Liggghts),
        ],
    )?;
    let damping = choose(
        "[contact]",
        "damping",
        contact.damping.as_deref(),
        NormalDamping::Mfix,
        &[
            ("mfix", NormalDamping::Mfix),
            ("exact_restitution", NormalDamping::ExactRestitution),
            ("mass_velocity", NormalDamping::MassVelocity),
            ("tsuji", NormalDamping::Tsuji),
            ("liggghts", NormalDamping::Liggghts),
        ],
    )?;
    let clip_attraction = contact.clip_attraction.unwrap_or(false);
    let coulomb = choose(
        "[contact]",
        "coulomb",
        contact.coulomb.as_deref(),
        CoulombCap::Mfix,
        &[("mfix", CoulombCap::Mfix), ("lammps", CoulombCap::Lammps), ("liggghts", CoulombCap::Liggghts)],
    )?;
    let sizes = choose(
        "[contact]",
        "sizes",
        contact.sizes.as_deref(),
        ContactSizes::Own,
        &[("own", ContactSizes::Own), ("phase", ContactSizes::Phase)],
    )?;
    let law = ContactLaw { normal, tangential, history, lever, damping, clip_attraction, coulomb, sizes };
    if normal == NormalModel::Jkr {
        // The damping JKR takes (LAMMPS's examples pair `jkr` with `damping tsuji`), and no
        // clipping, which would remove its adhesion.
        if damping != NormalDamping::Tsuji {
            return Err(CaseError::invalid(
                "[contact]",
                "damping",
                format!("{:?}", contact.damping.as_deref().unwrap_or("mfix")),
                "the jkr model takes damping = \"tsuji\" (LAMMPS's pair granular pairs jkr with it)",
            ));
        }
        if clip_attraction {
            return Err(CaseError::invalid(
                "[contact]",
                "clip_attraction",
                "true",
                "the jkr model is attractive by design: clipping the normal force at zero would remove its adhesion",
            ));
        }
    }
    if normal.elastic() {
        let model = law.normal_name();
        for p in phases {
            let table = format!("[[phases]] '{}'", p.name);
            require(
                p.youngs_modulus,
                &table,
                "youngs_modulus",
                &format!("Young's modulus in Pa, required by the {model} model"),
            )?;
            require(
                p.poisson_ratio,
                &table,
                "poisson_ratio",
                &format!("Poisson's ratio, required by the {model} model"),
            )?;
        }
        if has_walls {
            for m in wall_materials.iter() {
                let table = format!("[[wall_materials]] '{}'", m.name);
                require(
                    m.youngs_modulus,
                    &table,
                    "youngs_modulus",
                    &format!("Young's modulus in Pa, required by the {model} model for walls"),
                )?;
                require(
                    m.poisson_ratio,
                    &table,
                    "poisson_ratio",
                    &format!("Poisson's ratio, required by the {model} model for walls"),
                )?;
            }
        }
    }
    for (table, t, is_pair) in
        [("[contact.particle]", &contact.particle, None), ("[contact.wall]", &contact.wall, None)]
            .into_iter()
            .chain(contact.pairs.iter().map(|t| ("[[contact.pairs]]", t, Some(true))))
            .chain(contact.walls.iter().map(|t| ("[[contact.walls]]", t, Some(false))))
    {
        let misplaced = match is_pair {
            None => [
                ("phases", t.phases.is_some()),
                ("phase", t.phase.is_some()),
                ("material", t.material.is_some()),
            ]
            .into_iter()
            .find(|x| x.1),
            Some(true) => {
                [("phase", t.phase.is_some()), ("material", t.material.is_some())].into_iter().find(|x| x.1)
            }
            Some(false) => [("phases", t.phases.is_some())].into_iter().find(|x| x.1),
        };
        if let Some((key, _)) = misplaced {
            return Err(CaseError::invalid(
                table,
                key,
                "(given)",
                "this key selects a pair: `phases` belongs in [[contact.pairs]], `phase` and `material` in [[contact.walls]]",
            ));
        }
        check_params(table, t, law, warnings)?;
    }
    let n = phases.len();
    let mut pair_tables: Vec<Option<&RawContactParams>> = vec![None; n * (n + 1) / 2];
    for t in &contact.pairs {
        let table = "[[contact.pairs]]";
        let [a, b] = require(t.phases.clone(), table, "phases", "the two phase names of the pair")?;
        let (ia, ib) = (phase_index(phases, &a, table, "phases")?, phase_index(phases, &b, table, "phases")?);
        let slot = &mut pair_tables[grainflow::contact::coefficients::upper_triangle_index(ia, ib, n)];
        if slot.is_some() {
            return Err(CaseError::invalid(
                table,
                "phases",
                format!("[\"{a}\", \"{b}\"]"),
                "each phase pair may appear only once",
            ));
        }
        *slot = Some(t);
    }
    let nw = if !has_walls { 0 } else { wall_materials.len() };
    let mut wall_tables: Vec<Option<&RawContactParams>> = vec![None; n * nw];
    for t in &contact.walls {
        let table = "[[contact.walls]]";
        let ph = require(t.phase.clone(), table, "phase", "the phase name")?;
        let ip = phase_index(phases, &ph, table, "phase")?;
        let iw = material_index(wall_materials, &t.material, table, "material")?;
        if nw == 0 {
            continue;
        }
        let slot = &mut wall_tables[ip * nw + iw];
        if slot.is_some() {
            return Err(CaseError::invalid(
                table,
                "phase",
                format!("\"{ph}\""),
                "each phase and wall material may appear only once",
            ));
        }
        *slot = Some(t);
    }
    let mut pair_params = Vec::with_capacity(pair_tables.len());
    for m in 0..n {
        for l in m..n {
            let over = pair_tables[grainflow::contact::coefficients::upper_triangle_index(m, l, n)];
            let what = format!("phase pair '{}'-'{}'", phases[m].name, phases[l].name);
            pair_params.push(layer(over, &contact.particle, law, "[contact.particle]", &what)?);
        }
    }
    let mut wall_params = Vec::with_capacity(wall_tables.len());
    for m in 0..n {
        for w in 0..nw {
            let what =
                format!("phase '{}' against wall material '{}'", phases[m].name, wall_materials[w].name);
            wall_params.push(layer(wall_tables[m * nw + w], &contact.wall, law, "[contact.wall]", &what)?);
        }
    }
    if nw == 0 {
        wall_materials.clear();
    }
    Ok(Tables { law, pair_params, wall_params })
}

/// Range checks of one contact table, and warnings for keys the model does not use.
fn check_params(
    table: &str,
    t: &RawContactParams,
    law: ContactLaw,
    warnings: &mut Vec<String>,
) -> Result<(), CaseError> {
    let checks: [(&str, Option<f64>, Range); 10] = [
        ("kn", t.kn, limits::KN),
        ("kt_fac", t.kt_fac, limits::KT_FAC),
        ("etat_fac", t.etat_fac, limits::ETAT_FAC),
        ("en", t.en, limits::EN),
        ("et", t.et, limits::ET),
        ("mu", t.mu, limits::MU),
        ("mu_roll", t.mu_roll, limits::MU_ROLL),
        ("gamma_n", t.gamma_n, limits::GAMMA),
        ("gamma_t", t.gamma_t, limits::GAMMA),
        ("surface_energy", t.surface_energy, limits::SURFACE_ENERGY),
    ];
    for (key, v, r) in checks {
        if let Some(v) = v {
            check(r, table, key, v)?;
        }
    }
    let unused: &[(&str, bool)] = match law.normal {
        NormalModel::LinearSpringDashpot => {
            &[("et", t.et.is_some()), ("surface_energy", t.surface_energy.is_some())]
        }
        NormalModel::Hertz => &[
            ("kn", t.kn.is_some()),
            ("kt_fac", t.kt_fac.is_some()),
            ("surface_energy", t.surface_energy.is_some()),
        ],
        NormalModel::Jkr => &[
            ("kn", t.kn.is_some()),
            ("kt_fac", t.kt_fac.is_some()),
            ("et", t.et.is_some()),
            ("hertz_kn", t.hertz_kn.is_some()),
            ("hertz_kt", t.hertz_kt.is_some()),
        ],
    };
    for (key, given) in unused {
        if *given {
            warnings
                .push(format!("{table}: `{key}` is not used by the {} model (ignored)", law.normal_name()));
        }
    }
    Ok(())
}

/// Layers an override table over the defaults table over MFIX's built-in defaults, and checks
/// that the model's required values are present.
fn layer(
    over: Option<&RawContactParams>,
    base: &RawContactParams,
    law: ContactLaw,
    base_table: &str,
    what: &str,
) -> Result<ContactParams, CaseError> {
    let d = ContactParams::default();
    let pick = |f: fn(&RawContactParams) -> Option<f64>| over.and_then(f).or_else(|| f(base));
    let p = ContactParams {
        kn: pick(|t| t.kn),
        kt_fac: pick(|t| t.kt_fac).unwrap_or(d.kt_fac),
        // LIGGGHTS's tangential damping is on unless switched off (`etat_fac = 0`).
        etat_fac: pick(|t| t.etat_fac).unwrap_or(if law.damping == NormalDamping::Liggghts {
            1.0
        } else {
            d.etat_fac
        }),
        en: pick(|t| t.en).unwrap_or(d.en),
        et: pick(|t| t.et),
        mu: pick(|t| t.mu).unwrap_or(d.mu),
        mu_roll: pick(|t| t.mu_roll).unwrap_or(d.mu_roll),
        gamma_n: pick(|t| t.gamma_n),
        gamma_t: pick(|t| t.gamma_t),
        hertz_kn: pick(|t| t.hertz_kn),
        hertz_kt: pick(|t| t.hertz_kt),
        surface_energy: pick(|t| t.surface_energy),
    };
    match law.normal {
        NormalModel::LinearSpringDashpot if p.kn.is_none() => Err(CaseError::missing(
            base_table,
            "kn",
            format!("normal stiffness in N/m for the {what}; set it there or in an override table"),
        )),
        NormalModel::Hertz
            if p.et.is_none()
                && matches!(law.damping, NormalDamping::Mfix | NormalDamping::ExactRestitution) =>
        {
            Err(CaseError::missing(
                base_table,
                "et",
                format!("tangential restitution for the {what}, required by the hertz model"),
            ))
        }
        NormalModel::Jkr if p.surface_energy.is_none() => Err(CaseError::missing(
            base_table,
            "surface_energy",
            format!(
                "surface energy γ in J/m² for the {what}, required by the jkr model (LAMMPS's: the pull-off force is 3πγR*)"
            ),
        )),
        NormalModel::LinearSpringDashpot | NormalModel::Hertz | NormalModel::Jkr => Ok(p),
    }
}
