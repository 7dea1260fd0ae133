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
    // The first bad pair in slot order (the smaller slot first, then its partner's): two at
    // one centre, or an overlap above the limit.
    let bad = |i: usize, j: usize| {
        let overlap = p.radius[i] + p.radius[j] - (p.position[j] - p.position[i]).length();
        p.position[i] == p.position[j] || overlap > max_overlap * p.radius[i].min(p.radius[j])
    };
    if let Some((i, j)) = first_pair(p, bad) {
        if p.position[i] == p.position[j] {
            return Err(CaseError::Geometry(format!(
                "{} and particle {} have the same centre: their contact has no normal direction; move one of them",
                at(i),
                p.id[j]
            )));
        }
        let overlap = p.radius[i] + p.radius[j] - (p.position[j] - p.position[i]).length();
        let r = p.radius[i].min(p.radius[j]);
        return Err(CaseError::Geometry(format!(
            "{} and particle {} overlap by {:.3e} m = {:.3} of the smaller radius; the limit is [particles] max_initial_overlap = {max_overlap}",
            at(i),
            p.id[j],
            overlap,
            overlap / r
        )));
    }
    Ok(())
}

/// The touching pair `(i, j)`, `i < j`, that `bad` holds for with the smallest `i`, then `j`;
/// positions finite. The particles are sorted into cubic cells of the largest diameter (16 B
/// a particle, where a neighbour list of a large bed is many times that), x fastest; the
/// cells of each row of 3 × 3 neighbouring rows follow one after another in that order, so a
/// cursor per row walks forward through the sorted particles as the cells do.
fn first_pair(p: &Particles, bad: impl Fn(usize, usize) -> bool) -> Option<(usize, usize)> {
    let n = p.len();
    let r_max = p.max_radius();
    if n < 2 || !(r_max > 0.0 && r_max.is_finite()) {
        return None;
    }
    let cell = 2.0 * r_max;
    let (lo, hi) =
        p.position.iter().fold((Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)), |(l, h), &x| {
            (l.min(x), h.max(x))
        });
    let dims = ((hi - lo) / cell).floor().to_array().map(|c| c as u64 + 1);
    // A key for every cell, with room for one beyond each end of each axis.
    let (nx, ny) = (dims[0] + 2, dims[1] + 2);
    if (nx as u128) * (ny as u128) * (dims[2] as u128 + 2) >= 1u128 << 63 {
        return first_pair_by_list(p, bad);
    }
    let cell_of = |x: Vec3| ((x - lo) / cell).floor().to_array().map(|c| (c as u64).min(u64::MAX - 2) + 1);
    let key = |[cx, cy, cz]: [u64; 3]| (cz * ny + cy) * nx + cx;
    let mut sorted: Vec<(u64, u32)> = (0..n).map(|i| (key(cell_of(p.position[i])), i as u32)).collect();
    sorted.sort_unstable();
    let mut best: Option<(usize, usize)> = None;
    let mut cursor = [0usize; 9];
    let mut s = 0;
    while s < n {
        let k = sorted[s].0;
        let e = s + sorted[s..].partition_point(|c| c.0 == k);
        let (cx, cy, cz) = (k % nx, k / nx % ny, k / nx / ny);
        for (row, (dy, dz)) in (0..3).flat_map(|dz| (0..3).map(move |dy| (dy, dz))).enumerate() {
            let (ry, rz) = (cy + dy - 1, cz + dz - 1);
            let (from, to) = (key([cx - 1, ry, rz]), key([cx + 1, ry, rz]));
            let at = &mut cursor[row];
            while *at < n && sorted[*at].0 < from {
                *at += 1;
            }
            for &(kj, j) in sorted[*at..].iter().take_while(|c| c.0 <= to) {
                debug_assert!(kj >= from);
                for &(_, i) in &sorted[s..e] {
                    let (a, b) = (i.min(j) as usize, i.max(j) as usize);
                    if i < j && best.is_none_or(|w| (a, b) < w) && bad(a, b) {
                        best = Some((a, b));
                    }
                }
            }
        }
        s = e;
    }
    best
}

/// [`first_pair`] over a neighbour list (cells too many for the keys).
fn first_pair_by_list(p: &Particles, bad: impl Fn(usize, usize) -> bool) -> Option<(usize, usize)> {
    let mut nl = grainflow::neighbor::NeighborList::new(0.0);
    nl.build(p, &[]);
    nl.pairs().map(|[i, j]| (i.min(j) as usize, i.max(j) as usize)).filter(|&(i, j)| bad(i, j)).min()
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainflow::state::ParticleInit;
    use rand::{Rng, SeedableRng};

    /// A loose cloud of beads of mixed sizes, some pressed into others.
    fn cloud(n: usize, seed: u64) -> Particles {
        let mut rng = grainflow::insertion::InsertRng::seed_from_u64(seed);
        let init: Vec<ParticleInit> = (0..n)
            .map(|k| ParticleInit {
                id: k as u32 + 1,
                phase: 0,
                radius: rng.random_range(0.5e-3..1.5e-3),
                density: 2500.0,
                position: Vec3::new(
                    rng.random_range(0.0..0.05),
                    rng.random_range(0.0..0.05),
                    rng.random_range(0.0..0.02),
                ),
                velocity: Vec3::ZERO,
                omega: Vec3::ZERO,
            })
            .collect();
        Particles::from_init(&init)
    }

    #[test]
    fn the_cells_find_the_first_bad_pair_the_neighbour_list_finds() {
        for seed in 0..4 {
            let p = cloud(3000, seed);
            // Limits from every touching pair being bad to none being.
            for limit in [0.0, 0.05, 0.3, 0.9, 2.0] {
                let bad = |i: usize, j: usize| {
                    let overlap = p.radius[i] + p.radius[j] - (p.position[j] - p.position[i]).length();
                    overlap > limit * p.radius[i].min(p.radius[j])
                };
                let by_list = first_pair_by_list(&p, bad);
                assert_eq!(first_pair(&p, bad), by_list, "seed {seed}, limit {limit}");
                if limit == 0.0 {
                    assert!(by_list.is_some(), "the cloud has touching pairs");
                }
            }
        }
        // A pair at one centre, far into the set, is found.
        let mut p = cloud(3000, 9);
        p.position[2999] = p.position[1234];
        let same = |i: usize, j: usize| p.position[i] == p.position[j];
        assert_eq!(first_pair(&p, same), Some((1234, 2999)));
    }
}
