//! Particle sizes and mixtures of phases, drawn from a seeded stream.
//!
//! A [`SizeDistribution`] gives the diameter of one particle, m: constant, uniform, a normal or
//! log-normal truncated to a window `[min, max]`, or a discrete table by number or by mass. A
//! [`Mixture`] joins several of them, each with its phase and density, by number or by mass.
//! Distributions are plain data: [`SizeDistribution::check`] and [`Mixture::check`] say
//! whether one may be used; the other methods assume it was checked.
//!
//! All size distributions are by number (the probability that the next particle has a
//! diameter ≤ d); a [`Basis::Mass`] table or mixture is turned into number fractions, fraction
//! by fraction n ∝ w / (ρ·E\[d³\]) ([`Mixture::number_fractions`]). [`SizeDistribution::mean_cube`]
//! (E\[d³\] by number, in closed form) turns a target volume or mass into a particle count.
//!
//! ## What MFIX does, and what is matched
//! MFIX-DEM (21.3: `model/des/des_psd_mod.f`, `randomno_mod.f` and the DEM input checks) takes
//! `IC_PSD_TYPE` / `BC_PSD_TYPE` per region and solids phase:
//! - `MONO`: every particle at `D_P0` ([`SizeDistribution::Constant`]).
//! - `UNIFORM`: uniform in diameter on `[IC_PSD_MIN_DP, IC_PSD_MAX_DP]`, by number
//!   ([`SizeDistribution::Uniform`]).
//! - `NORMAL`: `IC_PSD_MEAN_DP` and `IC_PSD_STDEV` are the mean and standard deviation of the
//!   untruncated normal of the diameter; a draw outside `[IC_PSD_MIN_DP, IC_PSD_MAX_DP]` is
//!   thrown away and drawn again (so the truncated normal by number, whose own mean and
//!   deviation differ from the two given). Missing bounds default to mean ∓ 3·stdev.
//! - `LOG_NORMAL`: `IC_PSD_MEAN_DP` and `IC_PSD_STDEV` are the mean and standard deviation of
//!   the untruncated log-normal diameter itself (not of ln d), turned into the parameters of
//!   ln d as σ² = ln(1 + s²/m²), μ = ln m − σ²/2; truncated to the bounds by the same
//!   rejection. Missing bounds default to e^μ·e^(∓3σ).
//! - `CUSTOM`: a file of diameters against a PDF or CDF by number, sampled by inverting the
//!   CDF with linear interpolation between rows (a density uniform between listed diameters).
//!
//! MFIX counts the particles of a region from the mean particle volume, which it estimates
//! from 100 000 draws; it reseeds its generator from the clock, so its draws are not
//! reproducible.
//!
//! Here `Normal` and `LogNormal` mean exactly what MFIX's `NORMAL` and `LOG_NORMAL` mean (the
//! parameters of the untruncated distribution, truncated by conditioning on the closed window,
//! by number), and are also drawn by rejection. The differences: the bounds are always given
//! (no defaults); a window holding less than [`MIN_WINDOW_PROBABILITY`] of the untruncated
//! distribution is refused instead of looping; E\[d³\] is exact, not sampled; draws are
//! reproducible from the seed. [`SizeDistribution::Table`] is discrete: each listed diameter
//! exactly, not MFIX's interpolation between rows, so an MFIX `CUSTOM` file is not a table
//! row for row.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use std::f64::consts::{FRAC_1_SQRT_2, FRAC_2_SQRT_PI, PI};
use thiserror::Error;

/// How far the fractions of a table or a mixture may sum from 1.
pub const FRACTION_TOLERANCE: f64 = 1e-6;

/// The least probability of the untruncated distribution that the window of a truncated
/// normal or log-normal must hold: the acceptance rate of the rejection MFIX draws with.
pub const MIN_WINDOW_PROBABILITY: f64 = 1e-6;

/// Draws from the untruncated distribution before a truncated one turns to inverting its cdf.
/// A window holding p ≥ [`REJECTION_PROBABILITY`] falls through with probability (1 − p)^32, at
/// most 1e-4.
const REJECTION_TRIES: usize = 32;

/// A truncated distribution whose first draw misses its window goes on rejecting only if the
/// window holds at least this much (4 draws a particle on average); a narrower window inverts
/// its cdf at once.
const REJECTION_PROBABILITY: f64 = 0.25;

/// What a set of fractions counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Basis {
    /// The fraction of the particles.
    Number,
    /// The fraction of the mass.
    Mass,
}

/// The diameters of particles, m. By number: the probability that a particle's diameter is at
/// most d is [`cdf`](Self::cdf)(d).
#[derive(Debug, Clone, PartialEq)]
pub enum SizeDistribution {
    /// Every particle the same (MFIX's `MONO`).
    Constant {
        /// m.
        diameter: f64,
    },
    /// Uniform in diameter on `[min, max]`, by number (MFIX's `UNIFORM`).
    Uniform {
        /// m.
        min: f64,
        /// m.
        max: f64,
    },
    /// The normal of the diameter with this mean and standard deviation, truncated to
    /// `[min, max]` (MFIX's `NORMAL`: the parameters are the untruncated distribution's).
    Normal {
        /// Mean of the untruncated normal, m.
        mean: f64,
        /// Standard deviation of the untruncated normal, m.
        sigma: f64,
        /// m.
        min: f64,
        /// m.
        max: f64,
    },
    /// The log-normal diameter whose untruncated mean and standard deviation are these (of d,
    /// not of ln d), truncated to `[min, max]` (MFIX's `LOG_NORMAL` with `IC_PSD_MEAN_DP` and
    /// `IC_PSD_STDEV`).
    LogNormal {
        /// Mean diameter of the untruncated log-normal, m.
        mean: f64,
        /// Standard deviation of the diameter of the untruncated log-normal, m.
        sigma: f64,
        /// m.
        min: f64,
        /// m.
        max: f64,
    },
    /// Each listed diameter with its fraction, by number or by mass. By mass the number
    /// fractions are ∝ w_k / d_k³ (one density).
    Table {
        /// Distinct, positive, m; in any order.
        diameters: Vec<f64>,
        /// One a diameter, not negative, summing to 1.
        fractions: Vec<f64>,
        /// What the fractions count.
        basis: Basis,
    },
    /// A cumulative distribution by number given at points and linear between them, as
    /// MFIX's `CUSTOM` size distribution files give it: the diameter is drawn by inverting
    /// it at one uniform variate.
    Cdf {
        /// Increasing, positive, m.
        diameters: Vec<f64>,
        /// P(D ≤ d) at each diameter: non-decreasing from 0 at the first to 1 at the last.
        cdf: Vec<f64>,
    },
}

