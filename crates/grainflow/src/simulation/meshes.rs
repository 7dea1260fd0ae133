//! The mesh-wall stage of a force evaluation: each particle's candidate triangles (found with
//! the meshes' triangle grids whenever the neighbour list is rebuilt, within the particle's
//! radius plus the skin), its contacts with each mesh ([`crate::mesh::sphere_contacts`]: every
//! surface touched once), their loads by the case's law as against a plane wall, and their
//! tangential histories.
//!
//! A contact's history is kept under the triangle that owns it. A particle that rolls from one
//! triangle onto the next takes the history of its contact there before: a contact without a
//! history of its own takes that of the particle's unclaimed contact of the evaluation before
//! on the same mesh whose normal is closest to its own (within 60°), so that the spring does
//! not snap back at a seam.
//!
//! The loads are rounded to the sums' quanta like every other load (`forces::sum`), so adding
//! them after the pair stage, on one thread, gives the same sums as adding them anywhere else.

use super::Simulation;
use crate::contact::LeverArm;
use crate::contact::law::parts;
use crate::contact::pair::{PairInput, wall_law};
use crate::contact::submodel::{NormalSubModel, TangentialSubModel};
use crate::forces::{Peak, Quanta, Quantum, max_peak};
use crate::math::Vec3;
use crate::mesh::{Mesh, MeshContact, MeshWall, TriangleGrid, sphere_contacts};

/// A contact's normal may turn this far (cosine) from one evaluation to the next and still
/// carry its history to another triangle: 60°.
const CARRY_COS: f64 = 0.5;

/// The tangential history of one particle–mesh contact, under the triangle that owns it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MeshHistory {
    pub slot: u32,
    pub mesh: u32,
    pub triangle: u32,
    /// The contact's normal (from the surface to the centre) when the history was stored.
    pub normal: Vec3,
    pub h: Vec3,
}

/// What the mesh stage keeps between evaluations.
#[derive(Debug, Clone, Default)]
pub(crate) struct MeshStage {
    grids: Vec<TriangleGrid>,
    /// The neighbour-list build the candidates were found for.
    built_for: Option<u64>,
    /// Candidates of slot i: `candidates[start[i]..start[i + 1]]`, (mesh, triangle) ascending.
    start: Vec<u32>,
    candidates: Vec<(u32, u32)>,
    /// The histories of the last evaluation's contacts, by (slot, mesh, triangle).
    pub history: Vec<MeshHistory>,
}

impl MeshStage {
    /// Heap bytes of the stage.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.grids.iter().map(TriangleGrid::heap_bytes).sum::<usize>()
            + self.start.capacity() * 4
            + self.candidates.capacity() * 8
            + self.history.capacity() * std::mem::size_of::<MeshHistory>()
    }

    /// Fills `contacts` with the contacts of slot `i` (centre `centre`, radius `r`) with mesh
    /// `m` among its candidates, found within `r + reach` (`reach`: a cohesive law's pull-off
    /// distance, else 0; a contact's overlap with the radius is its `overlap − reach`).
    /// `triangles` is scratch.
    #[allow(clippy::too_many_arguments)]
    fn contacts_of(
        &self,
        i: usize,
        (m, mesh): (usize, &Mesh),
        centre: Vec3,
        r: f64,
        reach: f64,
        triangles: &mut Vec<u32>,
        contacts: &mut Vec<MeshContact>,
    ) {
        let cands = &self.candidates[self.start[i] as usize..self.start[i + 1] as usize];
        triangles.clear();
        triangles.extend(cands.iter().filter(|c| c.0 == m as u32).map(|c| c.1));
        contacts.clear();
        if !triangles.is_empty() {
            sphere_contacts(mesh, triangles, centre, r + reach, contacts);
        }
    }

    /// Slots renumbered: slot `k` is now what slot `order[k]` was (`new_of[old]`, `u32::MAX`
    /// for a removed slot). Histories of removed slots go; candidates are found again.
    pub(crate) fn remap(&mut self, new_of: &[u32]) {
        self.history.retain_mut(|h| {
            let k = new_of[h.slot as usize];
            h.slot = k;
            k != u32::MAX
        });
        self.history.sort_unstable_by_key(|h| (h.slot, h.mesh, h.triangle));
        self.built_for = None;
    }
}

