//! `[[insertions]]`, `[[outlets]]` and `[domain] leaving` → the engine's insertions and
//! outlets, with messages naming table, key and value.

use super::fields::{check, vec3};
use crate::error::CaseError;
use crate::raw::{RawInsertPhase, RawInsertion, RawOutlet, RawRegion};
use grainflow::contact::limits;
use grainflow::insertion::psd::{Basis, Mixture, MixturePart, SizeDistribution};
use grainflow::insertion::region::Region;
use grainflow::insertion::{Amount, Insertion, Outlet, OutletShape, Rate, Schedule};
use grainflow::mesh::MeshWall;
use grainflow::state::ParticleInit;
use grainflow::{Phase, Vec3};

/// Default time between a rate insertion's batches, s.
pub const DEFAULT_EVERY: f64 = 0.01;

/// The shallowest column of a `face` region, in largest diameters.
pub const FACE_MIN_DEPTH: f64 = 2.0;

/// The domain box and its periodic axes, which regions are checked against.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Domain {
    pub lo: Vec3,
    pub hi: Vec3,
    pub periodic: [bool; 3],
}

impl Domain {
    /// The bounds' slack: rounding of coordinates of the domain's size.
    fn slack(&self) -> f64 {
        1e-9 * (self.hi - self.lo)
            .abs()
            .max_element()
            .max(self.lo.abs().max_element())
            .max(self.hi.abs().max_element())
    }

    fn text(&self) -> String {
        format!("[{:?}, {:?}]", self.lo.to_array(), self.hi.to_array())
    }
}

/// The key, and its value, that place a region where it is (for messages).
fn placing_key(r: &RawRegion) -> (&'static str, String) {
    let v = |x: Option<[f64; 3]>| x.map_or_else(String::new, |x| format!("{x:?}"));
    match r.kind.as_deref() {
        Some("box") => ("max", v(r.max)),
        Some("mesh") => ("mesh", format!("\"{}\"", r.mesh.as_deref().unwrap_or(""))),
        Some("cylinder") => ("radius", format!("{}", r.radius.unwrap_or(0.0))),
        _ => ("base", v(r.base)),
    }
}

/// An insertion's region must lie inside the domain box (on a periodic axis: meet it), and its
/// largest particle must fit in it: else particles placed there would leave the domain at
/// once, or none of that size could ever be placed.
fn check_insertion_region(
    region: &Region,
    raw: &RawRegion,
    table: &str,
    domain: &Domain,
    max_diameter: f64,
) -> Result<(), CaseError> {
    let (lo, hi) = region.bounds();
    let slack = domain.slack();
    let (key, value) = placing_key(raw);
    let kind = raw.kind.as_deref().unwrap_or("box");
    let outside = (0..3).find(|&k| {
        if domain.periodic[k] {
            !(lo[k] < domain.hi[k] && hi[k] > domain.lo[k])
        } else {
            lo[k] < domain.lo[k] - slack || hi[k] > domain.hi[k] + slack
        }
    });
    if let Some(k) = outside {
        let axis = ["x", "y", "z"][k];
        let what = if kind == "face" {
            "the stream's column upstream of the face (|v|·every deep, at least two largest diameters)"
        } else {
            "the region"
        };
        return Err(CaseError::invalid(
            table,
            key,
            value,
            format!(
                "{what} spans [{:?}, {:?}] m, which reaches outside the domain {} along {axis}: particles placed there would leave the domain at once; keep the region inside [domain]",
                lo.to_array(),
                hi.to_array(),
                domain.text()
            ),
        ));
    }
    // The narrowest width a whole sphere must fit in (a periodic axis the region spans
    // repeats it, so it does not bound the sphere).
    let spans = |k: usize| domain.periodic[k] && lo[k] <= domain.lo[k] && hi[k] >= domain.hi[k];
    let narrowest = match region {
        Region::Box { lo, hi } => {
            (0..3).filter(|&k| !spans(k)).map(|k| hi[k] - lo[k]).fold(f64::INFINITY, f64::min)
        }
        Region::Cylinder { length, radius, axis, .. } => {
            let along = (0..3).find(|&k| axis[k].abs() == 1.0 && spans(k));
            if along.is_some() { 2.0 * radius } else { (2.0 * radius).min(*length) }
        }
        Region::Mesh(_) => f64::INFINITY,
    };
    if max_diameter >= narrowest {
        return Err(CaseError::invalid(
            table,
            key,
            value,
            format!(
                "the region is {narrowest:e} m across at its narrowest, not more than the largest diameter {max_diameter:e} m: no particle of that size could ever be placed in it"
            ),
        ));
    }
    Ok(())
}

