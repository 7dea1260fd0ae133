//! The loads of the touching pairs, a batch of [`LANES`] at a time: the gather of their
//! inputs from the particle arrays into one array per component, the batch loop over the
//! contact law (compiled for the common settings with only the parts of the law they pick, and
//! in AVX2 and AVX-512 copies chosen at run time where the build does not assume them), and the
//! adding of the loads to the particles in list order.
//!
//! The loop has no data-dependent branches, so it compiles to vector instructions; vector and
//! scalar instructions round alike (no fused multiply–add), so every copy gives the bits of
//! the scalar law ([`pair_law`], [`wall_law`]) on every processor.

use std::ops::Range;

use super::detect::Found;
use super::{Accumulators, CrossingLoad, ForceInputs, Peak, Quanta};
use crate::boundary::Images;
use crate::contact::law::parts;
use crate::contact::pair::{
    CommonMass, LoadBound, PairInput, PairLoad, common_pair_mass, contact_coeffs, kept_or_zero, pair_law,
    pair_mass, wall_geometry_for, wall_law,
};
use crate::contact::submodel::{NormalSubModel, TangentialSubModel};
use crate::contact::{CoeffTable, ContactCoeffs, ContactLaw};
use crate::math::Vec3;

/// Contacts in a batch: the vector width times a few, so that the loads of a batch compile to
/// a handful of vector passes.
pub(super) const LANES: usize = 16;

/// Vectors of a batch, one array per component (the layout vector instructions load).
#[derive(Debug, Clone, Copy)]
struct Vec3Lanes([[f64; LANES]; 3]);

impl Vec3Lanes {
    const ZERO: Vec3Lanes = Vec3Lanes([[0.0; LANES]; 3]);

    #[inline(always)]
    fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.0[0][i], self.0[1][i], self.0[2][i])
    }

    #[inline(always)]
    fn set(&mut self, i: usize, v: Vec3) {
        (self.0[0][i], self.0[1][i], self.0[2][i]) = (v.x, v.y, v.z);
    }
}

/// The [`PairInput`]s of a batch, component by component.
#[derive(Debug, Clone, Copy)]
pub(super) struct InputLanes {
    d: Vec3Lanes,
    dv: Vec3Lanes,
    wa: Vec3Lanes,
    wb: Vec3Lanes,
    h: Vec3Lanes,
    /// ra, rb, m_eff.
    scalars: [[f64; LANES]; 3],
    /// kn, kt, eta_n, eta_t, mu, mu_roll, r_star, surface_energy.
    coeffs: [[f64; LANES]; COEFFS],
}

impl InputLanes {
    const ZERO: InputLanes = InputLanes {
        d: Vec3Lanes::ZERO,
        dv: Vec3Lanes::ZERO,
        wa: Vec3Lanes::ZERO,
        wb: Vec3Lanes::ZERO,
        h: Vec3Lanes::ZERO,
        scalars: [[0.0; LANES]; 3],
        coeffs: [[0.0; LANES]; COEFFS],
    };

    /// Sets lane `i` to `p`.
    #[inline(always)]
    fn set(&mut self, i: usize, p: &PairInput) {
        self.d.set(i, p.d);
        self.dv.set(i, p.dv);
        self.wa.set(i, p.wa);
        self.wb.set(i, p.wb);
        self.h.set(i, p.h);
        for (lane, v) in self.scalars.iter_mut().zip([p.ra, p.rb, p.m_eff]) {
            lane[i] = v;
        }
        for (lane, v) in self.coeffs.iter_mut().zip(coeff_lanes(&p.c)) {
            lane[i] = v;
        }
    }

    /// Sets lane `i` to the pair (a, b) of slots at separation `d` (x_b − x_a, nearest image)
    /// with stored history `h`; its coefficients only if the phase pairs have their own (the
    /// coefficient lanes hold the one set all pairs share otherwise:
    /// [`fill_coeffs`](Self::fill_coeffs)).
    #[inline(always)]
    fn set_pair(&mut self, i: usize, s: &PairData, a: usize, b: usize, d: Vec3, h: Vec3) {
        let held = !s.held.is_empty();
        match (s.per_mass, held) {
            (true, true) => self.set_pair_for::<true, true>(i, s, a, b, d, h),
            (true, false) => self.set_pair_for::<true, false>(i, s, a, b, d, h),
            _ => self.set_pair_for::<false, false>(i, s, a, b, d, h),
        }
    }