/// A size distribution or mixture that cannot be used.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PsdError {
    /// A parameter is infinite or NaN.
    #[error("the {what} is {value}, not a finite number")]
    NotFinite {
        /// Which parameter.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// A parameter that must be positive is not.
    #[error("the {what} is {value} {unit}, but it must be positive")]
    NotPositive {
        /// Which parameter.
        what: &'static str,
        /// Its value.
        value: f64,
        /// Its unit.
        unit: &'static str,
    },
    /// The window's bounds are the wrong way round, or equal.
    #[error("the minimum diameter {min} m is not below the maximum diameter {max} m")]
    Window {
        /// m.
        min: f64,
        /// m.
        max: f64,
    },
    /// The window of a truncated distribution holds almost none of it: drawing from it would
    /// reject nearly every draw.
    #[error(
        "the window [{min}, {max}] m holds only {probability:.3e} of the untruncated \
         distribution, less than the {MIN_WINDOW_PROBABILITY:e} it must hold"
    )]
    WindowProbability {
        /// m.
        min: f64,
        /// m.
        max: f64,
        /// The untruncated distribution's probability of the window.
        probability: f64,
    },
    /// A table without rows.
    #[error("the table has no rows")]
    EmptyTable,
    /// A cumulative distribution that is not one.
    #[error("the cumulative distribution {0}")]
    BadCdf(String),
    /// A table whose columns differ in length.
    #[error("the table has {diameters} diameters but {fractions} fractions")]
    TableLengths {
        /// How many diameters.
        diameters: usize,
        /// How many fractions.
        fractions: usize,
    },
    /// A table diameter that is not finite and positive.
    #[error("table diameter {index} is {value} m, but it must be finite and positive")]
    TableDiameter {
        /// Its row, from 0.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The same diameter on two rows of a table.
    #[error("diameter {diameter} m is on two rows of the table")]
    RepeatedDiameter {
        /// m.
        diameter: f64,
    },
    /// A fraction that is negative or not finite.
    #[error("{what} {index} is {value}, but a fraction must be finite and not negative")]
    Fraction {
        /// Whose fraction ("table fraction", "part fraction").
        what: &'static str,
        /// Its row or part, from 0.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// Fractions that do not sum to 1.
    #[error("the {what} sum to {sum}, not 1 (within {FRACTION_TOLERANCE:e})")]
    FractionSum {
        /// Whose fractions.
        what: &'static str,
        /// Their sum.
        sum: f64,
    },
    /// A mixture without parts.
    #[error("the mixture has no parts")]
    NoParts,
    /// Something wrong with one part of a mixture.
    #[error("part {part}: {source}")]
    Part {
        /// The part, from 0.
        part: usize,
        /// What is wrong with it.
        source: Box<PsdError>,
    },
}

impl SizeDistribution {
    /// Whether the distribution may be used: parameters finite and positive, min < max, a
    /// truncation window holding at least [`MIN_WINDOW_PROBABILITY`] of the untruncated
    /// distribution, a table non-empty with as many fractions as diameters, its diameters
    /// distinct and its fractions not negative and summing to 1 within [`FRACTION_TOLERANCE`].
    pub fn check(&self) -> Result<(), PsdError> {
        match self {
            SizeDistribution::Constant { diameter } => positive("diameter", *diameter, "m"),
            SizeDistribution::Uniform { min, max } => check_window(*min, *max),
            SizeDistribution::Normal { mean, sigma, min, max } => {
                positive("mean", *mean, "m")?;
                positive("standard deviation", *sigma, "m")?;
                check_window(*min, *max)?;
                let (a, b) = normal_window(*mean, *sigma, *min, *max);
                check_probability(*min, *max, std_window(a, b))
            }
            SizeDistribution::LogNormal { mean, sigma, min, max } => {
                positive("mean", *mean, "m")?;
                positive("standard deviation", *sigma, "m")?;
                check_window(*min, *max)?;
                let (mu, s) = log_normal_parameters(*mean, *sigma);
                let (a, b) = normal_window(mu, s, min.ln(), max.ln());
                check_probability(*min, *max, std_window(a, b))
            }
            SizeDistribution::Table { diameters, fractions, .. } => {
                if diameters.is_empty() {
                    return Err(PsdError::EmptyTable);
                }
                if diameters.len() != fractions.len() {
                    return Err(PsdError::TableLengths {
                        diameters: diameters.len(),
                        fractions: fractions.len(),
                    });
                }
                for (index, &value) in diameters.iter().enumerate() {
                    if !(value.is_finite() && value > 0.0) {
                        return Err(PsdError::TableDiameter { index, value });
                    }
                }
                check_fractions("table fraction", "table's fractions", fractions.iter().copied())?;
                let mut sorted = diameters.clone();
                sorted.sort_by(f64::total_cmp);
                match sorted.windows(2).find(|w| w[0] == w[1]) {
                    Some(w) => Err(PsdError::RepeatedDiameter { diameter: w[0] }),
                    None => Ok(()),
                }
            }
            SizeDistribution::Cdf { diameters, cdf } => check_cdf(diameters, cdf),
        }
    }

    /// The smallest diameter drawn, m: the window's lower bound, or the table's smallest
    /// diameter with a positive fraction.
    pub fn min_diameter(&self) -> f64 {
        match self {
            SizeDistribution::Constant { diameter } => *diameter,
            SizeDistribution::Uniform { min, .. }
            | SizeDistribution::Normal { min, .. }
            | SizeDistribution::LogNormal { min, .. } => *min,
            SizeDistribution::Table { diameters, fractions, .. } => {
                table_support(diameters, fractions).fold(f64::INFINITY, f64::min)
            }
            SizeDistribution::Cdf { diameters, cdf } => {
                // The last point where the cdf is still 0 starts the support.
                let k = cdf.iter().rposition(|&c| c == 0.0).unwrap_or(0);
                diameters[k]
            }
        }
    }

    /// The largest diameter drawn, m: the window's upper bound, or the table's largest diameter
    /// with a positive fraction.
    pub fn max_diameter(&self) -> f64 {
        match self {
            SizeDistribution::Constant { diameter } => *diameter,
            SizeDistribution::Uniform { max, .. }
            | SizeDistribution::Normal { max, .. }
            | SizeDistribution::LogNormal { max, .. } => *max,
            SizeDistribution::Table { diameters, fractions, .. } => {
                table_support(diameters, fractions).fold(f64::NEG_INFINITY, f64::max)
            }
            SizeDistribution::Cdf { diameters, cdf } => {
                // The first point where the cdf reaches 1 ends the support.
                let k = cdf.iter().position(|&c| c >= 1.0).unwrap_or(cdf.len() - 1);
                diameters[k]
            }
        }
    }

    /// One diameter, m, from the stream: a function of the stream's state alone.
    ///
    /// A constant draws nothing; a uniform and a table draw one uniform variate. A truncated
    /// normal or log-normal draws from the untruncated distribution until a draw lands in
    /// `[min, max]` (MFIX's rejection); if the first misses and the window holds less than a
    /// quarter of the distribution, or 32 miss, it inverts the truncated cdf at one uniform
    /// variate instead. Each way gives exactly the truncated distribution (the choice depends
    /// on the parameters, not on where the misses fell), so their mixture does too.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        match self {
            SizeDistribution::Constant { diameter } => *diameter,
            SizeDistribution::Uniform { min, max } => {
                let u: f64 = rng.random();
                (min + (max - min) * u).min(*max)
            }
            SizeDistribution::Normal { mean, sigma, min, max } => truncated_draw(
                rng,
                |z| mean + sigma * z,
                *min,
                *max,
                || normal_window(*mean, *sigma, *min, *max),
            ),
            SizeDistribution::LogNormal { mean, sigma, min, max } => {
                let (mu, s) = log_normal_parameters(*mean, *sigma);
                truncated_draw(
                    rng,
                    |z| (mu + s * z).exp(),
                    *min,
                    *max,
                    || normal_window(mu, s, min.ln(), max.ln()),
                )
            }
            SizeDistribution::Table { diameters, fractions, basis } => {
                let total: f64 =
                    (0..diameters.len()).map(|k| table_weight(diameters, fractions, *basis, k)).sum();
                let target = rng.random::<f64>() * total;
                let mut cumulative = 0.0;
                let mut last = 0;
                for k in 0..diameters.len() {
                    let w = table_weight(diameters, fractions, *basis, k);
                    if w > 0.0 {
                        cumulative += w;
                        last = k;
                        if cumulative > target {
                            return diameters[k];
                        }
                    }
                }
                diameters[last]
            }
            SizeDistribution::Cdf { diameters, cdf } => {
                let u: f64 = rng.random();
                cdf_quantile(diameters, cdf, u)
            }
        }
    }

    /// The probability that a particle's diameter is at most `d` (m), by number: 0 below the
    /// smallest diameter, 1 from the largest on. Truncated normals and log-normals through
    /// [`erfc`], each tail from its own side so a window far out in a tail keeps its digits.
    pub fn cdf(&self, d: f64) -> f64 {
        match self {
            SizeDistribution::Constant { diameter } => {
                if d >= *diameter {
                    1.0
                } else {
                    0.0
                }
            }
            SizeDistribution::Uniform { min, max } => ((d - min) / (max - min)).clamp(0.0, 1.0),
            SizeDistribution::Normal { mean, sigma, min, max } => {
                if d <= *min {
                    return 0.0;
                }
                if d >= *max {
                    return 1.0;
                }
                let (a, b) = normal_window(*mean, *sigma, *min, *max);
                (std_window(a, (d - mean) / sigma) / std_window(a, b)).clamp(0.0, 1.0)
            }
            SizeDistribution::LogNormal { mean, sigma, min, max } => {
                if d <= *min {
                    return 0.0;
                }
                if d >= *max {
                    return 1.0;
                }
                let (mu, s) = log_normal_parameters(*mean, *sigma);
                let (a, b) = normal_window(mu, s, min.ln(), max.ln());
                (std_window(a, (d.ln() - mu) / s) / std_window(a, b)).clamp(0.0, 1.0)
            }
            SizeDistribution::Table { diameters, fractions, basis } => {
                let mut below = 0.0;
                let mut total = 0.0;
                for k in 0..diameters.len() {
                    let w = table_weight(diameters, fractions, *basis, k);
                    total += w;
                    if diameters[k] <= d {
                        below += w;
                    }
                }
                (below / total).clamp(0.0, 1.0)
            }
            SizeDistribution::Cdf { diameters, cdf } => {
                let n = diameters.len();
                if d <= diameters[0] {
                    return if n == 1 { 1.0 } else { cdf[0] };
                }
                if d >= diameters[n - 1] {
                    return 1.0;
                }
                let k = diameters.partition_point(|&x| x <= d);
                let (d0, d1, c0, c1) = (diameters[k - 1], diameters[k], cdf[k - 1], cdf[k]);
                (c0 + (c1 - c0) * (d - d0) / (d1 - d0)).clamp(0.0, 1.0)
            }
        }
    }

    /// E\[d³\] by number, m³: the mean particle volume is π/6 of it. Closed forms: uniform
    /// (a + b)(a² + b²)/4; truncated normal from the moments of the truncated standard normal
    /// (by parts, about the window's point nearest the mean so the terms do not cancel);
    /// truncated log-normal e^(3μ + 9σ²/2)·P(α − 3σ, β − 3σ)/P(α, β), with P the standard
    /// normal's probability of a window and α, β the window's bounds in units of σ about μ.
    pub fn mean_cube(&self) -> f64 {
        match self {
            SizeDistribution::Constant { diameter } => diameter * diameter * diameter,
            SizeDistribution::Uniform { min, max } => (min + max) * (min * min + max * max) / 4.0,
            SizeDistribution::Normal { mean, sigma, min, max } => {
                let (a, b) = normal_window(*mean, *sigma, *min, *max);
                // Moments of Y = Z − c for Z the standard normal on [a, b], by parts from
                // φ′(z) = −zφ(z): E[Y^(k+1)] = (ya^k φ(a) − yb^k φ(b))/P + k E[Y^(k−1)] − c E[Y^k].
                let c = 0.0f64.clamp(a, b);
                let p = std_window(a, b);
                let (fa, fb) = (std_density(a) / p, std_density(b) / p);
                let (ya, yb) = (a - c, b - c);
                let edge = |k: i32| power_times(ya, k, fa) - power_times(yb, k, fb);
                let m1 = edge(0) - c;
                let m2 = edge(1) + 1.0 - c * m1;
                let m3 = edge(2) + 2.0 * m1 - c * m2;
                let dc = mean + sigma * c;
                dc * dc * dc
                    + 3.0 * dc * dc * sigma * m1
                    + 3.0 * dc * sigma * sigma * m2
                    + sigma * sigma * sigma * m3
            }
            SizeDistribution::LogNormal { mean, sigma, min, max } => {
                let (mu, s) = log_normal_parameters(*mean, *sigma);
                let (a, b) = normal_window(mu, s, min.ln(), max.ln());
                (3.0 * mu + 4.5 * s * s).exp() * std_window(a - 3.0 * s, b - 3.0 * s) / std_window(a, b)
            }
            SizeDistribution::Table { diameters, fractions, basis } => {
                let (mut weighted, mut total) = (0.0, 0.0);
                for k in 0..diameters.len() {
                    let w = table_weight(diameters, fractions, *basis, k);
                    let d = diameters[k];
                    weighted += w * d * d * d;
                    total += w;
                }
                weighted / total
            }
            SizeDistribution::Cdf { diameters, cdf } => {
                // Uniform within each segment: E[d³] there is (b⁴ − a⁴)/(4(b − a)).
                let mut m = 0.0;
                for k in 1..diameters.len() {
                    let (a, b, p) = (diameters[k - 1], diameters[k], cdf[k] - cdf[k - 1]);
                    if p > 0.0 {
                        m += p * (a + b) * (a * a + b * b) / 4.0;
                    }
                }
                m
            }
        }
    }
}

