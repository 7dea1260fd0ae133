//! Particles a script creates: `region` (block, cylinder), `create_box`, the templates
//! (`fix particletemplate/sphere`), their mixtures (`fix particledistribution/discrete`) and
//! `fix insert/pack … insert_every once`, translated to `[[insertions]]` placed all at once.

use super::{Command, Data, Translator, at, number};
use crate::error::CaseError;
use crate::raw::{RawInsertPhase, RawInsertion, RawRegion};

/// A `region` of the script.
#[derive(Debug, Clone)]
pub(super) enum Region {
    Block {
        lo: [f64; 3],
        hi: [f64; 3],
    },
    /// Axis 0, 1 or 2; the centre in the other two axes (in order); radius; the axial range.
    Cylinder {
        axis: usize,
        centre: [f64; 2],
        radius: f64,
        lo: f64,
        hi: f64,
    },
}

/// A `particletemplate/sphere`: its atom type, density and radius.
#[derive(Debug, Clone)]
pub(super) struct Template {
    pub atom_type: usize,
    pub density: f64,
    pub radius: f64,
}

/// A `particledistribution/discrete`: (template id, weight) pairs, by mass or by number.
#[derive(Debug, Clone)]
pub(super) struct Mixture {
    pub parts: Vec<(String, f64)>,
    pub by_mass: bool,
}

/// A `fix insert/pack … insert_every once`, placed at the step its first run starts.
#[derive(Debug, Clone)]
pub(super) struct Pack {
    pub id: String,
    pub mixture: String,
    pub region: String,
    /// `particles_in_region`, `volumefraction_region` or `mass_in_region`, with its value.
    pub target: (String, f64),
    pub velocity: [f64; 3],
    pub seed: u64,
    pub step: u64,
    pub command: Command,
}

impl Translator {
    /// `region ID block x0 x1 y0 y1 z0 z1 [units box|lattice]` or `region ID cylinder x|y|z
    /// C1 C2 R LO HI [units …]` (LIGGGHTS's lattice is 1 unless a `lattice` sets it: the
    /// same numbers).
    pub(super) fn region(&mut self, c: &Command) -> Result<(), CaseError> {
        let w = &c.words;
        let units_ok = |from: usize| match &w[from.min(w.len())..] {
            [] => true,
            [u, v] => u == "units" && (v == "box" || v == "lattice"),
            _ => false,
        };
        let region = match w.get(2).map(String::as_str) {
            Some("block") if units_ok(9) && w.len() >= 9 => {
                let v: Vec<f64> = (3..9).map(|k| number(c, k)).collect::<Result<_, _>>()?;
                let (lo, hi) = ([v[0], v[2], v[4]], [v[1], v[3], v[5]]);
                if (0..3).any(|k| lo[k] >= hi[k]) {
                    return Err(at(c, "a block's lower bounds must lie below its upper ones".into()));
                }
                Region::Block { lo, hi }
            }
            Some("cylinder") if units_ok(9) && w.len() >= 9 => {
                let axis = match w[3].as_str() {
                    "x" => 0,
                    "y" => 1,
                    "z" => 2,
                    other => return Err(at(c, format!("`cylinder {other}`: the axis is x, y or z"))),
                };
                let v: Vec<f64> = (4..9).map(|k| number(c, k)).collect::<Result<_, _>>()?;
                if v[2] <= 0.0 || v[3] >= v[4] {
                    return Err(at(c, "a cylinder needs a positive radius and LO below HI".into()));
                }
                Region::Cylinder { axis, centre: [v[0], v[1]], radius: v[2], lo: v[3], hi: v[4] }
            }
            _ => {
                self.block(
                    c,
                    "grainflow translates `region … block` and `region … cylinder` (with `units box`)",
                );
                return Ok(());
            }
        };
        self.regions.insert(w[1].clone(), region);
        Ok(())
    }