/// The meshes of the case, by name, for mesh regions.
pub(crate) struct Meshes<'a> {
    pub walls: &'a [MeshWall],
    pub names: &'a [String],
}

fn positive(table: &str, key: &str, v: f64) -> Result<f64, CaseError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(CaseError::invalid(table, key, v, "must be a positive number"))
    }
}

fn finite(table: &str, key: &str, v: f64) -> Result<f64, CaseError> {
    if v.is_finite() { Ok(v) } else { Err(CaseError::invalid(table, key, v, "must be a finite number")) }
}

/// A region table.
/// A stream's motion, for a `face` region: the insertion's velocity, its batches' interval
/// and its particles' largest diameter.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Stream {
    velocity: Vec3,
    every: Option<f64>,
    max_diameter: f64,
}

pub(crate) fn region(
    r: &RawRegion,
    table: &str,
    meshes: &Meshes,
    stream: Option<Stream>,
) -> Result<Region, CaseError> {
    let kind = r
        .kind
        .as_deref()
        .ok_or_else(|| CaseError::missing(table, "kind", "\"box\", \"cylinder\", \"mesh\" or \"face\""))?;
    let given = |k: &str| match k {
        "min" => r.min.is_some(),
        "max" => r.max.is_some(),
        "base" => r.base.is_some(),
        "axis" => r.axis.is_some(),
        "length" => r.length.is_some(),
        "radius" => r.radius.is_some(),
        "mesh" => r.mesh.is_some(),
        _ => false,
    };
    let own: &[&str] = match kind {
        "box" => &["min", "max"],
        "cylinder" => &["base", "axis", "length", "radius"],
        "mesh" => &["mesh"],
        "face" => &["base", "radius"],
        other => {
            return Err(CaseError::invalid(
                table,
                "kind",
                format!("\"{other}\""),
                "must be \"box\", \"cylinder\", \"mesh\" or \"face\"",
            ));
        }
    };
    if let Some(k) = ["min", "max", "base", "axis", "length", "radius", "mesh"]
        .iter()
        .find(|k| given(k) && !own.contains(k))
    {
        return Err(CaseError::invalid(
            table,
            *k,
            "given",
            format!("not a key of kind = \"{kind}\" (its keys: {})", own.join(", ")),
        ));
    }
    let need = |k: &str| CaseError::missing(table, k, format!("required by kind = \"{kind}\""));
    let region = match kind {
        "box" => {
            let lo = vec3(r.min.ok_or_else(|| need("min"))?, table, "min")?;
            let hi = vec3(r.max.ok_or_else(|| need("max"))?, table, "max")?;
            if !hi.cmpgt(lo).all() {
                return Err(CaseError::invalid(
                    table,
                    "max",
                    format!("{:?}", hi.to_array()),
                    format!("every component must exceed min = {:?}", lo.to_array()),
                ));
            }
            Region::Box { lo, hi }
        }
        "cylinder" => {
            let base = vec3(r.base.ok_or_else(|| need("base"))?, table, "base")?;
            let axis = vec3(r.axis.ok_or_else(|| need("axis"))?, table, "axis")?;
            if axis.length_squared() == 0.0 {
                return Err(CaseError::invalid(table, "axis", "[0, 0, 0]", "must not be zero"));
            }
            let length = positive(table, "length", r.length.ok_or_else(|| need("length"))?)?;
            let radius = positive(table, "radius", r.radius.ok_or_else(|| need("radius"))?)?;
            Region::cylinder(base, axis, length, radius)
        }
        "face" => {
            // A stream through a disc: each batch fills the column upstream of the face that
            // the stream carries through it before the next batch (at least one particle deep).
            let (velocity, every, max_d) = match stream {
                Some(Stream { velocity, every: Some(every), max_diameter })
                    if velocity.length_squared() > 0.0 =>
                {
                    (velocity, every, max_diameter)
                }
                _ => {
                    return Err(CaseError::invalid(
                        table,
                        "kind",
                        "\"face\"",
                        "is the region of a stream: an insertion at a rate (rate or mass_rate) with a non-zero velocity, through the face along it",
                    ));
                }
            };
            let centre = vec3(r.base.ok_or_else(|| need("base"))?, table, "base")?;
            let radius = positive(table, "radius", r.radius.ok_or_else(|| need("radius"))?)?;
            // At least two largest diameters, as an MFIX mass inflow's layer: a column one
            // diameter deep holds no whole sphere with room to spare, so nothing could be placed.
            let depth = (velocity.length() * every).max(FACE_MIN_DEPTH * max_d);
            let along = velocity.normalize();
            Region::cylinder(centre - depth * along, along, depth, radius)
        }
        _ => {
            let name = r.mesh.as_deref().ok_or_else(|| need("mesh"))?;
            let Some(k) = meshes.names.iter().position(|n| n == name) else {
                let names: Vec<String> = meshes.names.iter().map(|n| format!("\"{n}\"")).collect();
                return Err(CaseError::invalid(
                    table,
                    "mesh",
                    format!("\"{name}\""),
                    if names.is_empty() {
                        "the case has no [[meshes]]".to_string()
                    } else {
                        format!("not a mesh; the meshes are {}", names.join(", "))
                    },
                ));
            };
            Region::mesh(&meshes.walls[k].mesh)
        }
    };
    region.check().map_err(|e| CaseError::Geometry(format!("{table}: {e}")))?;
    Ok(region)
}