    /// [`set_pair`](Self::set_pair) with `PER_MASS` if the damping takes the effective mass
    /// and `HELD` if some slots are held fixed (and so the list of held slots is not empty).
    #[inline(always)]
    fn set_pair_for<const PER_MASS: bool, const HELD: bool>(
        &mut self,
        i: usize,
        s: &PairData,
        a: usize,
        b: usize,
        d: Vec3,
        h: Vec3,
    ) {
        let n = s.position.len();
        assert!(a < n && b < n);
        self.d.set(i, d);
        self.dv.set(i, s.velocity[a] - s.velocity[b]);
        self.wa.set(i, s.omega[a]);
        self.wb.set(i, s.omega[b]);
        self.h.set(i, h);
        let m_eff = if !PER_MASS {
            0.0
        } else if let Some(CommonMass { m, both }) = s.common_mass {
            // No division per pair.
            common_pair_mass(m, both, HELD && s.held[a], HELD && s.held[b])
        } else if HELD {
            pair_mass(s.mass, s.held, a, b)
        } else {
            pair_mass(s.mass, &[], a, b)
        };
        for (lane, v) in self.scalars.iter_mut().zip([s.radius[a], s.radius[b], m_eff]) {
            lane[i] = v;
        }
        if let Some(phase) = s.phase {
            let c = s.coeffs.pair(phase[a] as usize, phase[b] as usize);
            for (lane, v) in self.coeffs.iter_mut().zip(coeff_lanes(c)) {
                lane[i] = v;
            }
        }
    }

    /// Sets the lanes of the listed pairs `group` of the rows below `r1` (a crossing pair's
    /// lane is left as it is); `hist` holds the histories of the pairs from index `k0` on.
    #[inline(always)]
    fn gather_pairs(&mut self, x: &ForceInputs, r1: usize, k0: usize, group: &[Found], hist: &[Vec3]) {
        let (per_mass, held) = (takes_mass(x), !x.held.is_empty());
        match (x.images.any(), per_mass, held) {
            (true, true, true) => self.gather_pairs_for::<true, true, true>(x, r1, k0, group, hist),
            (true, true, false) => self.gather_pairs_for::<true, true, false>(x, r1, k0, group, hist),
            (true, false, _) => self.gather_pairs_for::<true, false, false>(x, r1, k0, group, hist),
            (false, true, true) => self.gather_pairs_for::<false, true, true>(x, r1, k0, group, hist),
            (false, true, false) => self.gather_pairs_for::<false, true, false>(x, r1, k0, group, hist),
            (false, false, _) => self.gather_pairs_for::<false, false, false>(x, r1, k0, group, hist),
        }
    }

    /// [`gather_pairs`](Self::gather_pairs) for a domain with periodic axes (`PERIODIC`),
    /// damping that takes the contact's effective mass (`PER_MASS`) and slots held fixed
    /// (`HELD`), or without: the choices made once, not for each pair. Not inlined into the
    /// batch loop (one copy per choice serves every law): on its own, its loop keeps the
    /// arrays' addresses in registers, where the inlined loop reloaded them for each pair.
    #[inline(never)]
    fn gather_pairs_for<const PERIODIC: bool, const PER_MASS: bool, const HELD: bool>(
        &mut self,
        x: &ForceInputs,
        r1: usize,
        k0: usize,
        group: &[Found],
        hist: &[Vec3],
    ) {
        let s = PairData::of(x);
        let kept_apart = x.law.history.kept_apart();
        let group = &group[..group.len().min(LANES)];
        for (i, f) in group.iter().enumerate() {
            let (a, b) = (f.a as usize, x.partners[f.k()] as usize);
            if b < r1 {
                // The separation again, rather than kept from the contact test: the listing
                // stays small, and these positions are in cache.
                let d = s.position[b] - s.position[a];
                let d = if PERIODIC { s.images.nearest_on_periodic_axes(d) } else { d };
                let h = kept_or_zero(hist[f.k() - k0], !f.fresh() || kept_apart);
                self.set_pair_for::<PER_MASS, HELD>(i, &s, a, b, d, h);
            }
        }
    }

    /// Sets the coefficients of every lane to `c`.
    pub(super) fn fill_coeffs(&mut self, c: &ContactCoeffs) {
        for (lane, v) in self.coeffs.iter_mut().zip(coeff_lanes(c)) {
            *lane = [v; LANES];
        }
    }

    #[inline(always)]
    fn get(&self, i: usize) -> PairInput {
        // Indexed one by one: `map` over the arrays would copy them and keep the loop scalar.
        let (v, c) = (&self.scalars, &self.coeffs);
        let [ra, rb, m_eff] = [v[0][i], v[1][i], v[2][i]];
        let [kn, kt, eta_n, eta_t, mu, mu_roll] = [c[0][i], c[1][i], c[2][i], c[3][i], c[4][i], c[5][i]];
        let [r_star, surface_energy] = [c[6][i], c[7][i]];
        PairInput {
            d: self.d.get(i),
            ra,
            rb,
            dv: self.dv.get(i),
            wa: self.wa.get(i),
            wb: self.wb.get(i),
            h: self.h.get(i),
            c: ContactCoeffs {
                kn,
                kt,
                eta_n,
                eta_t,
                mu,
                mu_roll,
                m_eff: 0.0,
                r_star,
                surface_energy,
                pull_off: 0.0,
            },
            m_eff,
        }
    }
}