impl Simulation {
    /// The mesh-wall contacts' histories, by (slot, mesh, triangle).
    pub(crate) fn mesh_histories(&self) -> &[MeshHistory] {
        &self.mesh_stage.history
    }

    /// Restores the mesh-wall contacts' histories of a checkpoint: (particle id, mesh),
    /// triangle, normal and history of each.
    pub(crate) fn set_mesh_histories(
        &mut self,
        (owners, triangles, normals, h): (Vec<[u32; 2]>, Vec<u32>, Vec<Vec3>, Vec<Vec3>),
    ) -> Result<(), String> {
        let n = owners.len();
        if triangles.len() != n || normals.len() != n || h.len() != n {
            return Err("the mesh contacts' lists have different lengths".into());
        }
        let mut by_id: Vec<(u32, u32)> =
            self.particles.id.iter().enumerate().map(|(s, &id)| (id, s as u32)).collect();
        by_id.sort_unstable();
        let mut history = Vec::with_capacity(n);
        for k in 0..n {
            let [id, mesh] = owners[k];
            let slot = by_id
                .binary_search_by_key(&id, |e| e.0)
                .map(|j| by_id[j].1)
                .map_err(|_| format!("a mesh contact names particle {id}, which the case does not have"))?;
            let fits = self
                .meshes
                .get(mesh as usize)
                .is_some_and(|m| (triangles[k] as usize) < m.mesh.triangle_count());
            if !fits {
                return Err(format!(
                    "a mesh contact names triangle {} of mesh {mesh}, which the case does not have",
                    triangles[k]
                ));
            }
            history.push(MeshHistory { slot, mesh, triangle: triangles[k], normal: normals[k], h: h[k] });
        }
        history.sort_unstable_by_key(|h| (h.slot, h.mesh, h.triangle));
        if history
            .windows(2)
            .any(|w| (w[0].slot, w[0].mesh, w[0].triangle) == (w[1].slot, w[1].mesh, w[1].triangle))
        {
            return Err("a mesh contact appears twice".into());
        }
        self.mesh_stage.history = history;
        Ok(())
    }

    /// Calls `visit(slot, overlap)` for every mesh-wall contact of the current state, with the
    /// candidates of the last evaluation (none before the first), for diagnostics: as the next
    /// evaluation would find them (a cohesive contact formed at the last evaluation holds to
    /// its pull-off distance).
    pub(super) fn visit_mesh_contacts(
        &self,
        mut visit: impl FnMut(usize, f64, &crate::contact::ContactCoeffs),
    ) {
        let (st, p) = (&self.mesh_stage, &self.particles);
        if self.meshes.is_empty() || st.start.len() != p.len() + 1 {
            return;
        }
        let reaches = self.law.normal.reaches();
        let (mut contacts, mut triangles) = (Vec::new(), Vec::new());
        for i in 0..p.len() {
            for (m, MeshWall { mesh, material }) in self.meshes.iter().enumerate() {
                let c = self.coeffs.wall(p.phase[i] as usize, *material);
                let reach = if reaches { c.pull_off } else { 0.0 };
                st.contacts_of(
                    i,
                    (m, mesh),
                    p.position[i],
                    p.radius[i],
                    reach,
                    &mut triangles,
                    &mut contacts,
                );
                for k in &contacts {
                    let overlap = k.overlap - reach;
                    let formed = || {
                        st.history
                            .binary_search_by_key(&(i as u32, m as u32, k.triangle), |h| {
                                (h.slot, h.mesh, h.triangle)
                            })
                            .is_ok()
                    };
                    if overlap >= 0.0 || (reaches && formed()) {
                        visit(i, overlap, c);
                    }
                }
            }
        }
    }

    /// The candidates of every slot, found again if the neighbour list was rebuilt since.
    fn update_mesh_candidates(&mut self) {
        let build = self.neighbors.stats().builds;
        let st = &mut self.mesh_stage;
        if st.built_for == Some(build) && st.start.len() == self.particles.len() + 1 {
            return;
        }
        let skin = self.neighbors.skin();
        if st.grids.len() != self.meshes.len() {
            let cell = 2.0 * self.particles.max_radius() + skin;
            st.grids = self.meshes.iter().map(|m| TriangleGrid::new(&m.mesh, cell)).collect();
        }
        let p = &self.particles;
        st.start.clear();
        st.candidates.clear();
        st.start.push(0);
        let mut near = Vec::new();
        for i in 0..p.len() {
            for (m, (wall, grid)) in self.meshes.iter().zip(&st.grids).enumerate() {
                grid.near(&wall.mesh, p.position[i], p.radius[i] + skin, &mut near);
                st.candidates.extend(near.iter().map(|&t| (m as u32, t)));
            }
            st.start.push(st.candidates.len() as u32);
        }
        st.built_for = Some(build);
    }