/// One part of a [`Mixture`]: a phase with its density and size distribution.
#[derive(Debug, Clone, PartialEq)]
pub struct MixturePart {
    /// The solids phase of its particles.
    pub phase: u32,
    /// The particles' density, kg/m³.
    pub density: f64,
    /// Its fraction of the mixture, by the mixture's [`Basis`].
    pub fraction: f64,
    /// Its particles' diameters.
    pub sizes: SizeDistribution,
}

/// Particles of several parts (phases, or modes of one phase), by number or by mass.
#[derive(Debug, Clone, PartialEq)]
pub struct Mixture {
    /// The parts; two may share a phase.
    pub parts: Vec<MixturePart>,
    /// What the parts' fractions count.
    pub basis: Basis,
}

impl Mixture {
    /// All particles of one phase.
    pub fn single(phase: u32, density: f64, sizes: SizeDistribution) -> Mixture {
        Mixture { parts: vec![MixturePart { phase, density, fraction: 1.0, sizes }], basis: Basis::Number }
    }

    /// Whether the mixture may be used: at least one part, each with a finite positive density
    /// and a size distribution that passes [`SizeDistribution::check`] (an error names the part,
    /// from 0), the fractions not negative and summing to 1 within [`FRACTION_TOLERANCE`].
    pub fn check(&self) -> Result<(), PsdError> {
        if self.parts.is_empty() {
            return Err(PsdError::NoParts);
        }
        for (part, p) in self.parts.iter().enumerate() {
            positive("density", p.density, "kg/m³")
                .and_then(|()| p.sizes.check())
                .map_err(|e| PsdError::Part { part, source: Box::new(e) })?;
        }
        check_fractions("part fraction", "parts' fractions", self.parts.iter().map(|p| p.fraction))
    }

    /// The parts' fractions by number, summing to 1. By mass, n_i ∝ w_i / (ρ_i·E_i\[d³\]).
    pub fn number_fractions(&self) -> Vec<f64> {
        let weights: Vec<f64> = self.parts.iter().map(|p| self.number_weight(p)).collect();
        let total: f64 = weights.iter().sum();
        weights.iter().map(|w| w / total).collect()
    }

    /// One particle's (phase, diameter in m) from the stream. With more than one part, one
    /// uniform variate picks the part by its number fraction; then its sizes draw the diameter
    /// ([`SizeDistribution::sample`]). A single part draws only its diameter.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> (u32, f64) {
        let (part, d) = self.draw(rng);
        (part.phase, d)
    }

    /// [`sample`](Self::sample) with the part drawn (its phase and density), from the same
    /// variates.
    pub fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> (&MixturePart, f64) {
        let part = if self.parts.len() == 1 {
            &self.parts[0]
        } else {
            let total: f64 = self.parts.iter().map(|p| self.number_weight(p)).sum();
            let target = rng.random::<f64>() * total;
            let mut cumulative = 0.0;
            let mut chosen = None;
            for p in &self.parts {
                let w = self.number_weight(p);
                if w > 0.0 {
                    cumulative += w;
                    chosen = Some(p);
                    if cumulative > target {
                        break;
                    }
                }
            }
            chosen.unwrap_or(&self.parts[0])
        };
        (part, part.sizes.sample(rng))
    }

    /// The mean volume of a particle, by number, m³.
    pub fn mean_volume(&self) -> f64 {
        let n = self.number_fractions();
        PI / 6.0 * self.parts.iter().zip(&n).map(|(p, n)| n * p.sizes.mean_cube()).sum::<f64>()
    }

    /// The mean mass of a particle, by number, kg.
    pub fn mean_mass(&self) -> f64 {
        let n = self.number_fractions();
        PI / 6.0 * self.parts.iter().zip(&n).map(|(p, n)| n * p.density * p.sizes.mean_cube()).sum::<f64>()
    }

    /// The smallest diameter of the parts with a positive fraction, m.
    pub fn min_diameter(&self) -> f64 {
        self.drawn_parts().map(|p| p.sizes.min_diameter()).fold(f64::INFINITY, f64::min)
    }

    /// The largest diameter of the parts with a positive fraction, m.
    pub fn max_diameter(&self) -> f64 {
        self.drawn_parts().map(|p| p.sizes.max_diameter()).fold(f64::NEG_INFINITY, f64::max)
    }

    /// A part's unnormalised number fraction.
    fn number_weight(&self, p: &MixturePart) -> f64 {
        match self.basis {
            Basis::Number => p.fraction,
            Basis::Mass if p.fraction > 0.0 => p.fraction / (p.density * p.sizes.mean_cube()),
            Basis::Mass => 0.0,
        }
    }

    /// The parts with a positive fraction, or all of them if none has one.
    fn drawn_parts(&self) -> impl Iterator<Item = &MixturePart> {
        let any = self.parts.iter().any(|p| p.fraction > 0.0);
        self.parts.iter().filter(move |p| !any || p.fraction > 0.0)
    }
}

/// A finite, positive parameter.
fn positive(what: &'static str, value: f64, unit: &'static str) -> Result<(), PsdError> {
    if !value.is_finite() {
        Err(PsdError::NotFinite { what, value })
    } else if value <= 0.0 {
        Err(PsdError::NotPositive { what, value, unit })
    } else {
        Ok(())
    }
}

/// Positive bounds, min < max.
fn check_window(min: f64, max: f64) -> Result<(), PsdError> {
    positive("minimum diameter", min, "m")?;
    positive("maximum diameter", max, "m")?;
    if min < max { Ok(()) } else { Err(PsdError::Window { min, max }) }
}

/// A window holding at least [`MIN_WINDOW_PROBABILITY`].
fn check_probability(min: f64, max: f64, probability: f64) -> Result<(), PsdError> {
    if probability >= MIN_WINDOW_PROBABILITY {
        Ok(())
    } else {
        Err(PsdError::WindowProbability { min, max, probability })
    }
}

/// Fractions finite, not negative, summing to 1.
fn check_fractions(
    what: &'static str,
    whose: &'static str,
    fractions: impl Iterator<Item = f64>,
) -> Result<(), PsdError> {
    let mut sum = 0.0;
    for (index, value) in fractions.enumerate() {
        if !(value.is_finite() && value >= 0.0) {
            return Err(PsdError::Fraction { what, index, value });
        }
        sum += value;
    }
    if (sum - 1.0).abs() <= FRACTION_TOLERANCE {
        Ok(())
    } else {
        Err(PsdError::FractionSum { what: whose, sum })
    }
}

