//! Contact sources: everything a particle touches, one kind per file — particle pairs
//! ([`Pairs`]), plane walls ([`Planes`]), triangle meshes ([`Meshes`]) and cylinder walls
//! ([`Cylinders`]).
//!
//! A source keeps what its contacts need between evaluations (candidates, histories, working
//! memory) and answers for them: their loads in a force evaluation, the contacts of the state
//! for output, their part of the diagnostics, and what becomes of their histories when the
//! particles move to other slots. The simulation holds the sources in one [`Sources`] in a
//! fixed order (planes, pairs, meshes, cylinders) and loops over them with `each_source!`; adding a
//! kind of contact is one file here, a field of `Sources` and its name in `each_source!`. A
//! source with a wall also describes its surfaces for display there
//! ([`ContactSource::surfaces`], [`crate::surface`]): the output writers name no kind.
//!
//! The plane walls' and the particle pairs' candidates are found by the neighbour list in one
//! pass over its grid, and their loads are computed in one kernel (each block of particles
//! takes its own wall contacts before its rows: [`crate::forces`]): [`Pairs::loads`] runs it
//! for both, so [`Planes::loads`] adds nothing of its own. Their histories live in the list
//! too ([`crate::neighbor::NeighborState`]), so each of the two rearranges its part of it.
//!
//! Every load is rounded to the evaluation's quanta before it is added (`forces::sum`), so the
//! particles' sums are the same whichever source adds its loads first.

mod cylinders;
mod meshes;
mod pairs;
mod planes;

pub(crate) use cylinders::{Cylinders, check_cylinder};
pub use cylinders::{periodic_cylinder_message, periodic_cylinder_reach};
pub use meshes::{MeshLoad, periodic_mesh_message, periodic_mesh_reach};
pub(crate) use meshes::{Meshes, SCRIPTED_F64S};
pub(crate) use pairs::Pairs;
pub(crate) use planes::Planes;

use crate::boundary::Periodic;
use crate::contact::pair::{CommonMass, contact_coeffs, contact_reach};
use crate::contact::submodel::{NormalSubModel, TangentialSubModel};
use crate::contact::{CoeffTable, ContactCoeffs, ContactLaw};
use crate::forces::{Peak, Quanta};
use crate::math::Vec3;
use crate::neighbor::{NeighborList, NeighborState};
use crate::simulation::{ContactInfo, StageTimes};
use crate::state::Particles;
use crate::surface::{Surface, SurfaceKind, Which};
use crate::wall::Wall;

/// What a source reads of the state outside itself.
#[derive(Clone, Copy)]
pub(crate) struct View<'a> {
    pub particles: &'a Particles,
    pub law: ContactLaw,
    pub coeffs: &'a CoeffTable,
    pub periodic: Periodic,
    /// Slots held fixed (empty if none).
    pub held: &'a [bool],
    /// The neighbour list: the pairs' and plane walls' candidates and histories.
    pub neighbors: &'a NeighborList,
    /// The plane walls.
    pub walls: &'a [Wall],
    /// The time of the particles' positions, s.
    pub time: f64,
    /// The largest radius a particle of the run has or can be inserted with, m.
    pub r_max: f64,
    /// The slots from this one on are ghosts (copies of other ranks' particles): a contact is
    /// reported by the rank that owns its particle of the lower id.
    pub owned: usize,
}

/// One force evaluation, as the sources see it: the state, the accumulators they add their
/// loads to, and the evaluation's settings.
pub(crate) struct LoadRun<'a> {
    /// The particles; their force and torque accumulators take the loads (the pair kernel
    /// clears them first, so it runs first).
    pub particles: &'a mut Particles,
    pub neighbors: &'a mut NeighborList,
    pub held: &'a [bool],
    pub walls: &'a [Wall],
    pub coeffs: &'a CoeffTable,
    pub law: ContactLaw,
    pub periodic: Periodic,
    /// The mass every particle has, if all have the same.
    pub common_mass: Option<CommonMass>,
    /// The thread pool, when the evaluation runs on threads.
    pub pool: Option<&'a rayon::ThreadPool>,
    /// The quanta of the order-free sums.
    pub quanta: Quanta,
    /// Advance and store the tangential springs.
    pub advance: bool,
    /// The time step, s (the springs advance by it when `advance`).
    pub dt: f64,
    /// The time of the particles' positions, s.
    pub time: f64,
    /// The largest radius a particle of the run has or can be inserted with, m.
    pub r_max: f64,
    /// The first ghost slot (the particle count in one process).
    pub owned: usize,
    /// The largest force and torque bounds of the loads so far.
    pub peak: Peak,
    /// The stage times, when timing is on.
    pub times: Option<&'a mut StageTimes>,
}