/// One phase's size distribution.
pub(crate) fn sizes(p: &RawInsertPhase, table: &str, phase: &Phase) -> Result<SizeDistribution, CaseError> {
    let kind = p.distribution.as_deref().unwrap_or("constant");
    let keys: [(&str, bool); 9] = [
        ("diameter", p.diameter.is_some()),
        ("mean", p.mean.is_some()),
        ("sigma", p.sigma.is_some()),
        ("min_diameter", p.min_diameter.is_some()),
        ("max_diameter", p.max_diameter.is_some()),
        ("diameters", p.diameters.is_some()),
        ("weights", p.weights.is_some()),
        ("weights_by", p.weights_by.is_some()),
        ("cdf", p.cdf.is_some()),
    ];
    let own: &[&str] = match kind {
        "constant" => &["diameter"],
        "uniform" => &["min_diameter", "max_diameter"],
        "normal" | "lognormal" => &["mean", "sigma", "min_diameter", "max_diameter"],
        "table" => &["diameters", "weights", "weights_by"],
        "cdf" => &["diameters", "cdf"],
        other => {
            return Err(CaseError::invalid(
                table,
                "distribution",
                format!("\"{other}\""),
                "must be \"constant\", \"uniform\", \"normal\", \"lognormal\", \"table\" or \"cdf\"",
            ));
        }
    };
    if let Some((k, _)) = keys.iter().find(|(k, given)| *given && !own.contains(k)) {
        return Err(CaseError::invalid(
            table,
            *k,
            "given",
            format!("not a key of distribution = \"{kind}\" (its keys: {})", own.join(", ")),
        ));
    }
    let need = |k: &str| CaseError::missing(table, k, format!("required by distribution = \"{kind}\", m"));
    let d = |k: &str, v: Option<f64>| -> Result<f64, CaseError> {
        check(limits::DIAMETER, table, k, v.ok_or_else(|| need(k))?)
    };
    let s = match kind {
        "constant" => SizeDistribution::Constant {
            diameter: check(limits::DIAMETER, table, "diameter", p.diameter.unwrap_or(phase.diameter))?,
        },
        "uniform" => SizeDistribution::Uniform {
            min: d("min_diameter", p.min_diameter)?,
            max: d("max_diameter", p.max_diameter)?,
        },
        "normal" | "lognormal" => {
            let (mean, min, max) =
                (d("mean", p.mean)?, d("min_diameter", p.min_diameter)?, d("max_diameter", p.max_diameter)?);
            let sigma = positive(table, "sigma", p.sigma.ok_or_else(|| need("sigma"))?)?;
            if kind == "normal" {
                SizeDistribution::Normal { mean, sigma, min, max }
            } else {
                SizeDistribution::LogNormal { mean, sigma, min, max }
            }
        }
        "cdf" => {
            let diameters = p.diameters.clone().ok_or_else(|| need("diameters"))?;
            for &x in &diameters {
                check(limits::DIAMETER, table, "diameters", x)?;
            }
            let cdf =
                p.cdf.clone().ok_or_else(|| CaseError::missing(table, "cdf", "P(D ≤ d) at each diameter"))?;
            SizeDistribution::Cdf { diameters, cdf }
        }
        _ => {
            let diameters = p.diameters.clone().ok_or_else(|| need("diameters"))?;
            for &x in &diameters {
                check(limits::DIAMETER, table, "diameters", x)?;
            }
            let fractions = p
                .weights
                .clone()
                .ok_or_else(|| CaseError::missing(table, "weights", "one share per diameter"))?;
            let basis = basis(p.weights_by.as_deref(), table, "weights_by")?;
            SizeDistribution::Table { diameters, fractions, basis }
        }
    };
    s.check().map_err(|e| CaseError::invalid(table, "distribution", format!("\"{kind}\""), e.to_string()))?;
    Ok(s)
}