/// The coefficients the law reads, in the order of [`InputLanes::coeffs`] (the pull-off
/// distance is the contact test's, not the law's).
#[inline(always)]
fn coeff_lanes(c: &ContactCoeffs) -> [f64; COEFFS] {
    [c.kn, c.kt, c.eta_n, c.eta_t, c.mu, c.mu_roll, c.r_star, c.surface_energy]
}

/// Coefficients in a lane.
const COEFFS: usize = 8;

/// The loads and advanced histories of a batch, component by component; once computed, the
/// loads are rounded to the quanta of the sums (`forces::sum`).
#[derive(Debug, Clone, Copy)]
struct OutputLanes {
    f: Vec3Lanes,
    ta: Vec3Lanes,
    tb: Vec3Lanes,
    h: Vec3Lanes,
    /// Each lane's bounds of its force's and its torques' magnitudes ([`LoadBound`]).
    bound: [[f64; LANES]; 2],
}

impl OutputLanes {
    const ZERO: OutputLanes = OutputLanes {
        f: Vec3Lanes::ZERO,
        ta: Vec3Lanes::ZERO,
        tb: Vec3Lanes::ZERO,
        h: Vec3Lanes::ZERO,
        bound: [[0.0; LANES]; 2],
    };

    #[inline(always)]
    fn set(&mut self, i: usize, (l, h, b): (PairLoad, Vec3, LoadBound)) {
        self.f.set(i, l.f);
        self.ta.set(i, l.ta);
        self.tb.set(i, l.tb);
        self.h.set(i, h);
        self.bound[0][i] = b[0];
        self.bound[1][i] = b[1];
    }

    /// Rounds the loads to the quanta `q`, raising the lanes' peaks `peak` (force, torque) by
    /// the load bounds of the lanes where `live` is 1 (0: a lane that holds what an earlier
    /// batch left, or a crossing pair's, which the pass over the crossing pairs computed).
    #[inline(always)]
    fn round(&mut self, q: Quanta, live: &Live, peak: &mut PeakLanes) {
        for k in 0..3 {
            q.force.round_all(&mut self.f.0[k]);
            q.torque.round_all(&mut self.ta.0[k]);
            q.torque.round_all(&mut self.tb.0[k]);
        }
        for (peak, bound) in peak.iter_mut().zip(&self.bound) {
            raise_peaks(peak, bound, live);
        }
    }

    /// The load of lane `i`.
    #[inline(always)]
    fn load(&self, i: usize) -> PairLoad {
        PairLoad { f: self.f.get(i), ta: self.ta.get(i), tb: self.tb.get(i) }
    }
}

/// Raises each `peak[i]` to `bound[i]` where `live[i]` is 1. A loop that compiles to vector
/// instructions (no branch, and every lane's peak stored); a NaN bound leaves the peak as it
/// is.
#[inline(always)]
fn raise_peaks(peak: &mut [f64; LANES], bound: &[f64; LANES], live: &Live) {
    for ((p, &b), &m) in peak.iter_mut().zip(bound).zip(live) {
        let b = b * m;
        *p = if b > *p { b } else { *p };
    }
}

/// The largest force and torque bounds, lane by lane, of the loads of the batches so far.
type PeakLanes = [[f64; LANES]; 2];

/// 1 for the lanes of a batch that hold a load of this evaluation's own, 0 for the others.
type Live = [f64; LANES];

/// The first `n` lanes live.
#[inline(always)]
fn first_live(n: usize) -> Live {
    std::array::from_fn(|i| if i < n { 1.0 } else { 0.0 })
}

/// The inputs and outputs of a batch of touching pairs, and the peaks of the loads of the
/// batches so far.
pub(super) struct Lanes {
    pub(super) input: InputLanes,
    output: OutputLanes,
    peak: PeakLanes,
}

impl Lanes {
    pub(super) fn new() -> Self {
        Lanes { input: InputLanes::ZERO, output: OutputLanes::ZERO, peak: [[0.0; LANES]; 2] }
    }

    /// Forgets the peaks of the batches so far (a new evaluation begins).
    pub(super) fn clear_peaks(&mut self) {
        self.peak = [[0.0; LANES]; 2];
    }

    /// The largest force and torque bounds of the loads computed so far.
    pub(super) fn peak(&self) -> Peak {
        self.peak.map(|lanes| lanes.iter().fold(0.0, |m: f64, &v| if v > m { v } else { m }))
    }