impl LoadRun<'_> {
    /// The state as a [`View`].
    pub(crate) fn view(&self) -> View<'_> {
        View {
            particles: self.particles,
            law: self.law,
            coeffs: self.coeffs,
            periodic: self.periodic,
            held: self.held,
            neighbors: self.neighbors,
            walls: self.walls,
            time: self.time,
            r_max: self.r_max,
            owned: self.owned,
        }
    }
}

/// One diagnosed contact: its overlap, m, the smaller radius of its two sides, m, and the
/// elastic energy of its normal spring, J.
pub(crate) type Diagnosed = (f64, f64, f64);

/// Everything a particle touches of one kind.
pub(crate) trait ContactSource {
    /// Adds the loads of the source's contacts of the current state to `run`'s accumulators,
    /// each rounded to `run.quanta`, raising `run.peak`; with `run.advance`, advances and
    /// stores their tangential springs.
    fn loads<N: NormalSubModel, T: TangentialSubModel>(&mut self, run: &mut LoadRun);

    /// Appends the source's contacts of the current state with their forces, as the next
    /// evaluation would see them without advancing the springs.
    fn contact_infos(&self, v: &View, out: &mut Vec<ContactInfo>);

    /// Calls `visit` for each of the source's contacts of the current state.
    fn diagnose(&self, v: &View, visit: &mut dyn FnMut(Diagnosed));

    /// The slots renumbered: slot `k` is what slot `order[k]` was (`new_of[old]`, `u32::MAX`
    /// for a removed slot); `list` is the neighbour list's state, taken into the new slots.
    fn rearrange(&mut self, new_of: &[u32], list: &mut NeighborState);

    /// Particles appended to the `n_old` slots, up to `n`.
    fn appended(&mut self, _n_old: usize, _n: usize) {}

    /// The particles redistributed over the ranks: those of old slots with `new_of[old] !=
    /// u32::MAX` stayed on this rank, in slots `new_of[old]` (the first ones, in their order);
    /// the rest of the `n` slots are new (particles that arrived, and ghosts). Called before
    /// [`take_carried`](Self::take_carried), which gives the histories; a source may keep
    /// what it finds by slot for the particles that stayed.
    fn redistributed(&mut self, _new_of: &[u32], _n: usize) {}

    /// Heap bytes the source holds outside the neighbour list.
    fn heap_bytes(&self) -> usize {
        0
    }

    /// Words of each history record the source keeps outside the neighbour list (0: it keeps
    /// none), which travels with its particle to another rank.
    const CARRIED: usize = 0;

    /// Appends the source's histories kept outside the neighbour list, as records of
    /// [`CARRIED`](Self::CARRIED) words each, the slot of its particle first.
    fn carry(&self, _out: &mut Vec<u64>) {}

    /// Takes over histories written by [`carry`](Self::carry), with each record's first word
    /// the id of its particle instead of its slot (`ids`: the particles' ids by slot, after
    /// the particles moved between ranks); the candidates are found again at the next
    /// evaluation.
    fn take_carried(&mut self, _ids: &[u32], _records: &[u64]) -> Result<(), String> {
        Ok(())
    }

    /// The kinds of surface the source can show, in the order [`surfaces`](Self::surfaces)
    /// gives them (none: a source without a surface, like the particle pairs).
    const SURFACES: &'static [SurfaceKind] = &[];