fn basis(v: Option<&str>, table: &str, key: &str) -> Result<Basis, CaseError> {
    match v {
        None | Some("number") => Ok(Basis::Number),
        Some("mass") => Ok(Basis::Mass),
        Some(other) => {
            Err(CaseError::invalid(table, key, format!("\"{other}\""), "must be \"number\" or \"mass\""))
        }
    }
}

/// The `[[insertions]]` tables.
pub(crate) fn insertions(
    raw: &[RawInsertion],
    phases: &[Phase],
    meshes: &Meshes,
    t_start: f64,
    domain: &Domain,
    read_particles: &dyn Fn(&str) -> Result<Vec<ParticleInit>, CaseError>,
) -> Result<Vec<Insertion>, CaseError> {
    let mut out: Vec<Insertion> = Vec::with_capacity(raw.len());
    for (k, ins) in raw.iter().enumerate() {
        let table = format!("[[insertions]] #{}", k + 1);
        let name = ins
            .name
            .clone()
            .ok_or_else(|| CaseError::missing(&table, "name", "a name for messages and outputs"))?;
        if out.iter().any(|i| i.name == name) {
            return Err(CaseError::invalid(
                &table,
                "name",
                format!("\"{name}\""),
                "is used by an earlier insertion",
            ));
        }
        let table = format!("[[insertions]] '{name}'");
        if let Some(file) = &ins.file {
            out.push(given(ins, &table, name, file, t_start, read_particles)?);
            continue;
        }
        let raw_region = ins
            .region
            .as_ref()
            .ok_or_else(|| CaseError::missing(&table, "region", "a [insertions.region] table"))?;
        let amounts = [
            ins.count.map(Amount::Count),
            ins.volume_fraction.map(Amount::VolumeFraction),
            ins.mass.map(Amount::Mass),
        ];
        if amounts.iter().flatten().count() > 1 {
            return Err(CaseError::invalid(
                &table,
                "count",
                "with volume_fraction or mass",
                "give one of count, volume_fraction and mass",
            ));
        }
        let amount = amounts.into_iter().flatten().next();
        match amount {
            Some(Amount::VolumeFraction(f)) if !(f > 0.0 && f < 1.0) => {
                return Err(CaseError::invalid(&table, "volume_fraction", f, "must be a fraction in (0, 1)"));
            }
            Some(Amount::Mass(m)) => {
                positive(&table, "mass", m)?;
            }
            _ => {}
        }
        let rate = match (ins.rate, ins.mass_rate) {
            (Some(_), Some(_)) => {
                return Err(CaseError::invalid(
                    &table,
                    "rate",
                    "with mass_rate",
                    "give one of rate and mass_rate",
                ));
            }
            (Some(r), None) => Some(Rate::Particles(positive(&table, "rate", r)?)),
            (None, Some(r)) => Some(Rate::Mass(positive(&table, "mass_rate", r)?)),
            (None, None) => None,
        };
        let schedule = match rate {
            Some(rate) => {
                if ins.at.is_some() {
                    return Err(CaseError::invalid(
                        &table,
                        "at",
                        "with a rate",
                        "`at` is for an insertion all at once; a rate starts at `start`",
                    ));
                }
                let start = finite(&table, "start", ins.start.unwrap_or(t_start))?;
                let every = positive(&table, "every", ins.every.unwrap_or(DEFAULT_EVERY))?;
                Schedule::Rate { rate, start, every }
            }
            None => {
                for (key, given) in [("start", ins.start.is_some()), ("every", ins.every.is_some())] {
                    if given {
                        return Err(CaseError::invalid(
                            &table,
                            key,
                            "without a rate",
                            "is for a rate insertion (`rate` or `mass_rate`)",
                        ));
                    }
                }
                if amount.is_none() {
                    return Err(CaseError::missing(
                        &table,
                        "count",
                        "how much to insert: count, volume_fraction or mass (or a rate)",
                    ));
                }
                Schedule::Once { at: finite(&table, "at", ins.at.unwrap_or(t_start))? }
            }
        };
        if ins.phases.is_empty() {
            return Err(CaseError::missing(
                &table,
                "[[insertions.phases]]",
                "at least one phase (phase = \"name\") and its sizes",
            ));
        }
        let by = basis(ins.fractions_by.as_deref(), &table, "fractions_by")?;
        let mut parts = Vec::with_capacity(ins.phases.len());
        for (j, p) in ins.phases.iter().enumerate() {
            let ptable = format!("{table} phases #{}", j + 1);
            let phase_name =
                p.phase.as_deref().ok_or_else(|| CaseError::missing(&ptable, "phase", "a phase name"))?;
            let index = phases.iter().position(|ph| ph.name == phase_name).ok_or_else(|| {
                let names: Vec<String> = phases.iter().map(|p| format!("\"{}\"", p.name)).collect();
                CaseError::invalid(
                    &ptable,
                    "phase",
                    format!("\"{phase_name}\""),
                    format!("not a phase; the phases are {}", names.join(", ")),
                )
            })?;
            let fraction = match (p.fraction, ins.phases.len()) {
                (Some(f), _) if f.is_finite() && (0.0..=1.0).contains(&f) => f,
                (Some(f), _) => {
                    return Err(CaseError::invalid(&ptable, "fraction", f, "must be a fraction in [0, 1]"));
                }
                (None, 1) => 1.0,
                (None, _) => {
                    return Err(CaseError::missing(
                        &ptable,
                        "fraction",
                        "its share of the insertion, with several phases",
                    ));
                }
            };
            let phase = &phases[index];
            parts.push(MixturePart {
                phase: index as u32,
                density: phase.density,
                fraction,
                sizes: sizes(p, &ptable, phase)?,
            });
        }
        let mixture = Mixture { parts, basis: by };
        mixture.check().map_err(|e| CaseError::invalid(&table, "phases", "the fractions", e.to_string()))?;
        let velocity = vec3(ins.velocity.unwrap_or([0.0; 3]), &table, "velocity")?;
        let every = match schedule {
            Schedule::Rate { every, .. } => Some(every),
            Schedule::Once { .. } => None,
        };
        let stream = Stream { velocity, every, max_diameter: mixture.max_diameter() };
        let rtable = format!("{table} region");
        let region = region(raw_region, &rtable, meshes, Some(stream))?;
        check_insertion_region(&region, raw_region, &rtable, domain, mixture.max_diameter())?;
        let plane_z = ins.plane_z.map(|z| plane(z, &region, mixture.max_diameter(), &table)).transpose()?;
        out.push(Insertion {
            name,
            region,
            mixture,
            amount,
            schedule,
            velocity,
            seed: ins.seed.unwrap_or(k as u64 + 1),
            given: Vec::new(),
            max_initial_overlap: grainflow::insertion::DEFAULT_MAX_INITIAL_OVERLAP,
            plane_z,
        });
    }
    Ok(out)
}

