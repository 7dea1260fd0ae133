//! The incremental Mindlin tangential spring, on the elastic tangential force.

use super::TangentialSubModel;
use crate::contact::{HistoryFrame, TangentialModel};
use crate::math::{Vec3, pick};

/// The incremental Mindlin spring: the history is the elastic tangential force, incremented
/// by −k(δ)·v_t·Δt each step; F_t = history − η_t·v_t, capped at μ·F. Identical to
/// [`MfixTotal`](super::MfixTotal) for the linear law.
#[derive(Debug, Clone, Copy, Default)]
pub struct IncrementalMindlin;

impl TangentialSubModel for IncrementalMindlin {
    const MODEL: TangentialModel = TangentialModel::IncrementalMindlin;
    const NAME: &'static str = "incremental_mindlin";
    const DESCRIPTION: &'static str = "the incremental Mindlin spring on the stored elastic tangential force";
    const HISTORY: usize = 3;

    #[inline(always)]
    fn force(
        h: Vec3,
        _n: Vec3,
        v_t: Vec3,
        k: f64,
        damp_t: f64,
        limit: f64,
        lammps: bool,
        liggghts: bool,
        _frame: HistoryFrame,
        dt: f64,
    ) -> (Vec3, Vec3) {
        let f_el = h - k * dt * v_t;
        let trial = f_el - damp_t * v_t;
        let len = f_el.length();
        // Beyond the limit: LAMMPS scales the trial force down, MFIX and LIGGGHTS the spring
        // (LIGGGHTS also tests the spring alone against the limit).
        let lammps_capped = (limit / trial.length()) * trial;
        let mfix_capped = (limit / len) * f_el;
        let capped = pick(lammps, lammps_capped, mfix_capped);
        let capped_stored = pick(lammps, lammps_capped + damp_t * v_t, mfix_capped);
        let tested = pick(liggghts, f_el, trial);
        let sliding = tested.length_squared() > limit * limit;
        // |f_el| = 0 exactly when |f_el|² = 0: no square root where only LAMMPS's cap is used.
        let stuck = f_el.length_squared() == 0.0;
        (
            pick(sliding, pick(stuck, Vec3::ZERO, capped), trial),
            pick(sliding, pick(stuck, Vec3::ZERO, capped_stored), f_el),
        )
    }
}