    /// `create_box N REGION`: the box of a block region, N atom types, no particles yet.
    pub(super) fn create_box(&mut self, c: &Command) -> Result<(), CaseError> {
        let n = number(c, 1)?;
        if n < 1.0 || n.fract() != 0.0 || n > 64.0 {
            return Err(at(
                c,
                format!(
                    "`create_box {}`: the number of atom types must be a whole number, 1 to 64",
                    c.words[1]
                ),
            ));
        }
        let name = c.words.get(2).ok_or_else(|| at(c, "`create_box` needs a region".into()))?;
        let Some(Region::Block { lo, hi }) = self.regions.get(name).cloned() else {
            return Err(at(c, format!("`create_box`: `{name}` is not a block region defined before it")));
        };
        if self.data.is_some() {
            return Err(at(c, "the box is made already (`read_data` or `create_box` before)".into()));
        }
        self.data = Some(Data {
            file: String::new(),
            lo,
            hi,
            atoms: Vec::new(),
            first_of_type: vec![None; n as usize],
        });
        Ok(())
    }

    /// `fix ID all particletemplate/sphere SEED atom_type T density constant RHO radius
    /// constant R`.
    pub(super) fn template(&mut self, c: &Command) -> Result<(), CaseError> {
        let w: Vec<&str> = c.words.iter().map(String::as_str).collect();
        let key = |k: &str| w.iter().position(|x| *x == k);
        let (Some(t), Some(d), Some(r)) = (key("atom_type"), key("density"), key("radius")) else {
            return Err(at(
                c,
                "write `particletemplate/sphere SEED atom_type T density constant RHO radius constant R`"
                    .into(),
            ));
        };
        if w.get(d + 1) != Some(&"constant") || w.get(r + 1) != Some(&"constant") {
            self.block(c, "only `constant` densities and radii of a template are translated (a distribution of templates gives sizes)");
            return Ok(());
        }
        let known = [t, t + 1, d, d + 1, d + 2, r, r + 1, r + 2];
        if let Some(k) = (5..w.len()).find(|k| !known.contains(k)) {
            self.block(c, format!("`particletemplate/sphere … {}` is not translated", w[k]));
        }
        let (atom_type, density, radius) = (number(c, t + 1)?, number(c, d + 2)?, number(c, r + 2)?);
        if atom_type < 1.0 || atom_type.fract() != 0.0 || density <= 0.0 || radius <= 0.0 {
            return Err(at(c, "a template needs an atom type ≥ 1 and a positive density and radius".into()));
        }
        self.templates.insert(w[1].to_string(), Template { atom_type: atom_type as usize, density, radius });
        Ok(())
    }

    /// `fix ID all particledistribution/discrete[/massbased|/numberbased] SEED N T1 W1 …`.
    pub(super) fn mixture(&mut self, c: &Command, style: &str) -> Result<(), CaseError> {
        let w = &c.words;
        let n = number(c, 5)?;
        if n < 1.0 || n.fract() != 0.0 || w.len() != 6 + 2 * n as usize {
            return Err(at(c, format!("`{style} SEED N …` needs N template–weight pairs")));
        }
        let mut parts = Vec::new();
        for k in 0..n as usize {
            let (id, weight) = (w[6 + 2 * k].clone(), number(c, 7 + 2 * k)?);
            if !self.templates.contains_key(&id) {
                return Err(at(c, format!("`{id}`: no `particletemplate/sphere` of that id before it")));
            }
            if weight < 0.0 {
                return Err(at(c, format!("the weight of `{id}` is negative")));
            }
            parts.push((id, weight));
        }
        if parts.iter().all(|p| p.1 == 0.0) {
            return Err(at(c, "every weight is zero".into()));
        }
        self.mixtures.insert(w[1].clone(), Mixture { parts, by_mass: !style.ends_with("numberbased") });
        Ok(())
    }