    /// Adds every particle's mesh-contact loads, rounded to `quanta`, to the force and torque
    /// accumulators, raising `peak`; with `advance`, advances and stores their histories.
    pub(super) fn mesh_loads<N: NormalSubModel, T: TangentialSubModel>(
        &mut self,
        quanta: Quanta,
        advance: bool,
        peak: &mut Peak,
    ) {
        if self.meshes.is_empty() {
            return;
        }
        self.update_mesh_candidates();
        let dt = if advance { self.time_step.dt } else { 0.0 };
        let law = self.law;
        let (st, p, meshes, coeffs) = (&mut self.mesh_stage, &mut self.particles, &self.meshes, &self.coeffs);
        let old = std::mem::take(&mut st.history);
        let mut stored = Vec::with_capacity(old.len());
        let (mut contacts, mut triangles): (Vec<MeshContact>, Vec<u32>) = (Vec::new(), Vec::new());
        let mut claimed: Vec<bool> = Vec::new();
        let mut o = 0;
        for i in 0..p.len() {
            let o0 = o;
            while o < old.len() && old[o].slot as usize <= i {
                o += 1;
            }
            let mine = &old[o0..o];
            claimed.clear();
            claimed.resize(mine.len(), false);
            for (m, MeshWall { mesh, material }) in meshes.iter().enumerate() {
                let c = coeffs.wall(p.phase[i] as usize, *material);
                let reach = if N::REACHES { c.pull_off } else { 0.0 };
                st.contacts_of(
                    i,
                    (m, mesh),
                    p.position[i],
                    p.radius[i],
                    reach,
                    &mut triangles,
                    &mut contacts,
                );
                for k in contacts.iter() {
                    let overlap = k.overlap - reach;
                    let own = mine.iter().position(|h| h.mesh == m as u32 && h.triangle == k.triangle);
                    if !N::wall_touching(overlap, reach, own.is_some()) {
                        continue;
                    }
                    let from = own.or_else(|| carried(mine, &claimed, m as u32, k.normal));
                    let h = from.map_or(Vec3::ZERO, |j| {
                        claimed[j] = true;
                        mine[j].h
                    });
                    let lever = if law.lever == LeverArm::RadicalPlane { k.distance } else { p.radius[i] };
                    let input = PairInput {
                        d: -k.normal,
                        ra: overlap,
                        rb: lever,
                        dv: p.velocity[i],
                        wa: p.omega[i],
                        wb: Vec3::ZERO,
                        h,
                        c: *c,
                        m_eff: p.mass[i],
                    };
                    let (load, h_new, bound) = wall_law::<N, T, { parts::ALL }>(&law, dt, &input);
                    let round = |q: Quantum, v: Vec3| Vec3::new(q.round(v.x), q.round(v.y), q.round(v.z));
                    p.force[i] += round(quanta.force, load.f);
                    p.torque[i] += round(quanta.torque, load.ta);
                    *peak = max_peak(*peak, bound);
                    stored.push(MeshHistory {
                        slot: i as u32,
                        mesh: m as u32,
                        triangle: k.triangle,
                        normal: k.normal,
                        h: if advance { h_new } else { h },
                    });
                }
            }
        }
        // Two contacts of a particle never share an owner (`sphere_contacts` merges them), so
        // the order is that of (slot, mesh, triangle) once sorted.
        stored.sort_unstable_by_key(|h| (h.slot, h.mesh, h.triangle));
        st.history = if advance { stored } else { old };
    }
}

/// The particle's unclaimed contact of the evaluation before on mesh `mesh` whose normal is
/// closest to `normal`, if within [`CARRY_COS`].
fn carried(mine: &[MeshHistory], claimed: &[bool], mesh: u32, normal: Vec3) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (j, h) in mine.iter().enumerate() {
        let c = h.normal.dot(normal);
        if h.mesh == mesh && !claimed[j] && c >= CARRY_COS && best.is_none_or(|(_, b)| c > b) {
            best = Some((j, c));
        }
    }
    best.map(|(j, _)| j)
}