    /// Appends the source's surfaces of `which` where they are now, for display (see
    /// [`crate::surface`]), each of one of [`SURFACES`](Self::SURFACES); the infinite walls
    /// are shown within the box [lo, hi].
    fn surfaces(
        &self,
        _sim: &crate::Simulation,
        _lo: Vec3,
        _hi: Vec3,
        _which: Which,
        _out: &mut Vec<Surface>,
    ) {
    }
}

/// The contact sources of a simulation, in the order they are evaluated and reported.
#[derive(Debug, Clone)]
pub(crate) struct Sources {
    pub planes: Planes,
    pub pairs: Pairs,
    pub meshes: Meshes,
    pub cylinders: Cylinders,
}

/// Runs `$body` with `$s` bound to each source of `$sources` (a `Sources`, by reference or
/// mutable reference), in their order.
macro_rules! each_source {
    ($sources:expr, |$s:ident| $body:expr) => {{
        let sources = $sources;
        {
            let $s = &mut sources.planes;
            $body;
        }
        {
            let $s = &mut sources.pairs;
            $body;
        }
        {
            let $s = &mut sources.meshes;
            $body;
        }
        {
            let $s = &mut sources.cylinders;
            $body;
        }
    }};
    (ref $sources:expr, |$s:ident| $body:expr) => {{
        let sources = $sources;
        {
            let $s = &sources.planes;
            $body;
        }
        {
            let $s = &sources.pairs;
            $body;
        }
        {
            let $s = &sources.meshes;
            $body;
        }
        {
            let $s = &sources.cylinders;
            $body;
        }
    }};
}

/// Runs `$body` with the type `$t` standing for each source's type, in the sources' order.
macro_rules! each_source_type {
    (|$t:ident| $body:expr) => {{
        {
            type $t = $crate::forces::source::Planes;
            $body;
        }
        {
            type $t = $crate::forces::source::Pairs;
            $body;
        }
        {
            type $t = $crate::forces::source::Meshes;
            $body;
        }
        {
            type $t = $crate::forces::source::Cylinders;
            $body;
        }
    }};
}
pub(crate) use each_source_type;

impl Sources {
    /// Every source's loads (see [`ContactSource::loads`]).
    pub(crate) fn loads<N: NormalSubModel, T: TangentialSubModel>(&mut self, run: &mut LoadRun) {
        each_source!(self, |s| s.loads::<N, T>(run));
    }

    /// Every source's contacts (see [`ContactSource::contact_infos`]).
    pub(crate) fn contact_infos(&self, v: &View) -> Vec<ContactInfo> {
        let mut out = Vec::new();
        each_source!(ref self, |s| s.contact_infos(v, &mut out));
        out
    }

    /// Every source's contacts for diagnostics (see [`ContactSource::diagnose`]).
    pub(crate) fn diagnose(&self, v: &View, visit: &mut dyn FnMut(Diagnosed)) {
        each_source!(ref self, |s| s.diagnose(v, visit));
    }

    /// See [`ContactSource::rearrange`].
    pub(crate) fn rearrange(&mut self, new_of: &[u32], list: &mut NeighborState) {
        each_source!(self, |s| s.rearrange(new_of, list));
    }

    /// See [`ContactSource::appended`].
    pub(crate) fn appended(&mut self, n_old: usize, n: usize) {
        each_source!(self, |s| s.appended(n_old, n));
    }

    /// See [`ContactSource::redistributed`].
    pub(crate) fn redistributed(&mut self, new_of: &[u32], n: usize) {
        each_source!(self, |s| s.redistributed(new_of, n));
    }

    /// Every source's section of a checkpoint, in the sources' order (see
    /// [`crate::checkpoint::Saved`]).
    pub(crate) fn save<W: std::io::Write>(
        &self,
        sim: &crate::Simulation,
        e: &mut crate::checkpoint::Enc<W>,
    ) -> std::io::Result<()> {
        use crate::checkpoint::Saved;
        each_source!(ref self, |s| s.save(sim, e)?);
        Ok(())
    }

