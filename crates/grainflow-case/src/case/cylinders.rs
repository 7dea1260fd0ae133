//! `[[cylinders]]`: infinite cylinder walls, exact, their surfaces at rest or turning.

use super::fields::{choose, require, vec3};
use super::materials::material_index;
use crate::error::CaseError;
use crate::raw::RawCylinder;
use grainflow::{Cylinder, CylinderSide, Particles, Periodic, WallMaterial};

/// The `[[cylinders]]` tables, in the order of the case file.
pub(super) fn cylinders(
    raw: &[RawCylinder],
    wall_materials: &[WallMaterial],
) -> Result<Vec<Cylinder>, CaseError> {
    let mut out: Vec<Cylinder> = Vec::with_capacity(raw.len());
    for (k, c) in raw.iter().enumerate() {
        let table = format!("[[cylinders]] #{}", k + 1);
        let name = require(
            c.name.clone(),
            &table,
            "name",
            "a unique cylinder name, for messages and the time series",
        )?;
        let table = format!("[[cylinders]] '{name}'");
        if out.iter().any(|o| o.name == name) {
            return Err(CaseError::invalid(
                &table,
                "name",
                format!("\"{name}\""),
                "cylinder names must be unique",
            ));
        }
        let origin = vec3(require(c.origin, &table, "origin", "a point on the axis, m")?, &table, "origin")?;
        let a = require(c.axis, &table, "axis", "the direction of the axis, e.g. [0, 1, 0]")?;
        let axis = vec3(a, &table, "axis")?;
        if !(axis.length() > 0.0 && axis.length().is_finite()) {
            return Err(CaseError::invalid(&table, "axis", format!("{a:?}"), "must be a non-zero vector"));
        }
        let radius = require(c.radius, &table, "radius", "the radius, m")?;
        if !(radius.is_finite() && radius > 0.0) {
            return Err(CaseError::invalid(
                &table,
                "radius",
                radius,
                "must be a positive, finite length, in m",
            ));
        }
        if c.side.is_none() {
            return Err(CaseError::missing(
                &table,
                "side",
                "\"inside\" (a drum or pipe: the particles inside) or \"outside\" (a rod)",
            ));
        }
        let sides = [("inside", CylinderSide::Inside), ("outside", CylinderSide::Outside)];
        let side = choose(&table, "side", c.side.as_deref(), CylinderSide::Inside, &sides)?;
        if c.material.is_none() {
            return Err(CaseError::missing(&table, "material", "the name of a [[wall_materials]] table"));
        }
        let material = material_index(wall_materials, &c.material, &table, "material")?;
        let omega = match (c.omega, c.rpm) {
            (Some(_), Some(_)) => {
                return Err(CaseError::invalid(
                    &table,
                    "rpm",
                    "given with omega",
                    "give `omega` (rad/s) or `rpm`, not both",
                ));
            }
            (Some(w), None) => w,
            (None, Some(n)) => n * std::f64::consts::TAU / 60.0,
            (None, None) => 0.0,
        };
        if !omega.is_finite() {
            let (key, value) = if c.omega.is_some() { ("omega", c.omega) } else { ("rpm", c.rpm) };
            return Err(CaseError::invalid(&table, key, value.unwrap_or(omega), "must be a finite number"));
        }
        out.push(Cylinder::new(name, origin, axis, radius, side, material, omega));
    }
    Ok(out)
}

/// Particles must start on the particles' side of every cylinder, overlapping it by no more
/// than `max_overlap` of their radius (as at the plane walls); a cylinder must not meet the
/// faces of a periodic axis unless its axis lies along it (it has no periodic images).
pub(super) fn check(
    p: &Particles,
    cylinders: &[Cylinder],
    max_overlap: f64,
    periodic: Option<(&Periodic, f64)>,
) -> Result<(), CaseError> {
    for c in cylinders {
        let table = format!("[[cylinders]] '{}'", c.name);
        for i in 0..p.len() {
            let x = p.position[i];
            let at = format!("particle {} at ({:.6e}, {:.6e}, {:.6e}) m", p.id[i], x.x, x.y, x.z);
            // On the axis: a radius from the surface, inside or outside.
            let inside = c.side == CylinderSide::Inside;
            let on_axis = if inside { c.radius } else { -c.radius };
            let d = c.locate(x).map_or(on_axis, |k| k.distance);
            let side = if inside { "inside" } else { "outside" };
            if d < 0.0 {
                return Err(CaseError::Geometry(format!(
                    "{table}: {at} is not {side} the cylinder (radius {:e} m): its centre is {:.3e} m on the far side of the surface",
                    c.radius, -d
                )));
            }
            let overlap = p.radius[i] - d;
            if overlap > max_overlap * p.radius[i] {
                return Err(CaseError::Geometry(format!(
                    "{table}: {at} overlaps the cylinder by {overlap:.3e} m = {:.3} of its radius; the limit is [particles] max_initial_overlap = {max_overlap}",
                    overlap / p.radius[i]
                )));
            }
        }
    }
    if let Some((per, r_max)) = periodic
        && let Some((m, axis)) = grainflow::simulation::periodic_cylinder_reach(cylinders, per, r_max)
    {
        let text = grainflow::simulation::periodic_cylinder_message(&cylinders[m], axis, r_max);
        return Err(CaseError::Geometry(format!("[[cylinders]] '{}': {text}", cylinders[m].name)));
    }
    Ok(())
}