    /// The loads of the batch in the input lanes ([`contact_loads`]), into the output lanes,
    /// rounded for the sums, the peaks raised by those of the `live` lanes; a wall batch with
    /// `WALL`.
    #[inline(always)]
    fn compute<N: NormalSubModel, T: TangentialSubModel, const WALL: bool>(
        &mut self,
        x: &ForceInputs,
        live: &Live,
    ) {
        contact_loads::<N, T, WALL>(
            &x.law,
            x.coeffs.rolling(),
            x.coeffs.sized(),
            x.dt,
            Some((x.quanta, live, &mut self.peak)),
            &self.input,
            &mut self.output,
        )
    }

    /// The history to store for pair lane `lane`, whose advanced history is `h`: `h`, or the
    /// input's when the springs are not advanced (so a fresh contact's history becomes zero).
    #[inline(always)]
    fn stored_history(&self, x: &ForceInputs, lane: usize, h: Vec3) -> Vec3 {
        if x.advance { h } else { self.input.h.get(lane) }
    }

    /// Computes the loads of the listed pairs `group` (at most [`LANES`]) of the block's
    /// `rows` and adds them, in order, to the rows' accumulators, storing the histories in
    /// `hist` (those of the rows' pairs). A crossing pair takes its load from `crossing`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn add_loads<N: NormalSubModel, T: TangentialSubModel>(
        &mut self,
        x: &ForceInputs,
        rows: Range<usize>,
        group: &[Found],
        crossing: &mut std::slice::Iter<CrossingLoad>,
        acc: &mut Accumulators,
        hist: &mut [Vec3],
    ) {
        let (r0, r1) = (rows.start, rows.end);
        let k0 = x.offsets[r0];
        self.input.gather_pairs(x, r1, k0, group, hist);
        let mut live = [0.0; LANES];
        for (l, f) in live.iter_mut().zip(group) {
            *l = if (x.partners[f.k()] as usize) < r1 { 1.0 } else { 0.0 };
        }
        self.compute::<N, T, false>(x, &live);
        for (i, f) in group.iter().enumerate() {
            let (a, b, k) = (f.a as usize, x.partners[f.k()] as usize, f.k());
            let l = if b < r1 {
                let l = self.output.load(i);
                hist[k - k0] = self.stored_history(x, i, self.output.h.get(i));
                acc.add::<true>(b - r0, l.f, l.tb);
                l
            } else {
                match crossing.next() {
                    Some(Some(l)) => *l,
                    _ => continue,
                }
            };
            acc.add::<false>(a - r0, l.f, l.ta);
        }
    }

    /// The loads of crossing pairs `pairs` (at most [`LANES`]; row a and pair index k each)
    /// into `loads` (None for a pair that does not touch), their contact flags set and their
    /// histories stored in `hist` and `flags` (those of the pairs from index `k0` on). Like
    /// the contact test, without a branch on its outcome: every pair takes the next lane, which
    /// only a touching pair keeps.
    #[inline(always)]
    pub(super) fn crossing_loads<N: NormalSubModel, T: TangentialSubModel>(
        &mut self,
        x: &ForceInputs,
        pairs: &[(u32, usize)],
        k0: usize,
        hist: &mut [Vec3],
        flags: &mut [bool],
        loads: &mut [CrossingLoad],
    ) {
        let s = PairData::of(x);
        let mut kept = [0usize; LANES];
        let kept_apart = x.law.history.kept_apart();
        let mut n = 0;
        for (i, &(a, k)) in pairs.iter().enumerate() {
            let (a, b) = (a as usize, x.partners[k] as usize);
            let d = s.separation(a, b);
            let flag = &mut flags[k - k0];
            let reach = if N::REACHES { super::detect::pair_reach::<N>(x, a, b) } else { 0.0 };
            let touching = N::touching(d.length_squared(), s.radius[a], s.radius[b], reach, *flag);
            let fresh = !*flag;
            *flag = touching;
            loads[i] = None;
            let keep = !fresh || kept_apart;
            self.input.set_pair(n, &s, a, b, d, kept_or_zero(hist[k - k0], keep));
            kept[n] = i;
            n += touching as usize;
        }
        if n == 0 {
            return;
        }
        self.compute::<N, T, false>(x, &first_live(n));
        for (lane, &i) in kept[..n].iter().enumerate() {
            let k = pairs[i].1;
            hist[k - k0] = self.stored_history(x, lane, self.output.h.get(lane));
            loads[i] = Some(self.output.load(lane));
        }
    }

    /// As [`add_loads`](Self::add_loads), for the listed wall pairs `group` (indices into
    /// `wall_pairs`, whose histories are `hist`).
    #[inline(always)]
    pub(super) fn add_wall_loads<N: NormalSubModel, T: TangentialSubModel>(
        &mut self,
        x: &ForceInputs,
        r0: usize,
        wall_pairs: &[[u32; 2]],
        group: &[usize],
        acc: &mut Accumulators,
        hist: &mut [Vec3],
    ) {
        let mut live = [0.0; LANES];
        for (lane, &j) in group.iter().enumerate() {
            let [i, w] = wall_pairs[j];
            let (i, wall) = (i as usize, &x.walls[w as usize]);
            if let Some(g) = wall_geometry_for::<N>(x.position[i], x.radius[i], wall, x.law.lever) {
                live[lane] = 1.0;
                let input = PairInput {
                    d: g.normal,
                    ra: g.overlap,
                    rb: g.lever_i,
                    dv: x.velocity[i],
                    wa: x.omega[i],
                    wb: Vec3::ZERO,
                    h: hist[j],
                    c: contact_coeffs(
                        x.coeffs,
                        &x.law,
                        x.coeffs.wall(x.phase[i] as usize, wall.material),
                        x.radius[i],
                        x.mass[i],
                    ),
                    m_eff: x.mass[i],
                };
                self.input.set(lane, &input);
            }
        }
        self.compute::<N, T, true>(x, &live);
        for (lane, &j) in group.iter().enumerate() {
            let i = wall_pairs[j][0] as usize;
            let l = self.output.load(lane);
            if x.advance {
                hist[j] = self.output.h.get(lane);
            }
            acc.add::<false>(i - r0, l.f, l.ta);
        }
    }
}

