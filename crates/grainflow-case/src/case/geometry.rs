//! The checks across tables once every table is read: prescribed motions, the particles
//! against the box, the walls and the meshes, given insertions, and the periodic box.

use crate::error::CaseError;
use crate::raw::RawInsertion;
use grainflow::insertion::Insertion;
use grainflow::mesh::{MeshWall, TriangleGrid, closest_point_on_triangle};
use grainflow::{Particles, Periodic, PrescribedMotion, Vec3, Wall};

/// The checks across tables, in this order: the motions' rules, the particles' places and
/// overlaps, the insertions given as files, the periodic box's length and the meshes' reach
/// across its faces.
pub(super) fn check(
    motion: &[PrescribedMotion],
    particles: &Particles,
    walls: &[Wall],
    meshes: &[MeshWall],
    mesh_names: &[String],
    (min, max): (Vec3, Vec3),
    max_overlap: f64,
    raw_insertions: &[RawInsertion],
    insertions: &mut [Insertion],
    periodic: Option<&Periodic>,
    skin: Option<f64>,
    (t_start, t_stop): (f64, f64),
    warnings: &mut Vec<String>,
) -> Result<(), CaseError> {
    grainflow::motion::check_rules(motion).map_err(|e| CaseError::Geometry(format!("[[motion]]: {e}")))?;
    check_geometry(particles, walls, meshes, mesh_names, (min, max), max_overlap)?;
    super::flow::check_given(raw_insertions, insertions, particles, max_overlap, t_start, warnings)?;
    if let Some(per) = periodic {
        let skin = skin.unwrap_or_else(|| grainflow::simulation::default_skin(particles.max_radius()));
        per.check(particles.max_radius(), skin, walls)?;
        // The largest radius any particle has or is inserted with.
        let r_max = insertions
            .iter()
            .flat_map(|ins| &ins.mixture.parts)
            .map(|part| 0.5 * part.sizes.max_diameter())
            .fold(particles.max_radius(), f64::max);
        if let Some((m, axis, from, to)) =
            grainflow::simulation::periodic_mesh_reach(meshes, per, r_max, t_stop - t_start)
        {
            let text =
                grainflow::simulation::periodic_mesh_message(&mesh_names[m], (axis, from, to), per, r_max);
            return Err(CaseError::Geometry(format!("[[meshes]] '{}': {text}", mesh_names[m])));
        }
    }
    Ok(())
}

/// Particles must start inside the domain box, in front of every wall, and overlap no wall
/// or other particle by more than `max_overlap` of the (smaller) radius: a larger overlap
/// releases a burst of elastic energy at the first step.
///
/// A mesh has no "behind" (a sheet may be touched from either side): only the overlap is
/// checked, as the distance from the centre to the nearest triangle.
fn check_geometry(
    p: &Particles,
    walls: &[Wall],
    meshes: &[MeshWall],
    mesh_names: &[String],
    (lo, hi): (Vec3, Vec3),
    max_overlap: f64,
) -> Result<(), CaseError> {
    let at = |i: usize| {
        let x = p.position[i];
        format!("particle {} at ({:.6e}, {:.6e}, {:.6e}) m", p.id[i], x.x, x.y, x.z)
    };
    for i in 0..p.len() {
        let x = p.position[i];
        if x.cmplt(lo).any() || x.cmpgt(hi).any() {
            return Err(CaseError::Geometry(format!(
                "{} is outside the domain box [{:?}, {:?}]; move it inside or enlarge [domain]",
                at(i),
                lo.to_array(),
                hi.to_array()
            )));
        }
        for w in walls {
            let d = w.distance(x);
            if d < 0.0 {
                return Err(CaseError::Geometry(format!(
                    "{} is behind wall '{}' (its centre is {:.3e} m on the wall's far side)",
                    at(i),
                    w.name,
                    -d
                )));
            }
            let overlap = p.radius[i] - d;
            if overlap > max_overlap * p.radius[i] {
                return Err(CaseError::Geometry(format!(
                    "{} overlaps wall '{}' by {:.3e} m = {:.3} of its radius; the limit is [particles] max_initial_overlap = {max_overlap}",
                    at(i),
                    w.name,
                    overlap,
                    overlap / p.radius[i]
                )));
            }
        }
    }
    let mut near = Vec::new();
    for (MeshWall { mesh, .. }, name) in meshes.iter().zip(mesh_names) {
        let grid = TriangleGrid::new(mesh, 2.0 * p.max_radius());
        for i in 0..p.len() {
            let (x, r) = (p.position[i], p.radius[i]);
            // The triangles closer than r·(1 − max_overlap): those overlapped by more than the
            // limit (none when the limit is the whole radius or more).
            grid.near(mesh, x, r * (1.0 - max_overlap), &mut near);
            let closest = near
                .iter()
                .map(|&t| (t, (x - closest_point_on_triangle(x, mesh.corners(t)).point).length()))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((t, d)) = closest {
                let overlap = r - d;
                return Err(CaseError::Geometry(format!(
                    "{} overlaps mesh '{name}' (triangle {t}) by {:.3e} m = {:.3} of its radius; the limit is [particles] max_initial_overlap = {max_overlap}",
                    at(i),
                    overlap,
                    overlap / r
                )));
            }
        }
    }
    let mut nl = grainflow::neighbor::NeighborList::new(0.0);
    nl.build(p, &[]);
    for [i, j] in nl.pairs() {
        let (i, j) = (i as usize, j as usize);
        if p.position[i] == p.position[j] {
            return Err(CaseError::Geometry(format!(
                "{} and particle {} have the same centre: their contact has no normal direction; move one of them",
                at(i),
                p.id[j]
            )));
        }
        let overlap = p.radius[i] + p.radius[j] - (p.position[j] - p.position[i]).length();
        let r = p.radius[i].min(p.radius[j]);
        if overlap > max_overlap * r {
            return Err(CaseError::Geometry(format!(
                "{} and particle {} overlap by {:.3e} m = {:.3} of the smaller radius; the limit is [particles] max_initial_overlap = {max_overlap}",
                at(i),
                p.id[j],
                overlap,
                overlap / r
            )));
        }
    }
    Ok(())
}