/// A cumulative distribution: at least two points, diameters finite, positive and
/// increasing, the cdf finite and non-decreasing from 0 to 1.
fn check_cdf(diameters: &[f64], cdf: &[f64]) -> Result<(), PsdError> {
    let bad = |m: String| Err(PsdError::BadCdf(m));
    if diameters.len() != cdf.len() {
        return bad(format!("has {} diameters but {} values", diameters.len(), cdf.len()));
    }
    if diameters.len() < 2 {
        return bad("needs at least two points".into());
    }
    for (k, &d) in diameters.iter().enumerate() {
        if !(d.is_finite() && d > 0.0) {
            return bad(format!("diameter {} is {d} m, not finite and positive", k + 1));
        }
        if k > 0 && d <= diameters[k - 1] {
            return bad(format!("diameter {} ({d} m) does not exceed the one before it", k + 1));
        }
    }
    for (k, &c) in cdf.iter().enumerate() {
        if !(c.is_finite() && (0.0..=1.0).contains(&c)) {
            return bad(format!("value {} is {c}, not in [0, 1]", k + 1));
        }
        if k > 0 && c < cdf[k - 1] {
            return bad(format!("value {} ({c}) is less than the one before it", k + 1));
        }
    }
    if cdf[0] != 0.0 {
        return bad(format!("starts at {}, not 0", cdf[0]));
    }
    if (cdf[cdf.len() - 1] - 1.0).abs() > FRACTION_TOLERANCE {
        return bad(format!("ends at {}, not 1", cdf[cdf.len() - 1]));
    }
    Ok(())
}

/// The diameter where the piecewise-linear cdf reaches `u` ∈ [0, 1).
fn cdf_quantile(diameters: &[f64], cdf: &[f64], u: f64) -> f64 {
    let top = cdf[cdf.len() - 1];
    let u = u * top;
    // The first segment whose upper value exceeds u (a flat segment is never chosen).
    let k = cdf.partition_point(|&c| c <= u).clamp(1, cdf.len() - 1);
    let (d0, d1, c0, c1) = (diameters[k - 1], diameters[k], cdf[k - 1], cdf[k]);
    if c1 <= c0 {
        return d1;
    }
    (d0 + (d1 - d0) * (u - c0) / (c1 - c0)).clamp(d0, d1)
}

/// Row k's unnormalised number fraction.
#[inline]
fn table_weight(diameters: &[f64], fractions: &[f64], basis: Basis, k: usize) -> f64 {
    match basis {
        Basis::Number => fractions[k],
        Basis::Mass => {
            let d = diameters[k];
            fractions[k] / (d * d * d)
        }
    }
}

/// The table's diameters with a positive fraction, or all of them if none has one.
fn table_support<'a>(diameters: &'a [f64], fractions: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
    let any = fractions.iter().any(|&f| f > 0.0);
    diameters.iter().zip(fractions).filter(move |&(_, &f)| !any || f > 0.0).map(|(&d, _)| d)
}

/// The parameters (μ, σ) of ln d for a log-normal diameter of mean `mean` and standard
/// deviation `sd`: σ² = ln(1 + sd²/mean²), μ = ln(mean) − σ²/2.
#[inline]
fn log_normal_parameters(mean: f64, sd: f64) -> (f64, f64) {
    let r = sd / mean;
    let s2 = (r * r).ln_1p();
    (mean.ln() - 0.5 * s2, s2.sqrt())
}

/// The window `[lo, hi]` of a normal of mean `mu` and deviation `s`, in standard units.
#[inline]
fn normal_window(mu: f64, s: f64, lo: f64, hi: f64) -> (f64, f64) {
    ((lo - mu) / s, (hi - mu) / s)
}

/// The standard normal's density φ(z).
#[inline]
fn std_density(z: f64) -> f64 {
    (-0.5 * z * z).exp() * (0.5 * FRAC_2_SQRT_PI * FRAC_1_SQRT_2)
}

/// y^k·f, 0 where f is (a density underflowed far outside the window's near edge).
#[inline]
fn power_times(y: f64, k: i32, f: f64) -> f64 {
    if f == 0.0 { 0.0 } else { y.powi(k) * f }
}

/// The standard normal's upper tail Q(z) = P(Z > z) = erfc(z/√2)/2.
#[inline]
fn upper_tail(z: f64) -> f64 {
    0.5 * erfc(z * FRAC_1_SQRT_2)
}

/// The standard normal's probability of `[a, b]` (a ≤ b), from whichever tail keeps the
/// digits: Q(a) − Q(b) above 0, Q(−b) − Q(−a) below, 1 − Q(−a) − Q(b) across.
fn std_window(a: f64, b: f64) -> f64 {
    if a >= 0.0 {
        upper_tail(a) - upper_tail(b)
    } else if b <= 0.0 {
        upper_tail(-b) - upper_tail(-a)
    } else {
        (1.0 - upper_tail(-a)) - upper_tail(b)
    }
}

/// A diameter `to_diameter(z)` of the standard normal z truncated to where the diameter is in
/// `[min, max]`, `window()` in standard units: by rejection, or by inverting the truncated cdf
/// (see [`SizeDistribution::sample`]).
fn truncated_draw<R: Rng + ?Sized>(
    rng: &mut R,
    to_diameter: impl Fn(f64) -> f64,
    min: f64,
    max: f64,
    window: impl FnOnce() -> (f64, f64),
) -> f64 {
    let d = to_diameter(StandardNormal.sample(rng));
    if d >= min && d <= max {
        return d;
    }
    let (a, b) = window();
    let window = StdWindow::new(a, b);
    if window.probability() >= REJECTION_PROBABILITY {
        for _ in 1..REJECTION_TRIES {
            let d = to_diameter(StandardNormal.sample(rng));
            if d >= min && d <= max {
                return d;
            }
        }
    }
    to_diameter(window.quantile(rng.random())).clamp(min, max)
}

/// The standard normal on a window, turned (z → −z) if it lies mostly below 0 so that its
/// bounds' upper tails Q(a) ≥ Q(b) carry the digits of its probability and of its quantiles.
struct StdWindow {
    /// The window's bounds, after the turn.
    a: f64,
    b: f64,
    /// Q(a), Q(b).
    qa: f64,
    qb: f64,
    turned: bool,
}

impl StdWindow {
    fn new(a: f64, b: f64) -> StdWindow {
        let turned = a + b < 0.0;
        let (a, b) = if turned { (-b, -a) } else { (a, b) };
        StdWindow { a, b, qa: upper_tail(a), qb: upper_tail(b), turned }
    }

    /// The untruncated normal's probability of the window.
    fn probability(&self) -> f64 {
        self.qa - self.qb
    }

    /// The z of the window below which the truncated normal has probability `u`: Newton on
    /// Q(z) = Q(a) − u·(Q(a) − Q(b)) from Hastings' approximation of Q's inverse (within
    /// 4.5e-4), so three or four steps reach the rounding.
    fn quantile(&self, u: f64) -> f64 {
        let u = if self.turned { 1.0 - u } else { u };
        let t = self.qa - u * (self.qa - self.qb);
        let mut z = inverse_upper_tail_guess(t).clamp(self.a, self.b);
        for _ in 0..50 {
            let next = (z + (upper_tail(z) - t) / std_density(z)).clamp(self.a, self.b);
            if !next.is_finite() {
                break;
            }
            let step = (next - z).abs();
            z = next;
            if step <= 2.0 * f64::EPSILON * z.abs().max(1.0) {
                break;
            }
        }
        if self.turned { -z } else { z }
    }
}

/// z with Q(z) ≈ t, within 4.5e-4 (C. Hastings' rational approximation, Abramowitz & Stegun
/// 26.2.23).
fn inverse_upper_tail_guess(t: f64) -> f64 {
    if t.is_nan() || t <= 0.0 {
        return f64::INFINITY;
    }
    if t >= 1.0 {
        return f64::NEG_INFINITY;
    }
    let (p, sign) = if t > 0.5 { (1.0 - t, -1.0) } else { (t, 1.0) };
    let w = (-2.0 * p.ln()).sqrt();
    let z = w
        - (2.515517 + w * (0.802853 + w * 0.010328)) / (1.0 + w * (1.432788 + w * (0.189269 + w * 0.001308)));
    sign * z
}

// W. J. Cody, "Rational Chebyshev approximations for the error function", Math. Comp. 23
// (1969) 631–638, with his 1990 coefficients (netlib specfun CALERF): relative error below
// 1e-15 over each range. Written as published.
#[allow(clippy::excessive_precision)]
const ERF_A: [f64; 5] =
    [3.1611237438705656, 113.864154151050156, 377.485237685302021, 3209.37758913846947, 0.185777706184603153];
#[allow(clippy::excessive_precision)]
const ERF_B: [f64; 4] = [23.6012909523441209, 244.024637934444173, 1282.61652607737228, 2844.23683343917062];
#[allow(clippy::excessive_precision)]
const ERFC_C: [f64; 9] = [
    0.564188496988670089,
    8.88314979438837594,
    66.1191906371416295,
    298.635138197400131,
    881.95222124176909,
    1712.04761263407058,
    2051.07837782607147,
    1230.33935479799725,
    2.15311535474403846e-8,
];
#[allow(clippy::excessive_precision)]
const ERFC_D: [f64; 8] = [
    15.7449261107098347,
    117.693950891312499,
    537.181101862009858,
    1621.38957456669019,
    3290.79923573345963,
    4362.61909014324716,
    3439.36767414372164,
    1230.33935480374942,
];
#[allow(clippy::excessive_precision)]
const ERFC_P: [f64; 6] = [
    0.305326634961232344,
    0.360344899949804439,
    0.125781726111229246,
    0.0160837851487422766,
    6.58749161529837803e-4,
    0.0163153871373020978,
];
#[allow(clippy::excessive_precision)]
const ERFC_Q: [f64; 5] = [
    2.56852019228982242,
    1.87295284992346047,
    0.527905102951428412,
    0.0605183413124413191,
    0.00233520497626869185,
];