    /// `fix ID all insert/pack seed S distributiontemplate D insert_every once region R
    /// particles_in_region N|volumefraction_region F|mass_in_region M [vel constant VX VY VZ]
    /// [maxattempt A] [overlapcheck yes] [all_in yes|no] [verbose no]`.
    pub(super) fn insert_pack(&mut self, c: &Command, group: &str) -> Result<(), CaseError> {
        let w: Vec<&str> = c.words.iter().map(String::as_str).collect();
        if group != "all" {
            self.block(c, "an insertion into a group other than `all` is not translated");
        }
        let (mut mixture, mut region, mut target, mut every, mut velocity, mut seed) =
            (None, None, None, None, [0.0; 3], 0u64);
        let mut k = 4;
        while k < w.len() {
            let value = w.get(k + 1).copied().unwrap_or("");
            match w[k] {
                "seed" => seed = number(c, k + 1)? as u64,
                "distributiontemplate" => mixture = Some(value.to_string()),
                "region" => region = Some(value.to_string()),
                "insert_every" => every = Some(value.to_string()),
                "particles_in_region" | "volumefraction_region" | "mass_in_region" => {
                    target = Some((w[k].to_string(), number(c, k + 1)?));
                }
                "maxattempt" | "verbose" | "all_in" | "ntry_mc" => {}
                "overlapcheck" if value == "yes" => {}
                "vel" if value == "constant" => {
                    velocity = [number(c, k + 2)?, number(c, k + 3)?, number(c, k + 4)?];
                    k += 3;
                }
                other => {
                    self.block(c, format!("`insert/pack … {other} {value}` is not translated"));
                    return Ok(());
                }
            }
            k += 2;
        }
        if every.as_deref() != Some("once") {
            self.block(c, "`insert/pack` repeated (`insert_every N`) fills its region up to its target again and again, which is not yet translated: `insert_every once` is");
            return Ok(());
        }
        let (Some(mixture), Some(region), Some(target)) = (mixture, region, target) else {
            return Err(at(c, "`insert/pack` needs `distributiontemplate`, `region` and one of `particles_in_region`, `volumefraction_region`, `mass_in_region`".into()));
        };
        if !self.mixtures.contains_key(&mixture) {
            return Err(at(
                c,
                format!(
                    "`distributiontemplate {mixture}`: no `particledistribution/discrete` of that id before it"
                ),
            ));
        }
        if !self.regions.contains_key(&region) {
            return Err(at(c, format!("`region {region}`: no region of that id before it")));
        }
        if self.data.as_ref().is_some_and(|d| !d.atoms.is_empty()) {
            self.block(c, "`insert/pack` fills its region up to its target, counting the particles there: with particles of a data file that is not yet translated");
        }
        let step = self.steps;
        self.packs.push(Pack {
            id: c.words[1].clone(),
            mixture,
            region,
            target,
            velocity,
            seed,
            step,
            command: c.clone(),
        });
        Ok(())
    }

    /// The `[[insertions]]`, each at the time of the step it is placed at (`dt`).
    pub(super) fn raw_insertions(&self, dt: f64) -> Vec<RawInsertion> {
        self.packs
            .iter()
            .map(|p| {
                let m = &self.mixtures[&p.mixture];
                let (kind, value) = (&p.target.0, p.target.1);
                RawInsertion {
                    name: Some(p.id.clone()),
                    region: Some(raw_region(&self.regions[&p.region])),
                    file: None,
                    count: (kind == "particles_in_region").then_some(value as u64),
                    volume_fraction: (kind == "volumefraction_region").then_some(value),
                    mass: (kind == "mass_in_region").then_some(value),
                    at: (p.step > 0).then_some(p.step as f64 * dt),
                    rate: None,
                    mass_rate: None,
                    start: None,
                    every: None,
                    velocity: Some(p.velocity),
                    seed: Some(p.seed),
                    plane_z: None,
                    fractions_by: Some(if m.by_mass { "mass" } else { "number" }.into()),
                    phases: self.insert_phases(m),
                }
            })
            .collect()
    }

