//! Quantities users watch: energies, contacts, overlaps.

/// A snapshot of global quantities after a step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Diagnostics {
    /// Simulated time, s.
    pub time: f64,
    /// Steps taken.
    pub step: u64,
    /// Translational kinetic energy Σ½mv², J.
    pub kinetic_translational: f64,
    /// Rotational kinetic energy Σ½Iω², J.
    pub kinetic_rotational: f64,
    /// Gravitational potential energy −Σm·g·x (zero at the origin), J.
    pub potential: f64,
    /// Elastic energy in the normal springs of the current contacts, J.
    pub elastic: f64,
    /// Number of particle–particle and particle–wall contacts of the current state.
    pub contacts: usize,
    /// Largest overlap divided by the smaller radius of the contact, of the current state.
    pub max_overlap_ratio: f64,
}

impl Diagnostics {
    /// Kinetic + potential + elastic energy, J.
    pub fn total_energy(&self) -> f64 {
        self.kinetic_translational + self.kinetic_rotational + self.potential + self.elastic
    }
}

/// The sum of `values` independent of their order (so that a quantity summed over the
/// particles is the same however they are stored): every value is rounded to a multiple of
/// 2^(e + k − 126), where 2^e bounds the largest magnitude and 2^k the count, and the
/// multiples are added exactly as 128-bit integers; the exact sum is rounded once. Values
/// below that quantum (2⁻¹⁰⁰ of the largest or less) are lost. A sum with an infinite or NaN
/// value is NaN or infinite as the plain sum is.
pub fn order_free_sum(values: &[f64]) -> f64 {
    let largest = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if largest == 0.0 || !largest.is_finite() || values.iter().any(|v| v.is_nan()) {
        return values.iter().sum();
    }
    let e = largest.log2().ceil() as i32 + 1;
    let k = (values.len() as f64 + 1.0).log2().ceil() as i32;
    let scale = 2f64.powi(126 - k - e);
    // |v·scale| < 2^(126 − k): the sum of `len` of them stays below 2^126.
    let total: i128 = values.iter().map(|&v| (v * scale).round() as i128).sum();
    total as f64 / scale
}

#[cfg(test)]
mod tests {
    use super::order_free_sum;

    /// The sum does not depend on the order and is the exact sum, rounded once, for values
    /// that the quantum holds exactly (here: multiples of 2⁻²⁰ below 2²⁰).
    #[test]
    fn order_free_sums_are_exact_and_order_free() {
        let mut v: Vec<f64> = (0..1000).map(|i| ((i * 7919) % 1013) as f64 * 0.37 - 150.0).collect();
        v.push(1e-12);
        v.push(3.5e5);
        let forward = order_free_sum(&v);
        v.reverse();
        assert_eq!(order_free_sum(&v).to_bits(), forward.to_bits());
        v.swap(3, 700);
        assert_eq!(order_free_sum(&v).to_bits(), forward.to_bits());
        let exact: Vec<f64> = (0..100).map(|i| (i as f64 - 50.5) * 2f64.powi(-20)).collect();
        let want: f64 = exact.iter().sum();
        assert_eq!(order_free_sum(&exact), want);
        assert_eq!(order_free_sum(&[]), 0.0);
        assert!(order_free_sum(&[1.0, f64::NAN]).is_nan());
    }
}