/// Where Cody's small-argument form of erf ends.
const ERF_SMALL: f64 = 0.46875;
/// erfc(x) is below the smallest normal f64 beyond this.
const ERFC_ZERO: f64 = 26.543;

/// erf(x) for |x| ≤ [`ERF_SMALL`]: x·R(x²), R rational of degree 4/4.
#[inline]
fn erf_small(x: f64) -> f64 {
    let y = x * x;
    let mut num = ERF_A[4] * y;
    let mut den = y;
    for i in 0..3 {
        num = (num + ERF_A[i]) * y;
        den = (den + ERF_B[i]) * y;
    }
    x * (num + ERF_A[3]) / (den + ERF_B[3])
}

/// erfc(y) for y > [`ERF_SMALL`]: e^(−y²)·R(y) up to 4 (degree 8/8), e^(−y²)/y·(1/√π −
/// R(1/y²)/y²) beyond (degree 5/5). e^(−y²) is e^(−s²)·e^(−(y − s)(y + s)) with s = y to 1/16
/// below, both exact enough that y²'s rounding is not multiplied by y².
fn erfc_large(y: f64) -> f64 {
    let r = if y <= 4.0 {
        let mut num = ERFC_C[8] * y;
        let mut den = y;
        for i in 0..7 {
            num = (num + ERFC_C[i]) * y;
            den = (den + ERFC_D[i]) * y;
        }
        (num + ERFC_C[7]) / (den + ERFC_D[7])
    } else {
        if y >= ERFC_ZERO {
            return 0.0;
        }
        let z = 1.0 / (y * y);
        let mut num = ERFC_P[5] * z;
        let mut den = z;
        for i in 0..4 {
            num = (num + ERFC_P[i]) * z;
            den = (den + ERFC_Q[i]) * z;
        }
        let r = z * (num + ERFC_P[4]) / (den + ERFC_Q[4]);
        (0.5 * FRAC_2_SQRT_PI - r) / y
    };
    let s = (y * 16.0).trunc() / 16.0;
    let del = (y - s) * (y + s);
    (-s * s).exp() * (-del).exp() * r
}

/// The error function erf(x) = 2/√π ∫₀ˣ e^(−t²) dt, to about 1e-16 relative (W. J. Cody's
/// rational approximations).
pub fn erf(x: f64) -> f64 {
    let y = x.abs();
    if y.is_nan() || y <= ERF_SMALL {
        return erf_small(x);
    }
    let r = (0.5 - erfc_large(y)) + 0.5;
    if x < 0.0 { -r } else { r }
}

/// The complementary error function erfc(x) = 1 − erf(x), to about 1e-15 relative even where
/// it is tiny (W. J. Cody's rational approximations).
pub fn erfc(x: f64) -> f64 {
    let y = x.abs();
    if y.is_nan() {
        return f64::NAN;
    }
    if y <= ERF_SMALL {
        return 1.0 - erf_small(x);
    }
    let r = erfc_large(y);
    if x < 0.0 { 2.0 - r } else { r }
}

// The reference values are mpmath's to 20 digits, as printed.
#[cfg(test)]
#[allow(clippy::excessive_precision)]
mod tests {
    use super::*;
    use crate::insertion::InsertRng;
    use rand::SeedableRng;

    /// Draws a statistical test takes.
    const N: usize = 20_000;

    /// The one-sample Kolmogorov–Smirnov critical value at α = 0.001: K/√N with
    /// K = √(ln(2/α)/2) = 1.949 (the asymptotic Kolmogorov distribution; at N = 20 000 its
    /// finite-N correction, about 0.12/√N relative, is negligible).
    fn ks_critical() -> f64 {
        1.949 / (N as f64).sqrt()
    }

    fn draws(sizes: &SizeDistribution, seed: u64) -> Vec<f64> {
        let mut rng = InsertRng::seed_from_u64(seed);
        (0..N).map(|_| sizes.sample(&mut rng)).collect()
    }

    /// sup |F_N − F| over the sample: at each order statistic x_(i), max(F − (i−1)/N, i/N − F).
    fn ks_statistic(mut xs: Vec<f64>, cdf: impl Fn(f64) -> f64) -> f64 {
        xs.sort_by(f64::total_cmp);
        let n = xs.len() as f64;
        xs.iter()
            .enumerate()
            .map(|(i, &x)| {
                let f = cdf(x);
                (f - i as f64 / n).max((i + 1) as f64 / n - f)
            })
            .fold(0.0, f64::max)
    }

    /// The draws of `sizes` pass the KS test against its own cdf, all inside its bounds; the
    /// draws of `other` (its mean 10 % higher) fail it, so the test can tell them apart.
    fn kolmogorov_smirnov(sizes: &SizeDistribution, other: &SizeDistribution, seed: u64) {
        sizes.check().unwrap();
        other.check().unwrap();
        let xs = draws(sizes, seed);
        let (lo, hi) = (sizes.min_diameter(), sizes.max_diameter());
        assert!(xs.iter().all(|&d| d >= lo && d <= hi), "{sizes:?}: a draw outside [{lo}, {hi}]");
        let same = ks_statistic(xs, |d| sizes.cdf(d));
        let shifted = ks_statistic(draws(other, seed + 1), |d| sizes.cdf(d));
        println!("{sizes:?}: D = {same:.5}, shifted mean D = {shifted:.5}, critical {:.5}", ks_critical());
        assert!(same < ks_critical(), "{sizes:?}: D = {same} ≥ {}", ks_critical());
        assert!(shifted > ks_critical(), "{other:?}: D = {shifted} ≤ {}", ks_critical());
    }

    /// A bimodal cumulative distribution like MFIX's custom files: two ramps with a flat
    /// stretch between them.
    fn bimodal_cdf(shift: f64) -> SizeDistribution {
        SizeDistribution::Cdf {
            diameters: [1.0e-3, 1.2e-3, 2.0e-3, 2.2e-3, 2.6e-3].map(|d| d * shift).to_vec(),
            cdf: vec![0.0, 0.4, 0.4, 0.7, 1.0],
        }
    }

    #[test]
    fn a_cdf_distribution_draws_its_cdf() {
        kolmogorov_smirnov(&bimodal_cdf(1.0), &bimodal_cdf(1.1), 71);
        // Nothing is drawn on the flat stretch (its probability is 0).
        let xs = draws(&bimodal_cdf(1.0), 72);
        assert!(xs.iter().all(|&d| !(d > 1.2e-3 && d < 2.0e-3)));
    }

    #[test]
    fn a_two_point_cdf_is_the_uniform_distribution() {
        // Linear between (a, 0) and (b, 1) is exactly Uniform(a, b): the cdf and E[d³] agree
        // with the uniform's closed forms to rounding.
        let (a, b) = (0.8e-3, 1.3e-3);
        let c = SizeDistribution::Cdf { diameters: vec![a, b], cdf: vec![0.0, 1.0] };
        let u = SizeDistribution::Uniform { min: a, max: b };
        c.check().unwrap();
        for d in [0.5e-3, 0.8e-3, 0.9e-3, 1.05e-3, 1.3e-3, 2e-3] {
            assert!((c.cdf(d) - u.cdf(d)).abs() < 1e-15, "{d}");
        }
        assert!((c.mean_cube() / u.mean_cube() - 1.0).abs() < 1e-14);
        assert_eq!((c.min_diameter(), c.max_diameter()), (a, b));
    }

    #[test]
    fn a_bad_cdf_is_refused() {
        let bad = |d: Vec<f64>, c: Vec<f64>| SizeDistribution::Cdf { diameters: d, cdf: c }.check().is_err();
        assert!(bad(vec![1e-3], vec![1.0]));
        assert!(bad(vec![1e-3, 1e-3], vec![0.0, 1.0]));
        assert!(bad(vec![1e-3, 2e-3], vec![0.0, 0.9]));
        assert!(bad(vec![1e-3, 2e-3, 3e-3], vec![0.0, 0.6, 0.5]));
        assert!(bad(vec![1e-3, 2e-3], vec![0.1, 1.0]));
        assert!(bad(vec![-1e-3, 2e-3], vec![0.0, 1.0]));
    }

    fn uniform() -> SizeDistribution {
        SizeDistribution::Uniform { min: 1e-3, max: 2e-3 }
    }

    /// Mildly truncated, [mean − 2.5σ, mean + 3σ]: 0.992 of the normal, drawn by rejection.
    fn normal(mean: f64) -> SizeDistribution {
        SizeDistribution::Normal { mean, sigma: 1e-4, min: 0.75e-3, max: 1.3e-3 }
    }

