//! Sums of the contact loads that do not depend on their order.
//!
//! A particle's force is the sum of its contacts' loads. Floating-point addition is not
//! associative, so a sum taken in another order — other slots after a re-sort, other thread
//! blocks, another split of the particles over processes — would differ in its last bits and,
//! in a chaotic granular flow, soon in everything. So every load is first rounded to a multiple
//! of a quantum `Q`, a power of two ([`Quantum::round`]); sums of such multiples are exact
//! while they stay below 2⁵³·`Q`, hence the same in any order. This is fixed-point arithmetic
//! (AMBER's GPU engine sums its forces in 64-bit integers for the same reason), carried in
//! `f64`s so that it costs two additions a component and no conversions.
//!
//! The quantum follows the loads: each evaluation takes it from the peak of the evaluation
//! before (`peak`; a maximum, so the same in any order too), as `Q = 2^⌈log₂ peak⌉ · 2⁻⁴¹`.
//! The peak is that of bounds the law gives with each load rather than of the loads'
//! components, which would cost a comparison per component: a force's magnitude is at most
//! |F_n| + μ·F_c (the tangential force never exceeds its Coulomb limit), a torque's at most
//! the longer lever arm times μ·F_c plus the rolling torque's size. A load is then resolved to
//! about 2⁻⁴² of the largest load of the system (a bed's weakest contacts to its strongest as
//! double precision resolves one in 10¹² or so), and the sums stay exact while a load grows
//! less than 2¹⁰-fold from one evaluation to the next and a particle's sum stays below
//! 2¹²·peak. A force stage that exceeds that is
//! counted ([`Quanta::exceeded_by`]): its sums are still correctly rounded, but may depend on
//! their order. The peak is part of the state (checkpoints carry it). Before any contact, the
//! quantum is that of a floor, 2⁻⁴⁰ of the case's reference force (the normal force at an
//! overlap of the largest reference radius), so that it never falls into subnormal numbers.

use crate::math::Vec3;

/// 1.5·2⁵²: added to a number below 2⁵¹ in magnitude, it leaves the number rounded to an
/// integer in the sum's last bits (round half to even), and subtracted again gives it back.
const ROUNDER: f64 = 6_755_399_441_055_744.0;

/// How far a load may grow over one evaluation's peak with its sums staying exact: 2¹⁰.
const GROWTH: f64 = 1024.0;

/// The quantum of one kind of load (force or torque).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Quantum {
    /// `ROUNDER · Q`.
    rounder: f64,
    /// The largest load this quantum sums exactly: 2⁵¹·Q = 2^⌈log₂ peak⌉ · 2¹⁰.
    limit: f64,
}

impl Quantum {
    /// The quantum for loads whose largest component was `peak` (N or N·m) at the last
    /// evaluation, at least `floor`.
    pub(crate) fn for_peak(peak: f64, floor: f64) -> Quantum {
        let p = if peak.is_finite() { peak.max(floor) } else { floor };
        // ⌈log₂ p⌉ from the bits (no logarithm in a step's overhead), kept where 2^(e − 80)
        // and 2^(e + 10) are normal numbers.
        let bits = p.to_bits();
        let exponent = ((bits >> 52) & 0x7ff) as i32 - 1023;
        let exponent = (exponent + (bits & ((1 << 52) - 1) != 0) as i32).clamp(-900, 900);
        let q = pow2(exponent - 41);
        Quantum { rounder: ROUNDER * q, limit: pow2(exponent) * GROWTH }
    }

    /// `v` rounded to a multiple of the quantum (exactly so while |v| < 2⁵¹·Q).
    #[inline(always)]
    pub(crate) fn round(self, v: f64) -> f64 {
        (v + self.rounder) - self.rounder
    }

    /// Rounds every value of `values` in place: a loop that compiles to vector instructions.
    #[inline(always)]
    pub(crate) fn round_all<const N: usize>(self, values: &mut [f64; N]) {
        for v in values.iter_mut() {
            *v = self.round(*v);
        }
    }
}

/// 2^k for a normal result (k in −1022..=1023).
fn pow2(k: i32) -> f64 {
    f64::from_bits(((k + 1023) as u64) << 52)
}

/// The quanta of one force evaluation: forces and torques.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Quanta {
    pub force: Quantum,
    pub torque: Quantum,
}

/// The largest force and torque components of an evaluation's loads, N and N·m.
pub(crate) type Peak = [f64; 2];

/// The floors of the peaks for the reference force `f_ref` (N) and radius `r_ref` (m) of a
/// case (see the module doc): [force, torque].
pub(crate) fn peak_floor(f_ref: f64, r_ref: f64) -> Peak {
    let ok = |v: f64| if v.is_finite() && v > 0.0 { v } else { 1.0 };
    let f = ok(f_ref) * 2f64.powi(-40);
    [f, f * ok(r_ref)]
}