/// LAMMPS's `granular hertz/material … tangential mindlin … damping tsuji` (the rotated
/// history, its Coulomb cap, Tsuji damping): the Hertz–Mindlin yardstick case.
const LAMMPS_MINDLIN: u8 = parts::LAMMPS_CAP | parts::ROTATE | parts::TSUJI;

/// LIGGGHTS's `hertz tangential history` (its Coulomb cap, damping per √m_eff).
const LIGGGHTS_HERTZ: u8 = parts::LIGGGHTS_CAP | parts::TSUJI;

/// MFIX's law: its Coulomb cap and lever arms to the radical plane.
const MFIX: u8 = parts::MFIX_CAP | parts::RADICAL;

/// Every part, pairs' coefficients per unit size included.
const ALL_SIZED: u8 = parts::ALL | parts::SIZED;

/// The loads of a batch of touching pairs ([`pair_law`] on every lane) or, with `WALL`, of
/// particles touching walls ([`wall_law`]); `rolling` if some contact has rolling friction,
/// `sized` if the pairs' coefficients are per unit size (a wall batch's are its contacts').
///
/// The loop has no branches, so it compiles to vector instructions. It is compiled for the
/// settings most runs use — LAMMPS's `gran/hooke/history` and `granular … mindlin … tsuji`,
/// LIGGGHTS's `hooke/stiffness` and `hertz` with `tangential history`, MFIX's law — with only the parts of the law they pick ([`parts`]), and once for any
/// settings, with and without sizes of their own; the values are the same.
#[inline(always)]
fn contact_loads<N: NormalSubModel, T: TangentialSubModel, const WALL: bool>(
    law: &ContactLaw,
    rolling: bool,
    sized: bool,
    dt: f64,
    q: Option<(Quanta, &Live, &mut PeakLanes)>,
    input: &InputLanes,
    output: &mut OutputLanes,
) {
    match parts::needed(law, rolling, sized && !WALL) {
        parts::LAMMPS_CAP => loads_widest::<N, T, WALL, { parts::LAMMPS_CAP }>(law, dt, q, input, output),
        LAMMPS_MINDLIN => loads_widest::<N, T, WALL, LAMMPS_MINDLIN>(law, dt, q, input, output),
        MFIX => loads_widest::<N, T, WALL, MFIX>(law, dt, q, input, output),
        parts::LIGGGHTS_CAP => loads_widest::<N, T, WALL, { parts::LIGGGHTS_CAP }>(law, dt, q, input, output),
        LIGGGHTS_HERTZ => loads_widest::<N, T, WALL, LIGGGHTS_HERTZ>(law, dt, q, input, output),
        p if p & parts::SIZED != 0 => loads_widest::<N, T, WALL, ALL_SIZED>(law, dt, q, input, output),
        _ => loads_widest::<N, T, WALL, { parts::ALL }>(law, dt, q, input, output),
    }
}

/// [`loads_lanes`], in a copy compiled for AVX-512 or AVX2 where the processor has them and
/// the build does not assume them. Vector and scalar instructions round alike (IEEE 754, no
/// fused multiply–add), so every copy gives the same bits.
#[inline(always)]
fn loads_widest<N: NormalSubModel, T: TangentialSubModel, const WALL: bool, const PARTS: u8>(
    law: &ContactLaw,
    dt: f64,
    q: Option<(Quanta, &Live, &mut PeakLanes)>,
    input: &InputLanes,
    output: &mut OutputLanes,
) {
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx512f")))]
    #[allow(unsafe_code)]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the processor has AVX-512F (checked just above).
        return unsafe { simd::loads_avx512::<N, T, WALL, PARTS>(law, dt, q, input, output) };
    }
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
    #[allow(unsafe_code)]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2 (checked just above).
        return unsafe { simd::loads_avx2::<N, T, WALL, PARTS>(law, dt, q, input, output) };
    }
    loads_lanes::<N, T, WALL, PARTS>(law, dt, q, input, output)
}