    /// Strongly truncated, [mean + 2.5σ, mean + 6σ]: 6.2e-3 of the normal, so nearly every draw
    /// falls through the rejection to the cdf's inversion.
    fn normal_tail(mean: f64) -> SizeDistribution {
        SizeDistribution::Normal { mean, sigma: 1e-4, min: 1.25e-3, max: 1.6e-3 }
    }

    /// Far out, [mean + 4.3σ, mean + 6σ]: 8.5e-6 of the normal, just above the limit.
    fn normal_far(mean: f64) -> SizeDistribution {
        SizeDistribution::Normal { mean, sigma: 1e-4, min: 1.43e-3, max: 1.6e-3 }
    }

    /// Mean 1 mm, deviation 0.3 mm, [0.4, 2.5] mm: 0.998 of the log-normal.
    fn log_normal(mean: f64) -> SizeDistribution {
        SizeDistribution::LogNormal { mean, sigma: 3e-4, min: 0.4e-3, max: 2.5e-3 }
    }

    /// The lower tail, [0.3, 0.5] mm: 0.0134 of the log-normal; draws take both ways.
    fn log_normal_tail(mean: f64) -> SizeDistribution {
        SizeDistribution::LogNormal { mean, sigma: 3e-4, min: 0.3e-3, max: 0.5e-3 }
    }

    #[test]
    fn erf_and_erfc_match_reference_values() {
        // (x, erfc x, erf x) to 20 digits (mpmath at 40 digits).
        let reference = [
            (-3.0, 1.9999779095030014146, -0.99997790950300141456),
            (-0.7, 1.677801193837418473, -0.67780119383741847298),
            (-0.2, 1.2227025892104784541, -0.22270258921047845414),
            (0.0, 1.0, 0.0),
            (0.1, 0.8875370839817151078, 0.1124629160182848922),
            (0.46875, 0.50738652678206200841, 0.49261347321793799159),
            (0.5, 0.47950012218695346232, 0.52049987781304653768),
            (1.0, 0.15729920705028513066, 0.84270079294971486934),
            (2.0, 0.0046777349810472658379, 0.99532226501895273416),
            (3.5, 7.4309837234141274552e-7, 0.99999925690162765859),
            (4.0, 1.5417257900280018852e-8, 0.99999998458274209972),
            (5.0, 1.5374597944280348502e-12, 0.99999999999846254021),
            (8.0, 1.122429717298292708e-29, 1.0),
            (15.0, 7.2129941724512066666e-100, 1.0),
            (26.0, 5.6631924088561428465e-296, 1.0),
        ];
        // Cody's approximations are good to about 1e-16 relative; the arithmetic adds a few
        // ulps (measured against mpmath on 2 400 points in [−6, 27]: 7e-16 for erfc, 3e-16 for
        // erf), so 2e-15.
        for (x, c, e) in reference {
            let rel = |got: f64, want: f64| if want == 0.0 { got.abs() } else { ((got - want) / want).abs() };
            assert!(rel(erfc(x), c) < 2e-15, "erfc({x}) = {:e}, not {c:e}", erfc(x));
            assert!(rel(erf(x), e) < 2e-15, "erf({x}) = {:e}, not {e:e}", erf(x));
        }
        assert_eq!(erfc(f64::INFINITY), 0.0);
        assert_eq!(erfc(f64::NEG_INFINITY), 2.0);
        assert_eq!(erfc(30.0), 0.0);
        assert!(erfc(f64::NAN).is_nan() && erf(f64::NAN).is_nan());
    }

    #[test]
    fn uniform_passes_kolmogorov_smirnov() {
        // The alternative: the same width, its mean 10 % higher.
        kolmogorov_smirnov(&uniform(), &SizeDistribution::Uniform { min: 1.15e-3, max: 2.15e-3 }, 1);
    }

    #[test]
    fn truncated_normal_passes_kolmogorov_smirnov() {
        kolmogorov_smirnov(&normal(1e-3), &normal(1.1e-3), 2);
    }

    #[test]
    fn strongly_truncated_normals_pass_kolmogorov_smirnov() {
        kolmogorov_smirnov(&normal_tail(1e-3), &normal_tail(1.1e-3), 3);
        kolmogorov_smirnov(&normal_far(1e-3), &normal_far(1.1e-3), 4);
    }

    #[test]
    fn truncated_log_normal_passes_kolmogorov_smirnov() {
        kolmogorov_smirnov(&log_normal(1e-3), &log_normal(1.1e-3), 5);
    }

    #[test]
    fn strongly_truncated_log_normal_passes_kolmogorov_smirnov() {
        kolmogorov_smirnov(&log_normal_tail(1e-3), &log_normal_tail(1.1e-3), 6);
    }

    /// The inversion the truncated draws fall back on is the cdf's inverse, to 1e-13 in
    /// probability: windows across the mean, in the upper tail (to 4.3σ out), in the lower
    /// tail (turned), and one reaching 1000σ up.
    #[test]
    fn the_fallback_inverts_the_cdf() {
        let lower = SizeDistribution::Normal { mean: 1e-3, sigma: 1e-4, min: 0.5e-3, max: 0.6e-3 };
        let open = SizeDistribution::Normal { mean: 1e-3, sigma: 1e-4, min: 1.2e-3, max: 0.101 };
        for sizes in [normal(1e-3), normal_tail(1e-3), normal_far(1e-3), lower, open] {
            let SizeDistribution::Normal { mean, sigma, min, max } = sizes else { unreachable!() };
            let (a, b) = normal_window(mean, sigma, min, max);
            let window = StdWindow::new(a, b);
            assert!((window.probability() - std_window(a, b)).abs() <= 1e-16);
            for i in 0..=100 {
                let u = i as f64 / 100.0;
                let d = (mean + sigma * window.quantile(u)).clamp(min, max);
                assert!((sizes.cdf(d) - u).abs() < 1e-13, "{sizes:?}: cdf(quantile({u})) = {}", sizes.cdf(d));
            }
        }
    }

    #[test]
    fn cdfs_run_from_zero_to_one_and_never_fall() {
        let table = SizeDistribution::Table {
            diameters: vec![2e-3, 1e-3, 3e-3],
            fractions: vec![0.5, 0.2, 0.3],
            basis: Basis::Number,
        };
        let all = [
            uniform(),
            normal(1e-3),
            normal_tail(1e-3),
            normal_far(1e-3),
            log_normal(1e-3),
            log_normal_tail(1e-3),
            table,
        ];
        for sizes in all {
            let (lo, hi) = (sizes.min_diameter(), sizes.max_diameter());
            if !matches!(sizes, SizeDistribution::Table { .. }) {
                assert_eq!(sizes.cdf(lo), 0.0, "{sizes:?}");
            }
            assert_eq!(sizes.cdf(0.5 * lo), 0.0, "{sizes:?}");
            assert_eq!(sizes.cdf(hi), 1.0, "{sizes:?}");
            assert_eq!(sizes.cdf(2.0 * hi), 1.0, "{sizes:?}");
            let mut last = 0.0;
            for i in 0..=1000 {
                let f = sizes.cdf(lo + (hi - lo) * i as f64 / 1000.0);
                assert!(f >= last && f <= 1.0, "{sizes:?}: cdf falls to {f} after {last}");
                last = f;
            }
        }
    }

    /// Against the truncated cdfs to 20 digits (mpmath): 1e-14, the rounding of a few erfc
    /// and of the window's bounds in standard units.
    #[test]
    fn cdfs_match_reference_values() {
        let cases = [
            (uniform(), 1.25e-3, 0.25),
            (normal(1e-3), 1.1e-3, 0.8414964262923547909),
            (normal_tail(1e-3), 1.3e-3, 0.78261352445036332517),
            (normal_far(1e-3), 1.45e-3, 0.60221117175506925764),
            (log_normal(1e-3), 1.2e-3, 0.77880902104744435929),
            (log_normal_tail(1e-3), 0.45e-3, 0.37405796420160371246),
        ];
        for (sizes, d, want) in cases {
            let got = sizes.cdf(d);
            assert!(((got - want) / want).abs() < 1e-14, "{sizes:?}: cdf({d}) = {got}, not {want}");
        }
        // A window symmetric about the median puts half below it.
        let symmetric = SizeDistribution::Normal { mean: 1e-3, sigma: 1e-4, min: 0.8e-3, max: 1.2e-3 };
        assert!((symmetric.cdf(1e-3) - 0.5).abs() < 1e-15);
        let (mu, s) = log_normal_parameters(1e-3, 3e-4);
        let symmetric =
            SizeDistribution::LogNormal { mean: 1e-3, sigma: 3e-4, min: (mu - s).exp(), max: (mu + s).exp() };
        assert!((symmetric.cdf(mu.exp()) - 0.5).abs() < 1e-14);
    }

