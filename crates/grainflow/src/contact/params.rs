//! The plain types of the contact inputs and outputs, and the closed forms every model's
//! damping takes: what one phase pair's (or phase–wall pair's) contact is given
//! ([`ContactParams`]), what it is derived into ([`ContactCoeffs`]), the two bodies' elastic
//! constants ([`ElasticPair`]), MFIX's damping coefficient and Tsuji's damping ratio. They
//! depend on nothing else of the contact module: the sub-models (`normal`, `tangential`) and the
//! coefficient table (`coefficients`) build on them.

/// Contact inputs for one phase pair or one phase–wall-material pair.
///
/// Which fields are used depends on the normal model: LSD uses `kn`, `kt_fac`, `etat_fac`
/// and `en`; Hertz uses `en`, `et` and the phases' E and ν; JKR uses `en`, `etat_fac`,
/// `surface_energy` and the phases' E and ν. All use `mu` and `mu_roll`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Normal spring stiffness k_n, N/m (LSD: MFIX `KN` / `KN_W`).
    pub kn: Option<f64>,
    /// Tangential to normal stiffness ratio κ, in [0, 1] (LSD: `KT_FAC` / `KT_W_FAC`, default 2/7).
    pub kt_fac: f64,
    /// Tangential to normal damping ratio, in [0, 1] (LSD: `DES_ETAT_FAC` / `DES_ETAT_W_FAC`,
    /// default 1/2).
    pub etat_fac: f64,
    /// Normal coefficient of restitution e_n, in (0, 1] (`DES_EN_INPUT` / `DES_EN_WALL_INPUT`).
    pub en: f64,
    /// Tangential coefficient of restitution e_t, in (0, 1] (Hertz: `DES_ET_INPUT` /
    /// `DES_ET_WALL_INPUT`).
    pub et: Option<f64>,
    /// Coulomb friction coefficient μ ≥ 0 (`MEW` / `MEW_W`).
    pub mu: f64,
    /// Rolling friction μ_r ≥ 0, m (`MEW_R` / `MEW_RW`): torque −μ_r·|F_n,elastic|·ω̂.
    pub mu_roll: f64,
    /// Normal damping per unit effective mass γ_n, 1/s (damping `MassVelocity` only).
    pub gamma_n: Option<f64>,
    /// Tangential damping per unit effective mass γ_t, 1/s (damping `MassVelocity` only;
    /// default γ_n/2, as LAMMPS).
    pub gamma_t: Option<f64>,
    /// Hertz only: K_n (N/m^1.5) given directly instead of (4/3)E*√R* from E and ν.
    pub hertz_kn: Option<f64>,
    /// Hertz only: K_t (N/m^1.5) given directly instead of 8G*√R*.
    pub hertz_kt: Option<f64>,
    /// JKR only: the surface energy γ, J/m² (LAMMPS's: the work of adhesion is 2γ).
    pub surface_energy: Option<f64>,
}

impl Default for ContactParams {
    /// MFIX's defaults; `kn`, `et` unset, e_n = 1, μ = 0.
    fn default() -> Self {
        ContactParams {
            kn: None,
            kt_fac: 2.0 / 7.0,
            etat_fac: 0.5,
            en: 1.0,
            et: None,
            mu: 0.0,
            mu_roll: 0.0,
            gamma_n: None,
            gamma_t: None,
            hertz_kn: None,
            hertz_kt: None,
            surface_energy: None,
        }
    }
}

