//! `[domain]` and `[[walls]]`: the box, its periodic axes and walled faces, and plane walls.

use super::fields::{require, vec3};
use super::materials::material_index;
use crate::error::CaseError;
use crate::raw::{RawDomain, RawWall, WallSelection};
use grainflow::{Periodic, Vec3, Wall, WallMaterial};

/// The box's corners, `[domain] min` and `max`, m.
pub(super) fn corners(domain: &RawDomain) -> Result<(Vec3, Vec3), CaseError> {
    let min = vec3(require(domain.min, "[domain]", "min", "lower corner of the box, m")?, "[domain]", "min")?;
    let max = vec3(require(domain.max, "[domain]", "max", "upper corner of the box, m")?, "[domain]", "max")?;
    if !(max.cmpgt(min).all()) {
        return Err(CaseError::invalid(
            "[domain]",
            "max",
            format!("{:?}", max.to_array()),
            format!("every component must exceed min = {:?}", min.to_array()),
        ));
    }
    Ok((min, max))
}

/// The domain's periodic axes and walls, with the planes of `[[walls]]`.
pub(super) struct Walls {
    pub axes: [bool; 3],
    pub periodic: Option<Periodic>,
    pub walls: Vec<Wall>,
}

/// The periodic axes, the box's walled faces and the `[[walls]]` planes.
pub(super) fn walls(
    domain: &RawDomain,
    raw_walls: &[RawWall],
    (min, max): (Vec3, Vec3),
    wall_materials: &[WallMaterial],
) -> Result<Walls, CaseError> {
    let mut axes = [false; 3];
    for a in domain.periodic.iter().flatten() {
        let k = ["x", "y", "z"].iter().position(|n| n == a).ok_or_else(|| {
            CaseError::invalid(
                "[domain]",
                "periodic",
                format!("\"{a}\""),
                "each periodic axis must be \"x\", \"y\" or \"z\"",
            )
        })?;
        if axes[k] {
            return Err(CaseError::invalid(
                "[domain]",
                "periodic",
                format!("{:?}", domain.periodic.as_deref().unwrap_or_default()),
                format!("the axis \"{a}\" is listed twice; list each periodic axis once"),
            ));
        }
        axes[k] = true;
    }
    let periodic = axes.iter().any(|&a| a).then_some(Periodic { lo: min, hi: max, axes });
    let faces = ["x_min", "x_max", "y_min", "y_max", "z_min", "z_max"];
    let wanted: Vec<bool> = match &domain.walls {
        WallSelection::All(all) => (0..6).map(|k| *all && !axes[k / 2]).collect(),
        WallSelection::Faces(list) => {
            let mut w = vec![false; 6];
            for f in list {
                let k = faces.iter().position(|n| n == f).ok_or_else(|| {
                    CaseError::invalid(
                        "[domain]",
                        "walls",
                        format!("\"{f}\""),
                        "faces are \"x_min\", \"x_max\", \"y_min\", \"y_max\", \"z_min\", \"z_max\"",
                    )
                })?;
                if axes[k / 2] {
                    return Err(CaseError::invalid(
                        "[domain]",
                        "walls",
                        format!("\"{f}\""),
                        "a periodic axis has no walls",
                    ));
                }
                w[k] = true;
            }
            w
        }
    };
    let mut walls = Vec::new();
    if wanted.iter().any(|&w| w) {
        let m = material_index(wall_materials, &domain.wall_material, "[domain]", "wall_material")?;
        walls.extend(
            Wall::domain_box(min, max, m).into_iter().zip(&wanted).filter(|(_, w)| **w).map(|(wall, _)| wall),
        );
    }
    for (k, w) in raw_walls.iter().enumerate() {
        let name = w.name.clone().unwrap_or_else(|| format!("wall {}", k + 1));
        let table = format!("[[walls]] '{name}'");
        let point = vec3(require(w.point, &table, "point", "a point on the plane, m")?, &table, "point")?;
        let normal = vec3(
            require(w.normal, &table, "normal", "normal pointing into the particle space")?,
            &table,
            "normal",
        )?;
        if normal.length() == 0.0 {
            return Err(CaseError::invalid(
                &table,
                "normal",
                format!("{:?}", normal.to_array()),
                "the normal must not be zero",
            ));
        }
        walls.push(Wall::plane(
            name,
            point,
            normal,
            material_index(wall_materials, &w.material, &table, "material")?,
        ));
    }
    Ok(Walls { axes, periodic, walls })
}