    /// E\[d³\] in closed form against quadrature to 20 digits (mpmath) to 1e-13, against the
    /// untruncated moments for windows ±10σ wide, and against the mean of d³ over N draws to
    /// 4.5 of its standard errors (s/√N, s the draws' deviation of d³).
    #[test]
    fn mean_cube_matches_quadrature_moments_and_draws() {
        let reference = [
            (uniform(), 1.5e-3 * (1e-6 + 4e-6) / 2.0),
            (normal(1e-3), 1.0323289104228328491e-9),
            (normal_tail(1e-3), 2.111816608742934178e-9),
            (normal_far(1e-3), 3.0581300844840492275e-9),
            // The lower tail, [mean − 5σ, mean − 4σ], where the moments about the mean cancel.
            (
                SizeDistribution::Normal { mean: 1e-3, sigma: 1e-4, min: 0.5e-3, max: 0.6e-3 },
                1.9407271438113173195e-10,
            ),
            (log_normal(1e-3), 1.2865513249105987397e-9),
            (log_normal_tail(1e-3), 9.5282193278358720405e-11),
        ];
        for (seed, (sizes, want)) in reference.into_iter().enumerate() {
            sizes.check().unwrap();
            let got = sizes.mean_cube();
            assert!(((got - want) / want).abs() < 1e-13, "{sizes:?}: E[d³] = {got:e}, not {want:e}");
            let cubes: Vec<f64> = draws(&sizes, 100 + seed as u64).iter().map(|d| d * d * d).collect();
            let mean = cubes.iter().sum::<f64>() / N as f64;
            let var = cubes.iter().map(|c| (c - mean) * (c - mean)).sum::<f64>() / (N - 1) as f64;
            let se = (var / N as f64).sqrt();
            println!("{sizes:?}: E[d³] {got:e}, draws {mean:e} ({:.2} se)", (mean - got) / se);
            assert!(
                (mean - got).abs() < 4.5 * se,
                "{sizes:?}: draws' mean {mean:e}, E[d³] {got:e}, se {se:e}"
            );
        }
        // Untruncated: E[d³] = m³ + 3ms² for the normal, m³(1 + s²/m²)³ for the log-normal.
        let (m, s) = (1e-3, 1e-4);
        let wide = SizeDistribution::Normal { mean: m, sigma: s, min: m - 10.0 * s, max: m + 10.0 * s };
        assert!((wide.mean_cube() / (m * m * m + 3.0 * m * s * s) - 1.0).abs() < 1e-14);
        let s = 3e-4;
        let (mu, sl) = log_normal_parameters(m, s);
        let wide = SizeDistribution::LogNormal {
            mean: m,
            sigma: s,
            min: (mu - 12.0 * sl).exp(),
            max: (mu + 12.0 * sl).exp(),
        };
        let r = 1.0 + s * s / (m * m);
        assert!((wide.mean_cube() / (m * m * m * r * r * r) - 1.0).abs() < 1e-13);
        assert_eq!(SizeDistribution::Constant { diameter: 2e-3 }.mean_cube(), 8e-9);
    }

    #[test]
    fn a_table_by_number_is_drawn_at_its_frequencies() {
        let sizes = SizeDistribution::Table {
            diameters: vec![1e-3, 2e-3, 3e-3, 4e-3],
            fractions: vec![0.1, 0.4, 0.5, 0.0],
            basis: Basis::Number,
        };
        sizes.check().unwrap();
        assert_eq!((sizes.min_diameter(), sizes.max_diameter()), (1e-3, 3e-3));
        // E[d³] = 0.1·1 + 0.4·8 + 0.5·27 = 16.8 mm³.
        assert!((sizes.mean_cube() / 16.8e-9 - 1.0).abs() < 1e-15);
        let xs = draws(&sizes, 11);
        let n = N as f64;
        for (k, (&d, &p)) in [1e-3, 2e-3, 3e-3, 4e-3].iter().zip(&[0.1, 0.4, 0.5, 0.0]).enumerate() {
            let count = xs.iter().filter(|&&x| x == d).count() as f64;
            // Binomial: N·p ± 4.5·√(N·p·(1 − p)) (a 7e-6 two-sided chance for each row).
            let sd = (n * p * (1.0 - p)).sqrt();
            println!(
                "row {k}: {count} drawn, {} expected, {:.2} sd",
                n * p,
                (count - n * p) / sd.max(1e-300)
            );
            assert!((count - n * p).abs() <= 4.5 * sd, "row {k}: {count} drawn, {} expected", n * p);
        }
        assert!(xs.iter().all(|x| [1e-3, 2e-3, 3e-3].contains(x)));
    }

    #[test]
    fn a_table_by_mass_is_drawn_at_its_mass_fractions() {
        let diameters = vec![1e-3, 2e-3, 4e-3];
        let mass = vec![0.2, 0.3, 0.5];
        let sizes = SizeDistribution::Table {
            diameters: diameters.clone(),
            fractions: mass.clone(),
            basis: Basis::Mass,
        };
        sizes.check().unwrap();
        // Number fractions ∝ w/d³: 0.2, 0.0375, 0.0078125 (per mm³), summing to 0.2453125; so
        // E[d³] = Σw / Σ(w/d³) = 1/0.2453125 mm³.
        let numbers: Vec<f64> = [0.2, 0.0375, 0.0078125].iter().map(|w| w / 0.2453125).collect();
        assert!((sizes.mean_cube() / (1e-9 / 0.2453125) - 1.0).abs() < 1e-14);
        assert!((sizes.cdf(2e-3) - numbers[0] - numbers[1]).abs() < 1e-15);
        let xs = draws(&sizes, 12);
        let total: f64 = xs.iter().map(|d| d * d * d).sum();
        let ex: f64 = diameters.iter().zip(&numbers).map(|(d, n)| n * d * d * d).sum();
        for (k, &d) in diameters.iter().enumerate() {
            let got = xs.iter().filter(|&&x| x == d).map(|x| x * x * x).sum::<f64>() / total;
            // The ratio estimator's standard error (delta method): with X = d³, I the row's
            // indicator and m its mass fraction, √(E[X²(I − m)²]/N)/E[X], from the table.
            let ey2: f64 = diameters
                .iter()
                .zip(&numbers)
                .enumerate()
                .map(|(j, (e, n))| {
                    let i = if j == k { 1.0 } else { 0.0 };
                    n * e.powi(6) * (i - mass[k]) * (i - mass[k])
                })
                .sum();
            let se = (ey2 / N as f64).sqrt() / ex;
            println!("row {k}: mass fraction {got:.5}, {} wanted, {:.2} se", mass[k], (got - mass[k]) / se);
            assert!(
                (got - mass[k]).abs() < 4.5 * se,
                "row {k}: mass fraction {got}, not {} (se {se})",
                mass[k]
            );
        }
    }

    fn two_phases() -> Mixture {
        Mixture {
            parts: vec![
                MixturePart { phase: 1, density: 2500.0, fraction: 0.3, sizes: normal(1e-3) },
                MixturePart {
                    phase: 2,
                    density: 7800.0,
                    fraction: 0.7,
                    sizes: SizeDistribution::LogNormal { mean: 2e-3, sigma: 4e-4, min: 1e-3, max: 4e-3 },
                },
            ],
            basis: Basis::Mass,
        }
    }

    #[test]
    fn a_mixture_by_mass_is_drawn_at_its_mass_fractions() {
        let mix = two_phases();
        mix.check().unwrap();
        let n = mix.number_fractions();
        let mut rng = InsertRng::seed_from_u64(21);
        let drawn: Vec<(u32, f64)> = (0..N).map(|_| mix.sample(&mut rng)).collect();
        let mass: Vec<f64> =
            drawn.iter().map(|&(phase, d)| if phase == 1 { 2500.0 } else { 7800.0 } * d * d * d).collect();
        let total: f64 = mass.iter().sum();
        let mean_mass = total / N as f64;
        // π/6 of the draws' mean ρd³ is the mean particle mass, within 4.5 standard errors.
        let sd =
            (mass.iter().map(|m| (m - mean_mass) * (m - mean_mass)).sum::<f64>() / (N - 1) as f64).sqrt();
        let se = sd / (N as f64).sqrt();
        assert!((PI / 6.0 * mean_mass - mix.mean_mass()).abs() < 4.5 * PI / 6.0 * se);
        for (i, (phase, want)) in [(1, 0.3), (2, 0.7)].into_iter().enumerate() {
            let mine: Vec<bool> = drawn.iter().map(|&(p, _)| p == phase).collect();
            let got = mass.iter().zip(&mine).filter(|&(_, &m)| m).map(|(m, _)| m).sum::<f64>() / total;
            // The ratio estimator's standard error (delta method), from the draws:
            // √(mean of M²(I − m)²/N) / mean M.
            let ey2 = mass
                .iter()
                .zip(&mine)
                .map(|(m, &b)| {
                    let i = if b { 1.0 } else { 0.0 };
                    m * m * (i - got) * (i - got)
                })
                .sum::<f64>()
                / N as f64;
            let se = (ey2 / N as f64).sqrt() / mean_mass;
            let count = mine.iter().filter(|&&b| b).count() as f64;
            let sd_count = (N as f64 * n[i] * (1.0 - n[i])).sqrt();
            println!(
                "phase {phase}: mass fraction {got:.5} ({:.2} se), number {count} ({:.2} sd)",
                (got - want) / se,
                (count - N as f64 * n[i]) / sd_count
            );
            assert!(
                (got - want).abs() < 4.5 * se,
                "phase {phase}: mass fraction {got}, not {want} (se {se})"
            );
            assert!((count - N as f64 * n[i]).abs() < 4.5 * sd_count, "phase {phase}: {count} particles");
        }
    }