/// Derived coefficients of one contact type, as used in the force loop.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactCoeffs {
    /// Normal stiffness: k_n (N/m, LSD), K_n = (4/3)·E*·√R* (N/m^1.5, Hertz) or (4/3)·E*
    /// (Pa, JKR: times the contact radius a).
    pub kn: f64,
    /// Tangential stiffness: k_t = κ·k_n (N/m, LSD), K_t = 8·G*·√R* (N/m^1.5, Hertz) or 8·G*
    /// (Pa, JKR: times a).
    pub kt: f64,
    /// Normal damping η_n (kg/s, or kg/(s·m^¼) for Hertz). For damping that depends on the
    /// particles' masses it is per unit mass (`MassVelocity`: γ_n) or per √mass (`Tsuji`:
    /// α√K_n), and the force loop multiplies by m_eff or √m_eff of the contact.
    pub eta_n: f64,
    /// Tangential damping η_t, scaled like `eta_n`.
    pub eta_t: f64,
    /// Coulomb friction coefficient.
    pub mu: f64,
    /// Rolling friction length, m.
    pub mu_roll: f64,
    /// Effective mass used for the damping, kg.
    pub m_eff: f64,
    /// R*, m: of the phases' radii (JKR; 0 otherwise), or of the contact's own
    /// ([`sized`](super::normal::sized)).
    pub r_star: f64,
    /// Surface energy γ, J/m² (JKR; 0 otherwise).
    pub surface_energy: f64,
    /// The pull-off distance δ_c, m: a formed contact holds down to overlap −δ_c (JKR; 0
    /// otherwise).
    pub pull_off: f64,
}

/// η(K, M, e) = 2·√(K·M)·|ln e|/√(π² + (ln e)²) for 0 < e ≤ 1, and 2·√(K·M) for e = 0.
pub fn damping_coefficient(k: f64, m: f64, e: f64) -> f64 {
    if e <= 0.0 {
        return 2.0 * (k * m).sqrt();
    }
    let l = e.ln();
    2.0 * (k * m).sqrt() * l.abs() / (std::f64::consts::PI.powi(2) + l * l).sqrt()
}

/// LIGGGHTS's damping ratio from restitution, −β = |ln e|/√(ln²e + π²) (1 at e = 0).
pub fn liggghts_beta(e: f64) -> f64 {
    if e <= 0.0 {
        return 1.0;
    }
    let l = e.ln();
    l.abs() / (l * l + std::f64::consts::PI * std::f64::consts::PI).sqrt()
}

/// LAMMPS's fit of Tsuji's damping ratio to the restitution coefficient:
/// α = 1.2728 − 4.2783e + 11.087e² − 22.348e³ + 27.467e⁴ − 18.022e⁵ + 4.8218e⁶.
pub fn tsuji_alpha(e: f64) -> f64 {
    1.2728 - 4.2783 * e + 11.087 * e.powi(2) - 22.348 * e.powi(3) + 27.467 * e.powi(4) - 18.022 * e.powi(5)
        + 4.8218 * e.powi(6)
}

/// The elastic constants of the two bodies of a contact and its effective radius, for the
/// normal models that derive their stiffness from them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticPair {
    /// Young's modulus and Poisson's ratio of body 1, Pa and –.
    pub e1: f64,
    /// Poisson's ratio of body 1.
    pub nu1: f64,
    /// Young's modulus of body 2 (a wall's for a wall contact), Pa.
    pub e2: f64,
    /// Poisson's ratio of body 2.
    pub nu2: f64,
    /// R* = R₁R₂/(R₁ + R₂) of the phases' radii (R of the phase at a wall), m.
    pub r_star: f64,
}

impl ElasticPair {
    /// E* = 1/((1 − ν₁²)/E₁ + (1 − ν₂²)/E₂), Pa.
    pub fn e_star(&self) -> f64 {
        1.0 / ((1.0 - self.nu1 * self.nu1) / self.e1 + (1.0 - self.nu2 * self.nu2) / self.e2)
    }

    /// G* = 1/((2 − ν₁)/G₁ + (2 − ν₂)/G₂), G = E/(2(1 + ν)), Pa.
    pub fn g_star(&self) -> f64 {
        let g1 = self.e1 / (2.0 * (1.0 + self.nu1));
        let g2 = self.e2 / (2.0 * (1.0 + self.nu2));
        1.0 / ((2.0 - self.nu1) / g1 + (2.0 - self.nu2) / g2)
    }
}