/// An insertion's `plane_z`: finite, and the region holds spheres of the largest diameter
/// `d_max` centred there (its z range covers z ± d_max/2), so that the placement's centres
/// lie in the plane to its rounding margin before they are put in it exactly.
fn plane(z: f64, region: &Region, d_max: f64, table: &str) -> Result<f64, CaseError> {
    let z = finite(table, "plane_z", z)?;
    let (lo, hi) = region.bounds();
    let r = 0.5 * d_max;
    if lo.z > z - r || hi.z < z + r {
        return Err(CaseError::invalid(
            table,
            "plane_z",
            z,
            format!(
                "the region's z range [{:e}, {:e}] m must hold spheres of the largest diameter {d_max:e} m centred at z = {z:e} m",
                lo.z, hi.z
            ),
        ));
    }
    Ok(z)
}

/// An insertion of the particles of `file`, as they are, at `at`: no other key that draws or
/// places particles may be given.
fn given(
    ins: &RawInsertion,
    table: &str,
    name: String,
    file: &str,
    t_start: f64,
    read_particles: &dyn Fn(&str) -> Result<Vec<ParticleInit>, CaseError>,
) -> Result<Insertion, CaseError> {
    let others = [
        ("region", ins.region.is_some()),
        ("count", ins.count.is_some()),
        ("volume_fraction", ins.volume_fraction.is_some()),
        ("mass", ins.mass.is_some()),
        ("rate", ins.rate.is_some()),
        ("mass_rate", ins.mass_rate.is_some()),
        ("start", ins.start.is_some()),
        ("every", ins.every.is_some()),
        ("velocity", ins.velocity.is_some()),
        ("seed", ins.seed.is_some()),
        ("plane_z", ins.plane_z.is_some()),
        ("fractions_by", ins.fractions_by.is_some()),
        ("[[insertions.phases]]", !ins.phases.is_empty()),
    ];
    if let Some((key, _)) = others.iter().find(|(_, given)| *given) {
        return Err(CaseError::invalid(
            table,
            *key,
            "with file",
            "the file's particles come as they are (positions, diameters, velocities); give only name, file and at",
        ));
    }
    let at = finite(table, "at", ins.at.unwrap_or(t_start))?;
    let particles = read_particles(file)?;
    Insertion::of_given(name, at, particles)
        .ok_or_else(|| CaseError::invalid(table, "file", format!("\"{file}\""), "holds no particles"))
}