    /// Equal masses of 1 mm grains at 1000 kg/m³ and 2 mm grains at 2000 kg/m³: the small ones
    /// outnumber the large (ρ_B/ρ_A)(d_B/d_A)³ = 16 to 1.
    #[test]
    fn number_fractions_volumes_and_masses_by_hand() {
        let mix = Mixture {
            parts: vec![
                MixturePart {
                    phase: 0,
                    density: 1000.0,
                    fraction: 0.5,
                    sizes: SizeDistribution::Constant { diameter: 1e-3 },
                },
                MixturePart {
                    phase: 1,
                    density: 2000.0,
                    fraction: 0.5,
                    sizes: SizeDistribution::Constant { diameter: 2e-3 },
                },
            ],
            basis: Basis::Mass,
        };
        mix.check().unwrap();
        let n = mix.number_fractions();
        assert!((n[0] - 16.0 / 17.0).abs() < 1e-15 && (n[1] - 1.0 / 17.0).abs() < 1e-15, "{n:?}");
        // (16·1 + 1·8)/17 mm³ and (16·1·1000 + 1·8·2000)/17 mm³·kg/m³, times π/6.
        assert!((mix.mean_volume() / (PI / 6.0 * 24.0 / 17.0 * 1e-9) - 1.0).abs() < 1e-15);
        assert!((mix.mean_mass() / (PI / 6.0 * 32000.0 / 17.0 * 1e-9) - 1.0).abs() < 1e-15);
        assert_eq!((mix.min_diameter(), mix.max_diameter()), (1e-3, 2e-3));
        // By number the fractions are the counts.
        let by_number = Mixture { basis: Basis::Number, ..mix };
        assert_eq!(by_number.number_fractions(), vec![0.5, 0.5]);
        assert!((by_number.mean_volume() / (PI / 6.0 * 4.5e-9) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn a_single_phase_draws_only_its_sizes() {
        let sizes = normal_tail(1e-3);
        let mix = Mixture::single(3, 2500.0, sizes.clone());
        mix.check().unwrap();
        assert_eq!(mix.number_fractions(), vec![1.0]);
        let (mut a, mut b) = (InsertRng::seed_from_u64(5), InsertRng::seed_from_u64(5));
        for _ in 0..1000 {
            assert_eq!(mix.sample(&mut a), (3, sizes.sample(&mut b)));
        }
        assert!((mix.mean_mass() - 2500.0 * PI / 6.0 * sizes.mean_cube()).abs() <= 1e-15 * mix.mean_mass());
    }

    fn three_parts() -> Mixture {
        Mixture {
            parts: vec![
                MixturePart { phase: 1, density: 2500.0, fraction: 0.4, sizes: normal_tail(1e-3) },
                MixturePart { phase: 2, density: 2500.0, fraction: 0.3, sizes: log_normal(1e-3) },
                MixturePart {
                    phase: 3,
                    density: 1200.0,
                    fraction: 0.3,
                    sizes: SizeDistribution::Table {
                        diameters: vec![1e-3, 2e-3],
                        fractions: vec![0.5, 0.5],
                        basis: Basis::Mass,
                    },
                },
            ],
            basis: Basis::Number,
        }
    }

    #[test]
    fn a_seed_gives_one_sequence_and_a_restored_position_continues_it() {
        let mix = three_parts();
        mix.check().unwrap();
        let run = |rng: &mut InsertRng, n: usize| (0..n).map(|_| mix.sample(rng)).collect::<Vec<_>>();
        let (mut a, mut b) = (InsertRng::seed_from_u64(7), InsertRng::seed_from_u64(7));
        let first = run(&mut a, 1000);
        assert_eq!(first, run(&mut b, 1000));
        assert_ne!(first, run(&mut InsertRng::seed_from_u64(8), 1000));
        // A checkpoint stores the word position; a restart from the seed at that position
        // draws what the uninterrupted run draws next.
        let position = a.get_word_pos();
        let rest = run(&mut a, 1000);
        let mut restarted = InsertRng::seed_from_u64(7);
        restarted.set_word_pos(position);
        assert_eq!(rest, run(&mut restarted, 1000));
        assert_eq!(a.get_word_pos(), restarted.get_word_pos());
    }

    #[test]
    fn refusals_say_what_is_wrong() {
        let nan = f64::NAN;
        let cases = [
            (SizeDistribution::Constant { diameter: 0.0 }, "the diameter is 0 m, but it must be positive"),
            (
                SizeDistribution::Uniform { min: nan, max: 1e-3 },
                "the minimum diameter is NaN, not a finite number",
            ),
            (
                SizeDistribution::Uniform { min: 2e-3, max: 1e-3 },
                "the minimum diameter 0.002 m is not below the maximum diameter 0.001 m",
            ),
            (
                SizeDistribution::Normal { mean: 1e-3, sigma: -1e-4, min: 0.5e-3, max: 1.5e-3 },
                "the standard deviation is -0.0001 m, but it must be positive",
            ),
            (
                SizeDistribution::Normal { mean: 1e-3, sigma: 1e-4, min: 1.6e-3, max: 1.8e-3 },
                "the window [0.0016, 0.0018] m holds only 9.866e-10 of the untruncated distribution, \
                 less than the 1e-6 it must hold",
            ),
            (
                SizeDistribution::LogNormal { mean: 1e-3, sigma: 1e-4, min: 2e-3, max: 3e-3 },
                "the window [0.002, 0.003] m holds only 1.292e-12 of the untruncated distribution, \
                 less than the 1e-6 it must hold",
            ),
            (
                SizeDistribution::LogNormal { mean: f64::INFINITY, sigma: 1e-4, min: 2e-3, max: 3e-3 },
                "the mean is inf, not a finite number",
            ),
            (
                SizeDistribution::Table { diameters: vec![], fractions: vec![], basis: Basis::Number },
                "the table has no rows",
            ),
            (
                SizeDistribution::Table {
                    diameters: vec![1e-3, 2e-3],
                    fractions: vec![0.5, 0.25, 0.25],
                    basis: Basis::Number,
                },
                "the table has 2 diameters but 3 fractions",
            ),
            (
                SizeDistribution::Table {
                    diameters: vec![-1e-3, 2e-3],
                    fractions: vec![0.5, 0.5],
                    basis: Basis::Mass,
                },
                "table diameter 0 is -0.001 m, but it must be finite and positive",
            ),
            (
                SizeDistribution::Table {
                    diameters: vec![1e-3, 2e-3],
                    fractions: vec![1.1, -0.1],
                    basis: Basis::Number,
                },
                "table fraction 1 is -0.1, but a fraction must be finite and not negative",
            ),
            (
                SizeDistribution::Table {
                    diameters: vec![1e-3, 2e-3],
                    fractions: vec![0.5, 0.4],
                    basis: Basis::Mass,
                },
                "the table's fractions sum to 0.9, not 1 (within 1e-6)",
            ),
            (
                SizeDistribution::Table {
                    diameters: vec![1e-3, 2e-3, 1e-3],
                    fractions: vec![0.5, 0.25, 0.25],
                    basis: Basis::Number,
                },
                "diameter 0.001 m is on two rows of the table",
            ),
        ];
        for (sizes, message) in cases {
            assert_eq!(sizes.check().unwrap_err().to_string(), message, "{sizes:?}");
        }
        // Within the tolerance is accepted.
        let close = SizeDistribution::Table {
            diameters: vec![1e-3, 2e-3],
            fractions: vec![0.5, 0.5000009],
            basis: Basis::Number,
        };
        close.check().unwrap();

        let part = |density: f64, fraction: f64, sizes: SizeDistribution| MixturePart {
            phase: 0,
            density,
            fraction,
            sizes,
        };
        let mixtures = [
            (Mixture { parts: vec![], basis: Basis::Mass }, "the mixture has no parts"),
            (
                Mixture {
                    parts: vec![part(2500.0, 0.5, uniform()), part(0.0, 0.5, uniform())],
                    basis: Basis::Mass,
                },
                "part 1: the density is 0 kg/m³, but it must be positive",
            ),
            (
                Mixture {
                    parts: vec![
                        part(2500.0, 0.5, SizeDistribution::Uniform { min: 1e-3, max: 1e-3 }),
                        part(2500.0, 0.5, uniform()),
                    ],
                    basis: Basis::Number,
                },
                "part 0: the minimum diameter 0.001 m is not below the maximum diameter 0.001 m",
            ),
            (
                Mixture {
                    parts: vec![part(2500.0, 0.5, uniform()), part(2500.0, 0.25, uniform())],
                    basis: Basis::Number,
                },
                "the parts' fractions sum to 0.75, not 1 (within 1e-6)",
            ),
            (
                Mixture { parts: vec![part(2500.0, nan, uniform())], basis: Basis::Number },
                "part fraction 0 is NaN, but a fraction must be finite and not negative",
            ),
        ];
        for (mix, message) in mixtures {
            assert_eq!(mix.check().unwrap_err().to_string(), message, "{mix:?}");
        }
    }
}