/// The loads of the batch; with `q` (the quanta, the count of live lanes and the peaks),
/// rounded for the sums (`forces::sum`) and the peaks raised.
#[inline(always)]
fn loads_lanes<N: NormalSubModel, T: TangentialSubModel, const WALL: bool, const PARTS: u8>(
    law: &ContactLaw,
    dt: f64,
    q: Option<(Quanta, &Live, &mut PeakLanes)>,
    input: &InputLanes,
    output: &mut OutputLanes,
) {
    let law = *law;
    for i in 0..LANES {
        let p = input.get(i);
        let load =
            if WALL { wall_law::<N, T, PARTS>(&law, dt, &p) } else { pair_law::<N, T, PARTS>(&law, dt, &p) };
        output.set(i, load);
    }
    if let Some((q, live, peak)) = q {
        output.round(q, live, peak);
    }
}

/// [`loads_lanes`] compiled for wider vector units than the build assumes.
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx512f")))]
mod simd {
    use super::*;

    #[target_feature(enable = "avx512f")]
    pub(super) fn loads_avx512<
        N: NormalSubModel,
        T: TangentialSubModel,
        const WALL: bool,
        const PARTS: u8,
    >(
        law: &ContactLaw,
        dt: f64,
        q: Option<(Quanta, &Live, &mut PeakLanes)>,
        input: &InputLanes,
        output: &mut OutputLanes,
    ) {
        loads_lanes::<N, T, WALL, PARTS>(law, dt, q, input, output)
    }

    #[cfg(not(target_feature = "avx2"))]
    #[target_feature(enable = "avx2")]
    pub(super) fn loads_avx2<N: NormalSubModel, T: TangentialSubModel, const WALL: bool, const PARTS: u8>(
        law: &ContactLaw,
        dt: f64,
        q: Option<(Quanta, &Live, &mut PeakLanes)>,
        input: &InputLanes,
        output: &mut OutputLanes,
    ) {
        loads_lanes::<N, T, WALL, PARTS>(law, dt, q, input, output)
    }
}

/// What the force stage reads of the particles for a pair's lane: the per-particle arrays, cut
/// to one length (so that one check of a slot covers them all), and the settings that decide
/// what the lane holds.
#[derive(Clone, Copy)]
struct PairData<'a> {
    position: &'a [Vec3],
    velocity: &'a [Vec3],
    omega: &'a [Vec3],
    radius: &'a [f64],
    mass: &'a [f64],
    /// Slots held fixed (empty if none).
    held: &'a [bool],
    /// The phases, if the phase pairs have coefficients of their own.
    phase: Option<&'a [u32]>,
    coeffs: &'a CoeffTable,
    /// The law takes the contact's effective mass ([`takes_mass`]).
    per_mass: bool,
    /// See [`ForceInputs::common_mass`].
    common_mass: Option<CommonMass>,
    images: Images,
}

/// True if a pair's law takes its effective mass: damping that scales with it, or
/// coefficients per unit size formed for it.
#[inline(always)]
fn takes_mass(x: &ForceInputs) -> bool {
    x.law.damping.per_particle_mass() || x.coeffs.sized()
}

impl<'a> PairData<'a> {
    #[inline(always)]
    fn of(x: &ForceInputs<'a>) -> Self {
        let n = x.position.len();
        PairData {
            position: x.position,
            velocity: &x.velocity[..n],
            omega: &x.omega[..n],
            radius: &x.radius[..n],
            mass: &x.mass[..n],
            held: if x.held.is_empty() { &[] } else { &x.held[..n] },
            phase: x.coeffs.uniform_pair().is_none().then(|| &x.phase[..n]),
            coeffs: x.coeffs,
            per_mass: takes_mass(x),
            common_mass: x.common_mass,
            images: x.images,
        }
    }