/// The `[[outlets]]` tables, and the domain's faces as the outlet "domain" if particles
/// leaving it are removed.
pub(crate) fn outlets(
    raw: &[RawOutlet],
    meshes: &Meshes,
    leaving: Option<&str>,
    domain: &Domain,
) -> Result<Vec<Outlet>, CaseError> {
    let (periodic, slack) = (domain.periodic, domain.slack());
    let mut out: Vec<Outlet> = Vec::with_capacity(raw.len() + 1);
    for (k, o) in raw.iter().enumerate() {
        let table = format!("[[outlets]] #{}", k + 1);
        let name = o
            .name
            .clone()
            .ok_or_else(|| CaseError::missing(&table, "name", "a name for messages and outputs"))?;
        if name == "domain" || out.iter().any(|i| i.name == name) {
            return Err(CaseError::invalid(
                &table,
                "name",
                format!("\"{name}\""),
                "is used by an earlier outlet (\"domain\" is [domain] leaving's)",
            ));
        }
        let table = format!("[[outlets]] '{name}'");
        let shape = match (&o.region, o.point, o.normal) {
            (Some(r), None, None) => {
                let rtable = format!("{table} region");
                let shape = region(r, &rtable, meshes, None)?;
                let (lo, hi) = shape.bounds();
                if lo.cmpgt(domain.hi + Vec3::splat(slack)).any()
                    || hi.cmplt(domain.lo - Vec3::splat(slack)).any()
                {
                    let (key, value) = placing_key(r);
                    return Err(CaseError::invalid(
                        &rtable,
                        key,
                        value,
                        format!(
                            "the outlet spans [{:?}, {:?}] m, wholly outside the domain {}: no particle can reach it, so it would never remove one",
                            lo.to_array(),
                            hi.to_array(),
                            domain.text()
                        ),
                    ));
                }
                OutletShape::Region(shape)
            }
            (None, Some(p), Some(n)) => {
                let normal = vec3(n, &table, "normal")?;
                if normal.length_squared() == 0.0 {
                    return Err(CaseError::invalid(&table, "normal", "[0, 0, 0]", "must not be zero"));
                }
                let point = vec3(p, &table, "point")?;
                // The domain's corner farthest along the normal: if even it is short of the
                // plane, no particle inside the domain is ever beyond it.
                let far = Vec3::from_array(std::array::from_fn(|k| {
                    if normal[k] >= 0.0 { domain.hi[k] } else { domain.lo[k] }
                }));
                let u = normal.normalize();
                if (far - point).dot(u) < -slack {
                    return Err(CaseError::invalid(
                        &table,
                        "point",
                        format!("{p:?}"),
                        format!(
                            "the plane lies {:e} m beyond the domain {} on its normal's side ({n:?}): no particle can reach it, so it would never remove one; put the plane on a face of the domain or inside it",
                            -(far - point).dot(u),
                            domain.text()
                        ),
                    ));
                }
                OutletShape::Plane { point, normal }
            }
            (None, _, _) if o.point.is_some() || o.normal.is_some() => {
                return Err(CaseError::missing(
                    &table,
                    if o.point.is_some() { "normal" } else { "point" },
                    "a plane needs a point and a normal",
                ));
            }
            (None, _, _) => {
                return Err(CaseError::missing(
                    &table,
                    "region",
                    "a [outlets.region] table, or a plane's point and normal",
                ));
            }
            (Some(_), _, _) => {
                return Err(CaseError::invalid(
                    &table,
                    "point",
                    "with a region",
                    "give a region or a plane (point and normal), not both",
                ));
            }
        };
        out.push(Outlet { name, shape });
    }
    match leaving {
        None | Some("stop") => {}
        Some("remove") => out.push(Outlet {
            name: "domain".into(),
            shape: OutletShape::OutsideBox { lo: domain.lo, hi: domain.hi, axes: periodic.map(|p| !p) },
        }),
        Some(other) => {
            return Err(CaseError::invalid(
                "[domain]",
                "leaving",
                format!("\"{other}\""),
                "must be \"stop\" or \"remove\"",
            ));
        }
    }
    Ok(out)
}