    /// One `[[insertions.phases]]` a type: its share of the weights, and its templates' sizes
    /// as a table weighted as the mixture is.
    fn insert_phases(&self, m: &Mixture) -> Vec<RawInsertPhase> {
        let total: f64 = m.parts.iter().map(|p| p.1).sum();
        let mut types: Vec<usize> = m.parts.iter().map(|p| self.templates[&p.0].atom_type).collect();
        types.sort_unstable();
        types.dedup();
        types
            .into_iter()
            .map(|t| {
                let own: Vec<(f64, f64)> = m
                    .parts
                    .iter()
                    .filter(|p| self.templates[&p.0].atom_type == t)
                    .map(|p| (2.0 * self.templates[&p.0].radius, p.1))
                    .collect();
                let share: f64 = own.iter().map(|p| p.1).sum();
                let single = own.len() == 1;
                RawInsertPhase {
                    phase: Some(format!("type{t}")),
                    fraction: Some(share / total),
                    distribution: Some(if single { "constant" } else { "table" }.into()),
                    diameter: single.then_some(own[0].0),
                    mean: None,
                    sigma: None,
                    min_diameter: None,
                    max_diameter: None,
                    diameters: (!single).then(|| own.iter().map(|p| p.0).collect()),
                    weights: (!single).then(|| own.iter().map(|p| p.1 / share).collect()),
                    weights_by: (!single).then(|| if m.by_mass { "mass" } else { "number" }.into()),
                    cdf: None,
                }
            })
            .collect()
    }

    /// Each type's diameter and density from its first template, where the data file gives
    /// none; a type whose templates differ in density is refused.
    pub(super) fn template_phases(&mut self) {
        let Some(data) = self.data.as_mut() else { return };
        let mut blockers = Vec::new();
        for (id, t) in &self.templates {
            let Some(slot) = data.first_of_type.get_mut(t.atom_type - 1) else {
                blockers.push(CaseError::Syntax(format!(
                    "template `{id}`: atom type {} is beyond the {} types of the box",
                    t.atom_type,
                    data.first_of_type.len()
                )));
                continue;
            };
            match slot {
                None => *slot = Some((2.0 * t.radius, t.density)),
                Some((_, rho)) if *rho != t.density => blockers.push(CaseError::Syntax(format!(
                    "template `{id}`: atom type {} has two densities ({rho} and {}); grainflow has one density a phase",
                    t.atom_type, t.density
                ))),
                Some(_) => {}
            }
        }
        self.blockers.extend(blockers);
    }

    /// `unfix ID` of an `insert/pack … once`, which has placed its particles already. True if
    /// ID was one.
    pub(super) fn unfix_pack(&mut self, id: &str) -> bool {
        self.packs.iter().any(|p| p.id == id)
    }
}

fn raw_region(r: &Region) -> RawRegion {
    let none = RawRegion {
        kind: None,
        min: None,
        max: None,
        base: None,
        axis: None,
        length: None,
        radius: None,
        mesh: None,
    };
    match *r {
        Region::Block { lo, hi } => {
            RawRegion { kind: Some("box".into()), min: Some(lo), max: Some(hi), ..none }
        }
        Region::Cylinder { axis, centre, radius, lo, hi } => {
            let mut base = [0.0; 3];
            let mut dir = [0.0; 3];
            let others: Vec<usize> = (0..3).filter(|&k| k != axis).collect();
            base[others[0]] = centre[0];
            base[others[1]] = centre[1];
            base[axis] = lo;
            dir[axis] = 1.0;
            RawRegion {
                kind: Some("cylinder".into()),
                base: Some(base),
                axis: Some(dir),
                length: Some(hi - lo),
                radius: Some(radius),
                ..none
            }
        }
    }
}