impl Quanta {
    /// The quanta after an evaluation whose peaks were `peak`, with the case's `floor`.
    pub(crate) fn new(peak: Peak, floor: Peak) -> Quanta {
        Quanta { force: Quantum::for_peak(peak[0], floor[0]), torque: Quantum::for_peak(peak[1], floor[1]) }
    }

    /// True when an evaluation with these quanta had loads as large as `peak`: beyond what
    /// they sum exactly (see the module doc).
    pub(crate) fn exceeded_by(&self, peak: Peak) -> bool {
        // The bounds hold to a few roundings: a margin of 2⁻⁴⁰ covers them.
        const MARGIN: f64 = 1.0 + 1.0 / (1u64 << 40) as f64;
        !(peak[0] * MARGIN < self.force.limit && peak[1] * MARGIN < self.torque.limit)
    }
}

/// Where a block adds its loads: the slots' force and torque accumulators, and the peaks of
/// the loads added.
pub(crate) struct Accumulators<'a> {
    pub force: &'a mut [Vec3],
    pub torque: &'a mut [Vec3],
    pub peak: Peak,
}

impl Accumulators<'_> {
    /// Adds force `f` (with `OPPOSITE`, −`f`: the other particle of a pair) and torque `t`, both
    /// rounded to the quanta, to slot `i` (an index into the block's slots).
    #[inline(always)]
    pub(crate) fn add<const OPPOSITE: bool>(&mut self, i: usize, f: Vec3, t: Vec3) {
        if OPPOSITE {
            self.force[i] -= f;
        } else {
            self.force[i] += f;
        }
        self.torque[i] += t;
    }

    /// Takes the peaks `p` into the block's.
    #[inline(always)]
    pub(crate) fn note_peak(&mut self, p: Peak) {
        self.peak = max_peak(self.peak, p);
    }
}

/// The larger of two peaks, component by component.
#[inline(always)]
pub(crate) fn max_peak(a: Peak, b: Peak) -> Peak {
    [a[0].max(b[0]), a[1].max(b[1])]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Rounded values differ from the values by at most half a quantum, and any order of
        /// adding them gives the same bits, while they stay within the quantum's limit.
        #[test]
        fn rounded_sums_do_not_depend_on_order(
            peak in 1e-12f64..1e12,
            values in prop::collection::vec(-1.0f64..1.0, 1..64),
            scale_exp in -40i32..6,
            seed in any::<u64>(),
        ) {
            let q = Quantum::for_peak(peak, 0.0);
            let scale = peak * 2f64.powi(scale_exp);
            let vs: Vec<f64> = values.iter().map(|v| q.round(v * scale)).collect();
            let quantum = q.rounder / ROUNDER;
            for (&v, &r) in values.iter().zip(&vs) {
                prop_assert!((r - v * scale).abs() <= 0.5 * quantum, "v {} r {r}", v * scale);
            }
            let sum = |order: &[usize]| order.iter().fold(0.0, |s, &i| s + vs[i]).to_bits();
            let forward: Vec<usize> = (0..vs.len()).collect();
            let mut shuffled = forward.clone();
            // A seeded Fisher–Yates shuffle (xorshift).
            let mut s = seed | 1;
            for i in (1..shuffled.len()).rev() {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                shuffled.swap(i, (s % (i as u64 + 1)) as usize);
            }
            let reversed: Vec<usize> = forward.iter().rev().copied().collect();
            prop_assert_eq!(sum(&forward), sum(&shuffled));
            prop_assert_eq!(sum(&forward), sum(&reversed));
        }
    }

    /// A value rounded and its negation rounded are exact opposites (Newton's third law holds
    /// to the bit in the sums).
    #[test]
    fn rounding_is_odd() {
        let q = Quantum::for_peak(3.7e4, 0.0);
        for v in [1e-9, 0.3, 123.456, 3.7e4, 5e6, 1e-30] {
            // (Equal as numbers: a zero may come out +0 for both signs, which adds alike.)
            assert!(q.round(v) == -q.round(-v), "v = {v}");
        }
    }

    /// The limit is the peak's power of two times the growth allowed, and the floor holds.
    #[test]
    fn limits_follow_the_peak() {
        let q = Quanta::new([3.0, 0.0], [1e-9, 1e-12]);
        assert_eq!(q.force.limit, 4.0 * GROWTH);
        assert!(!q.exceeded_by([4.0 * GROWTH * 0.999, 0.0]));
        assert!(q.exceeded_by([4.0 * GROWTH, 0.0]));
        assert_eq!(q.torque.limit, 2f64.powi((1e-12f64).log2().ceil() as i32) * GROWTH);
    }
}