/// Pairs of spheres (centre, radius) that touch or overlap: (i, j) with i < j and
/// |x_i − x_j| < r_i + r_j, found through a grid of cells of the largest diameter.
fn touching_pairs(spheres: &[(Vec3, f64)]) -> Vec<(usize, usize)> {
    let r_max = spheres.iter().map(|s| s.1).fold(0.0, f64::max);
    if spheres.len() < 2 || !(r_max > 0.0 && r_max.is_finite()) {
        return Vec::new();
    }
    let cell = 2.0 * r_max;
    let key = |x: Vec3| {
        let c = (x / cell).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    };
    let mut grid: std::collections::HashMap<(i64, i64, i64), Vec<usize>> = Default::default();
    for (i, s) in spheres.iter().enumerate() {
        grid.entry(key(s.0)).or_default().push(i);
    }
    let mut out = Vec::new();
    for (i, &(x, r)) in spheres.iter().enumerate() {
        let (cx, cy, cz) = key(x);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    for &j in grid.get(&(cx + dx, cy + dy, cz + dz)).map_or(&[][..], |v| v.as_slice()) {
                        if j > i && (spheres[j].0 - x).length() < r + spheres[j].1 {
                            out.push((i, j));
                        }
                    }
                }
            }
        }
    }
    out
}