    /// The bytes of [`save`](Self::save).
    pub(crate) fn saved_bytes(&self, sim: &crate::Simulation) -> usize {
        use crate::checkpoint::Saved;
        let mut bytes = 0;
        each_source!(ref self, |s| bytes += s.saved_bytes(sim));
        bytes
    }

    /// Every source's carried histories (see [`ContactSource::carry`]), one list per source
    /// in the sources' order, with the words per record of each.
    pub(crate) fn carry(&self) -> Vec<(usize, Vec<u64>)> {
        let mut out = Vec::new();
        each_source!(ref self, |s| {
            let mut words = Vec::new();
            s.carry(&mut words);
            out.push((carried_words(s), words));
        });
        out
    }

    /// Every source takes its carried histories (see [`ContactSource::take_carried`]), given
    /// in the order [`carry`](Self::carry) gives them.
    pub(crate) fn take_carried(&mut self, ids: &[u32], lists: &[Vec<u64>]) -> Result<(), String> {
        let mut lists = lists.iter();
        each_source!(self, |s| s.take_carried(ids, lists.next().map_or(&[][..], |l| &l[..]))?);
        Ok(())
    }

    /// See [`ContactSource::heap_bytes`].
    pub(crate) fn heap_bytes(&self) -> usize {
        let mut bytes = 0;
        each_source!(ref self, |s| bytes += s.heap_bytes());
        bytes
    }

    /// Every source's surfaces, in the sources' order (see [`ContactSource::surfaces`]).
    pub(crate) fn surfaces(&self, sim: &crate::Simulation, lo: Vec3, hi: Vec3, which: Which) -> Vec<Surface> {
        let mut out = Vec::new();
        each_source!(ref self, |s| s.surfaces(sim, lo, hi, which, &mut out));
        out
    }

    /// Every source's kinds of surface, in the sources' order (see
    /// [`ContactSource::SURFACES`]).
    pub(crate) fn surface_kinds() -> Vec<SurfaceKind> {
        let mut kinds = Vec::new();
        each_source_type!(|S| kinds.extend_from_slice(<S as ContactSource>::SURFACES));
        kinds
    }
}

/// [`ContactSource::CARRIED`] of the source `_s`.
fn carried_words<S: ContactSource>(_s: &S) -> usize {
    S::CARRIED
}

/// The terms whose sums, negated, are the load a wall takes from its contacts' loads on the
/// particles, each (the particle's centre, the force and the torque about the centre on it):
/// the force's components, then those of the torque about `about`.
pub(crate) fn wall_load_terms(parts: &[(Vec3, Vec3, Vec3)], about: Vec3) -> [Vec<f64>; 6] {
    let mut terms: [Vec<f64>; 6] = Default::default();
    for &(x, f, t) in parts {
        let m = (x - about).cross(f) + t;
        for (k, v) in f.to_array().into_iter().chain(m.to_array()).enumerate() {
            terms[k].push(v);
        }
    }
    terms
}

/// The load a wall takes from its contacts' loads on the particles (see
/// [`wall_load_terms`]), from the sums of its terms: minus the force's sum, minus the torque's
/// about `about`. The sums do not depend on the contacts' order.
pub(crate) fn wall_load(sums: [f64; 6]) -> MeshLoad {
    MeshLoad { force: -Vec3::new(sums[0], sums[1], sums[2]), torque: -Vec3::new(sums[3], sums[4], sums[5]) }
}

/// The coefficients of slot `i`'s contacts with wall material `material`: its phase's,
/// formed for its own radius and mass where the table is per unit size (the pull-off distance
/// too).
#[inline]
pub(crate) fn wall_coeffs_of(
    coeffs: &CoeffTable,
    law: &ContactLaw,
    p: &Particles,
    i: usize,
    material: usize,
) -> ContactCoeffs {
    let c = coeffs.wall(p.phase[i] as usize, material);
    if !coeffs.sized() {
        return *c;
    }
    let r = p.radius[i];
    let mut sized = contact_coeffs(coeffs, law, c, r, p.mass[i]);
    sized.pull_off = crate::with_normal_submodel!(law.normal, |N| contact_reach::<N>(coeffs, c, r));
    sized
}
