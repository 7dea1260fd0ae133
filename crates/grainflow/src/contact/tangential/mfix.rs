//! MFIX 21.3's tangential spring, on the total tangential displacement.

use super::TangentialSubModel;
use crate::contact::{HistoryFrame, TangentialModel};
use crate::math::{Vec3, pick};

/// MFIX 21.3's tangential spring: the history is the total tangential displacement s;
/// F_t = −k·s − η_t·v_t, capped at μ·F.
#[derive(Debug, Clone, Copy, Default)]
pub struct MfixTotal;

impl TangentialSubModel for MfixTotal {
    const MODEL: TangentialModel = TangentialModel::MfixTotal;
    const NAME: &'static str = "mfix";
    const DESCRIPTION: &'static str = "MFIX 21.3's spring on the stored total tangential displacement";
    const HISTORY: usize = 3;

    #[inline(always)]
    fn force(
        h: Vec3,
        n: Vec3,
        v_t: Vec3,
        k: f64,
        damp_t: f64,
        limit: f64,
        lammps: bool,
        liggghts: bool,
        frame: HistoryFrame,
        dt: f64,
    ) -> (Vec3, Vec3) {
        let s = h + dt * v_t;
        let s = pick(frame.projected(), s - s.dot(n) * n, s);
        let spring = -k * s;
        let trial = spring - damp_t * v_t;
        let len = s.length();
        let dir = s / len;
        let lammps_capped = (limit / trial.length()) * trial;
        // LIGGGHTS compares the spring alone, k·|s|, with the limit and drops the dashpot when
        // it slides.
        let liggghts_capped = (limit / (k * len)) * spring;
        let capped = pick(liggghts, liggghts_capped, pick(lammps, lammps_capped, -limit * dir));
        let capped_stored = pick(
            liggghts,
            -liggghts_capped / k,
            pick(lammps, -(lammps_capped + damp_t * v_t) / k, (limit / k) * dir),
        );
        let capped_stored = pick(k > 0.0, capped_stored, Vec3::ZERO);
        let tested = pick(liggghts, spring, trial);
        let sliding = tested.length_squared() > limit * limit;
        let stuck = s.length_squared() == 0.0;
        (
            pick(sliding, pick(stuck, Vec3::ZERO, capped), trial),
            pick(sliding, pick(stuck, Vec3::ZERO, capped_stored), s),
        )
    }
}