/// The particles of `file` insertions, as the particle file's are: two at one centre are
/// refused (their contact has no normal), among themselves or with a particle present at the
/// start when they come in at the start; the largest overlap above `max_overlap` of the
/// smaller radius is a warning. Every insertion gets `max_overlap` as its limit for the
/// particles present when it comes in later (the engine's notice).
pub(crate) fn check_given(
    raw: &[RawInsertion],
    insertions: &mut [Insertion],
    present: &grainflow::Particles,
    max_overlap: f64,
    t_start: f64,
    warnings: &mut Vec<String>,
) -> Result<(), CaseError> {
    for (ins, r) in insertions.iter_mut().zip(raw) {
        ins.max_initial_overlap = max_overlap;
        let (Some(file), Schedule::Once { at }) = (&r.file, ins.schedule) else { continue };
        let table = format!("[[insertions]] '{}'", ins.name);
        let g = ins.given.len();
        let mut spheres: Vec<(Vec3, f64)> = ins.given.iter().map(|p| (p.position, p.radius)).collect();
        // At the start the particles present are those of the case, where they are now.
        if at <= t_start {
            spheres.extend(present.position.iter().zip(&present.radius).map(|(&x, &r)| (x, r)));
        }
        let name = |i: usize| {
            if i < g {
                format!("particle {} of the file", ins.given[i].id)
            } else {
                format!("particle {} present at the start", present.id[i - g])
            }
        };
        let mut worst: Option<(f64, usize, usize)> = None;
        for (i, j) in touching_pairs(&spheres) {
            if i >= g && j >= g {
                continue;
            }
            let ((xi, ri), (xj, rj)) = (spheres[i], spheres[j]);
            if xi == xj {
                return Err(CaseError::invalid(
                    &table,
                    "file",
                    format!("\"{file}\""),
                    format!(
                        "{} and {} have the same centre ({:e}, {:e}, {:e}) m: their contact has no normal direction; move one of them",
                        name(i),
                        name(j),
                        xi.x,
                        xi.y,
                        xi.z
                    ),
                ));
            }
            let ratio = (ri + rj - (xi - xj).length()) / ri.min(rj);
            if ratio > max_overlap && worst.is_none_or(|w| ratio > w.0) {
                worst = Some((ratio, i, j));
            }
        }
        if let Some((ratio, i, j)) = worst {
            warnings.push(format!(
                "{table}: file = \"{file}\": {} and {} overlap by {ratio:.3} of the smaller radius (the largest overlap), above [particles] max_initial_overlap = {max_overlap}; the contact starts with a burst of elastic energy",
                name(i),
                name(j)
            ));
        }
    }
    Ok(())
}