    /// x_b − x_a, the nearest image on periodic axes.
    #[inline(always)]
    fn separation(&self, a: usize, b: usize) -> Vec3 {
        self.images.nearest(self.position[b] - self.position[a])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{CoulombCap, HistoryFrame, LeverArm, NormalDamping};

    /// A small deterministic generator (xorshift64*), enough to spread inputs over their ranges.
    struct Rng(u64);

    impl Rng {
        fn unit(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.unit()
        }
        fn vec(&mut self, scale: f64) -> Vec3 {
            Vec3::new(self.range(-scale, scale), self.range(-scale, scale), self.range(-scale, scale))
        }
    }

    /// Touching pairs and wall contacts of every kind the law distinguishes: sticking and
    /// sliding, zero and non-zero history, with and without rolling friction.
    fn random_inputs(rng: &mut Rng) -> InputLanes {
        let mut lanes = InputLanes::ZERO;
        for i in 0..LANES {
            let (ra, rb) = (rng.range(0.5e-3, 1.5e-3), rng.range(0.5e-3, 1.5e-3));
            let dir = rng.vec(1.0).normalize_or(Vec3::X);
            let d = dir * (ra + rb) * rng.range(0.97, 0.9999);
            let h = if i % 4 == 0 { Vec3::ZERO } else { rng.vec(1e-4) };
            let kn = rng.range(1e3, 1e6);
            let c = ContactCoeffs {
                kn,
                kt: kn * rng.range(0.0, 1.0),
                eta_n: rng.range(0.0, 10.0),
                eta_t: rng.range(0.0, 10.0),
                mu: if i % 3 == 0 { 0.0 } else { rng.range(0.01, 1.0) },
                mu_roll: if i % 2 == 0 { 0.0 } else { rng.range(0.0, 1e-4) },
                m_eff: 0.0,
                // JKR's (the other laws do not read them); drawn from no random numbers, so
                // that the other laws' inputs are as before.
                r_star: ra * rb / (ra + rb),
                surface_energy: 1e-3 * (1 + i) as f64,
                pull_off: 0.0,
            };
            let p = PairInput {
                d,
                ra,
                rb,
                dv: rng.vec(1.0) - rng.vec(1.0),
                wa: if i % 5 == 0 { Vec3::ZERO } else { rng.vec(100.0) },
                wb: rng.vec(100.0),
                h,
                c,
                m_eff: rng.range(1e-6, 1e-3),
            };
            lanes.set(i, &p);
        }
        lanes
    }

    fn bits(o: &OutputLanes) -> Vec<u64> {
        [o.f, o.ta, o.tb, o.h].iter().flat_map(|v| v.0.iter().flatten().map(|x| x.to_bits())).collect()
    }

    /// The bits of the pair and wall loads of `input` by every copy of the loop for `PARTS`
    /// that is built and that this processor runs: the build's own, AVX2, AVX-512.
    #[allow(unsafe_code)]
    fn every_copy<N: NormalSubModel, T: TangentialSubModel, const PARTS: u8>(
        law: &ContactLaw,
        dt: f64,
        input: &InputLanes,
    ) -> Vec<(&'static str, [Vec<u64>; 2])> {
        let mut batch = OutputLanes::ZERO;
        let mut run = |f: &dyn Fn(&mut OutputLanes, bool)| {
            f(&mut batch, false);
            let pair = bits(&batch);
            f(&mut batch, true);
            [pair, bits(&batch)]
        };
        // Pushed to below only where the build does not assume AVX2 or AVX-512.
        #[allow(unused_mut)]
        let mut copies = vec![(
            "the build's instruction set",
            run(&|out, wall| {
                if wall {
                    loads_lanes::<N, T, true, PARTS>(law, dt, None, input, out)
                } else {
                    loads_lanes::<N, T, false, PARTS>(law, dt, None, input, out)
                }
            }),
        )];
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY (both calls): the processor has AVX2.
            copies.push((
                "AVX2",
                run(&|out, wall| unsafe {
                    if wall {
                        simd::loads_avx2::<N, T, true, PARTS>(law, dt, None, input, out)
                    } else {
                        simd::loads_avx2::<N, T, false, PARTS>(law, dt, None, input, out)
                    }
                }),
            ));
        }
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx512f")))]
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY (both calls): the processor has AVX-512F.
            copies.push((
                "AVX-512",
                run(&|out, wall| unsafe {
                    if wall {
                        simd::loads_avx512::<N, T, true, PARTS>(law, dt, None, input, out)
                    } else {
                        simd::loads_avx512::<N, T, false, PARTS>(law, dt, None, input, out)
                    }
                }),
            ));
        }
        copies
    }

    /// Every law variant: each lane of the batched loads is, to the bit, the scalar law of that
    /// lane, whichever instruction set computes the batch (scalar, AVX2, AVX-512 where the
    /// processor has them). This is what makes results independent of the machine's vector
    /// width, and equal to the particle-by-particle form of the law.
    fn batches_equal_lane_by_lane<N: NormalSubModel, T: TangentialSubModel>() {
        let (normal, tangential) = (N::MODEL, T::MODEL);
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut cases = 0;
        for history in
            [HistoryFrame::Mfix, HistoryFrame::Project, HistoryFrame::Rotate, HistoryFrame::Liggghts]
        {
            for lever in
                [LeverArm::RadicalPlane, LeverArm::Radius, LeverArm::LammpsGranular, LeverArm::Liggghts]
            {
                for damping in [
                    NormalDamping::Mfix,
                    NormalDamping::ExactRestitution,
                    NormalDamping::MassVelocity,
                    NormalDamping::Tsuji,
                    NormalDamping::Liggghts,
                ] {
                    for (clip_attraction, coulomb) in [
                        (false, CoulombCap::Mfix),
                        (true, CoulombCap::Lammps),
                        (true, CoulombCap::Mfix),
                        (false, CoulombCap::Liggghts),
                    ] {
                        let law = ContactLaw {
                            normal,
                            tangential,
                            history,
                            lever,
                            damping,
                            clip_attraction,
                            coulomb,
                            sizes: crate::contact::ContactSizes::Own,
                        };
                        let dt = 1e-6;
                        for k in 0..8 {
                            let mut input = random_inputs(&mut rng);
                            // Every other batch without rolling friction, so that the loops
                            // compiled for fewer parts of the law are checked too.
                            let rolling = k % 2 == 0;
                            if !rolling {
                                input.coeffs[5] = [0.0; LANES];
                            }
                            // Half of them with the pairs' coefficients per unit size.
                            let sized = (k / 2) % 2 == 1;
                            let mut scalar = OutputLanes::ZERO;
                            let mut wall_scalar = OutputLanes::ZERO;
                            for i in 0..LANES {
                                // One lane at a time (`black_box` keeps the compiler from
                                // turning this loop into vector code as well), every part of
                                // the law compiled.
                                let p = std::hint::black_box(input.get(i));
                                let pair = if sized {
                                    pair_law::<N, T, ALL_SIZED>(&law, dt, &p)
                                } else {
                                    pair_law::<N, T, { parts::ALL }>(&law, dt, &p)
                                };
                                scalar.set(i, pair);
                                wall_scalar.set(i, wall_law::<N, T, { parts::ALL }>(&law, dt, &p));
                            }
                            let expected = [bits(&scalar), bits(&wall_scalar)];
                            let mut batch = OutputLanes::ZERO;
                            contact_loads::<N, T, false>(&law, rolling, sized, dt, None, &input, &mut batch);
                            assert_eq!(bits(&batch), expected[0], "{law:?}");
                            contact_loads::<N, T, true>(&law, rolling, sized, dt, None, &input, &mut batch);
                            assert_eq!(bits(&batch), expected[1], "{law:?} (walls)");
                            // Every loop compiled for parts that include the law's, on every
                            // instruction set.
                            let needed = parts::needed(&law, rolling, sized);
                            let sets = [
                                parts::LAMMPS_CAP,
                                LAMMPS_MINDLIN,
                                MFIX,
                                parts::LIGGGHTS_CAP,
                                LIGGGHTS_HERTZ,
                                parts::ALL,
                                ALL_SIZED,
                            ];
                            for p in sets {
                                // Sizing is not a part a loop may have unneeded: it changes the
                                // coefficients.
                                if needed & !p != 0 || (p ^ needed) & parts::SIZED != 0 {
                                    continue;
                                }
                                let copies = match p {
                                    parts::LAMMPS_CAP => {
                                        every_copy::<N, T, { parts::LAMMPS_CAP }>(&law, dt, &input)
                                    }
                                    LAMMPS_MINDLIN => every_copy::<N, T, LAMMPS_MINDLIN>(&law, dt, &input),
                                    MFIX => every_copy::<N, T, MFIX>(&law, dt, &input),
                                    parts::LIGGGHTS_CAP => {
                                        every_copy::<N, T, { parts::LIGGGHTS_CAP }>(&law, dt, &input)
                                    }
                                    LIGGGHTS_HERTZ => every_copy::<N, T, LIGGGHTS_HERTZ>(&law, dt, &input),
                                    ALL_SIZED => every_copy::<N, T, ALL_SIZED>(&law, dt, &input),
                                    _ => every_copy::<N, T, { parts::ALL }>(&law, dt, &input),
                                };
                                for (copy, got) in copies {
                                    assert_eq!(got, expected, "{law:?}, parts {p:#b}, {copy}");
                                }
                            }
                            cases += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(cases, 4 * 4 * 5 * 4 * 8);
    }

    /// Every pair of the registries' models (`normal_models!`, `tangential_models!`).
    #[test]
    fn batched_loads_equal_the_scalar_law_on_every_instruction_set() {
        use crate::contact::{NormalModel, TangentialModel};
        let mut laws = 0;
        for &normal in NormalModel::ALL {
            for &tangential in TangentialModel::ALL {
                let law = ContactLaw { tangential, ..ContactLaw::mfix(normal) };
                crate::with_submodels!(law, |N, T| batches_equal_lane_by_lane::<N, T>());
                laws += 1;
            }
        }
        assert_eq!(laws, NormalModel::ALL.len() * TangentialModel::ALL.len());
    }
}
