//! Plane walls as a contact source. The neighbour list finds each particle's candidate walls
//! with its pairs and keeps their histories (`wall_pairs`, `wall_history`); the pair kernel
//! computes their loads, each block of particles its own walls first ([`crate::forces`]).

use super::{ContactSource, Diagnosed, LoadRun, View, wall_coeffs_of};
use crate::contact::geometry::{relative_velocity, wall_contact};
use crate::contact::law::{contact_force_dyn, normal_spring_energy};
use crate::contact::pair::{scaled_damping, wall_geometry_in_contact};
use crate::contact::submodel::{NormalSubModel, TangentialSubModel, formed};
use crate::math::Vec3;
use crate::neighbor::NeighborState;
use crate::simulation::{ContactInfo, ContactPartner};
use crate::surface::{CellData, CellValues, Surface, SurfaceKind, Which, clip_plane_to_box};

/// The plane walls' contacts (their geometry and candidates are the neighbour list's).
#[derive(Debug, Clone, Default)]
pub(crate) struct Planes;

impl ContactSource for Planes {
    /// Nothing: the pair kernel adds the plane walls' loads ([`super::Pairs`]).
    fn loads<N: NormalSubModel, T: TangentialSubModel>(&mut self, _run: &mut LoadRun) {}

    fn contact_infos(&self, v: &View, out: &mut Vec<ContactInfo>) {
        let (p, law) = (v.particles, &v.law);
        let nl = v.neighbors;
        for (&[i, w], &h) in nl.wall_pairs().iter().zip(nl.wall_history()) {
            let (i, wall) = (i as usize, &v.walls[w as usize]);
            let c = &wall_coeffs_of(v.coeffs, law, p, i, wall.material);
            let (x, r) = (p.position[i], p.radius[i]);
            if let Some(g) =
                wall_geometry_in_contact(law.normal, x, r, wall, law.lever, c.pull_off, formed(h))
            {
                let c = scaled_damping(c, law.damping, p.mass[i]);
                let v_r = relative_velocity(&g, p.velocity[i], Vec3::ZERO, p.omega[i], Vec3::ZERO);
                let mut h = h;
                let f = contact_force_dyn(law, &c, &g, v_r, &mut h, 0.0);
                out.push(ContactInfo {
                    particle: i,
                    other: ContactPartner::Wall(w as usize),
                    point: p.position[i] + g.lever_i * g.normal,
                    normal: g.normal,
                    overlap: g.overlap,
                    normal_force: f.normal.length(),
                    tangential_force: f.tangential.length(),
                });
            }
        }
    }

    fn diagnose(&self, v: &View, visit: &mut dyn FnMut(Diagnosed)) {
        let (p, law) = (v.particles, &v.law);
        let (normal, reaches, lever) = (law.normal, law.normal.reaches(), law.lever);
        let nl = v.neighbors;
        for (&[i, w], &h) in nl.wall_pairs().iter().zip(nl.wall_history()) {
            let (i, wall) = (i as usize, &v.walls[w as usize]);
            let c = &wall_coeffs_of(v.coeffs, law, p, i, wall.material);
            let (x, r) = (p.position[i], p.radius[i]);
            // A cohesive contact holds beyond the touch.
            let g = if reaches {
                wall_geometry_in_contact(normal, x, r, wall, lever, c.pull_off, formed(h))
            } else {
                wall_contact(x, r, wall.point, wall.normal)
            };
            if let Some(g) = g {
                visit((g.overlap, p.radius[i], normal_spring_energy(normal, c, g.overlap)));
            }
        }
    }

    /// The wall pairs of a removed particle go with it; the others follow their particles.
    fn rearrange(&mut self, new_of: &[u32], list: &mut NeighborState) {
        let (wall_pairs, wall_history): (Vec<[u32; 2]>, Vec<Vec3>) = list
            .wall_pairs
            .iter()
            .zip(&list.wall_history)
            .filter(|([i, _], _)| new_of[*i as usize] != u32::MAX)
            .map(|(&[i, w], &h)| ([new_of[i as usize], w], h))
            .unzip();
        (list.wall_pairs, list.wall_history) = (wall_pairs, wall_history);
    }

    const SURFACES: &'static [SurfaceKind] = &[WALLS];

    /// The walls (always, none or many) as polygons clipped to the box, one per wall that
    /// cuts it. Cell data: `wall` (the wall's index), `material`.
    fn surfaces(&self, sim: &crate::Simulation, lo: Vec3, hi: Vec3, which: Which, out: &mut Vec<Surface>) {
        if !which.wants(WALLS) {
            return;
        }
        let mut s = Surface::new(WALLS);
        let (mut index, mut material) = (Vec::new(), Vec::new());
        for (k, w) in sim.walls().iter().enumerate() {
            let poly = clip_plane_to_box(w, lo, hi);
            if poly.is_empty() {
                continue;
            }
            let base = s.points.len();
            s.points.extend(poly);
            s.push_polygon(base..s.points.len());
            index.push(k as i32);
            material.push(w.material as i32);
        }
        s.cell_data = vec![
            CellData { name: "wall", values: CellValues::Int(index) },
            CellData { name: "material", values: CellValues::Int(material) },
        ];
        out.push(s);
    }
}

/// The plane walls' surface: fixed.
const WALLS: SurfaceKind = SurfaceKind { stem: "walls", moves: false };

/// The plane-wall pairs (particle id, wall) and their histories, from the neighbour list.
impl crate::checkpoint::Saved for Planes {
    fn save<W: std::io::Write>(
        &self,
        sim: &crate::Simulation,
        e: &mut crate::checkpoint::Enc<W>,
    ) -> std::io::Result<()> {
        let (id, nl) = (&sim.particles().id, sim.neighbors());
        e.pairs(nl.wall_pairs().len(), nl.wall_pairs().iter().map(|&[i, w]| [id[i as usize], w]))?;
        e.vec3s(nl.wall_history())
    }

    fn saved_bytes(&self, sim: &crate::Simulation) -> usize {
        crate::checkpoint::pairs_bytes(sim.neighbors().wall_pairs().len())
    }

    fn load<R: std::io::Read>(
        d: &mut crate::checkpoint::Dec<R>,
        state: &mut crate::checkpoint::SourceState,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        state.wall_pairs = d.pairs("wall pairs")?;
        state.wall_history = d.vec3s("wall history")?;
        Ok(())
    }
}
