//! The MFIX keywords grainflow knows: their type, unit, MFIX default and what grainflow does
//! with them. docs/mfix-decks.md lists the same table; a test checks that every keyword here
//! is documented there.
//!
//! Defaults are MFIX 21.3's, from its keyword documentation (MFIX User Guide, "Keyword
//! reference": Run Control, Physical Parameters, Geometry and Discretization, Gas Phase, Solids
//! Phase, Discrete Element Simulation, Discrete Element Model, Output Control), which is
//! generated from MFIX's namelist initialisation. Only names and values are taken from it.

/// The type of a keyword's values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ty {
    /// A real number (also `@( … )`).
    Real,
    /// A whole number.
    Int,
    /// A logical.
    Bool,
    /// A character string.
    Str,
    /// Not inspected (ignored keywords).
    Any,
}

/// The dimension of a keyword's value, for `UNITS = 'CGS'` decks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// Dimensionless, or a time (s in both systems).
    None,
    /// cm → m.
    Length,
    /// g/cm³ → kg/m³.
    Density,
    /// dyne/cm → N/m.
    Stiffness,
    /// barye (dyne/cm²) → Pa.
    Modulus,
    /// cm/s² → m/s².
    Acceleration,
    /// cm/s → m/s.
    Velocity,
    /// g/s → kg/s.
    MassFlow,
}

impl Unit {
    /// Converts a CGS value to SI. Divisions by exact powers of ten give the correctly rounded
    /// SI value of the number as written.
    pub fn cgs_to_si(self, v: f64) -> f64 {
        match self {
            Unit::None => v,
            Unit::Length | Unit::Acceleration | Unit::Velocity => v / 100.0,
            Unit::Density => v * 1000.0,
            Unit::Stiffness | Unit::MassFlow => v / 1000.0,
            Unit::Modulus => v / 10.0,
        }
    }

    /// SI unit name for messages.
    pub fn si(self) -> &'static str {
        match self {
            Unit::None => "",
            Unit::Length => "m",
            Unit::Density => "kg/m³",
            Unit::Stiffness => "N/m",
            Unit::Modulus => "Pa",
            Unit::Acceleration => "m/s²",
            Unit::Velocity => "m/s",
            Unit::MassFlow => "kg/s",
        }
    }

    /// CGS unit name for messages.
    pub fn cgs(self) -> &'static str {
        match self {
            Unit::None => "",
            Unit::Length => "cm",
            Unit::Density => "g/cm³",
            Unit::Stiffness => "dyne/cm",
            Unit::Modulus => "barye (dyne/cm²)",
            Unit::Acceleration => "cm/s²",
            Unit::Velocity => "cm/s",
            Unit::MassFlow => "g/s",
        }
    }
}

/// Why an ignored keyword cannot change a pure-DEM result. The sentence is printed once per
/// group with the keywords of the deck that fall in it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Why {
    /// Gas-phase properties and gas–particle coupling.
    Gas,
    /// Initial and boundary conditions of the Eulerian fields.
    Fields,
    /// The fluid solver.
    FluidSolver,
    /// The fluid grid.
    Grid,
    /// Energy, species and heat transfer.
    Thermal,
    /// Continuum (TFM) solids.
    Continuum,
    /// MPPIC parcels.
    Pic,
    /// Neighbour search.
    Neighbor,
    /// Cohesion parameters (USE_COHESION itself is refused when true).
    Cohesion,
    /// Output, restart files, logs and run management.
    Output,
}

impl Why {
    /// The reason, as printed.
    pub fn sentence(self) -> &'static str {
        match self {
            Why::Gas => "gas phase and gas–particle coupling (RO_G0 = 0: there is no gas)",
            Why::Fields => {
                "initial and boundary conditions of the gas and continuum fields (they do not act on the particles once there is no gas)"
            }
            Why::FluidSolver => "fluid solver settings (no fluid is solved)",
            Why::Grid => {
                "fluid grid (the DEM needs no grid; IMAX, JMAX, KMAX only place MFIX's cells: the IC and BC regions on their faces, the cut cells of STL walls)"
            }
            Why::Thermal => "energy, species and heat transfer (they do not act on the particle motion)",
            Why::Continuum => "continuum (TFM) solids settings (every solids phase is DEM)",
            Why::Pic => "MPPIC settings (every solids phase is DEM)",
            Why::Neighbor => {
                "neighbour search tuning (grainflow rebuilds its Verlet list whenever a particle has moved half the skin, so every contact is found)"
            }
            Why::Cohesion => "cohesion parameters (used only with USE_COHESION = .TRUE.)",
            Why::Output => {
                "output, restart files, logs and run management (grainflow writes its own outputs)"
            }
        }
    }
}

/// The value a refused keyword may have (its MFIX default) without being refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Allow {
    /// `.FALSE.`
    False,
    /// `0`
    Zero,
    /// Refused whatever its value.
    Never,
}

/// What grainflow does with a keyword.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Translated into the case.
    Used,
    /// Inspected by a rule of the translation: accepted for some values, refused for others.
    Checked,
    /// Accepted and ignored: it cannot change a pure-DEM result.
    Ignored(Why),
    /// Refused unless it has the allowed value: it would change the result and grainflow
    /// cannot do what it asks.
    Refused(Allow, &'static str),
}

/// MFIX's default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Dflt {
    /// No default: the keyword is required (by MFIX and by grainflow).
    Required,
    /// MFIX requires it; grainflow does without (a missing one is reported).
    MfixRequired,
    /// Undefined unless given; what that means is said where it is used.
    Undefined,
    /// A number.
    Real(f64),
    /// A whole number.
    Int(i64),
    /// A logical.
    Bool(bool),
    /// A string.
    Str(&'static str),
    /// A rule, in words.
    Rule(&'static str),
}

/// One keyword. A name ending in `*` stands for every keyword with that prefix (exact names
/// take precedence).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Keyword {
    /// Upper-case name.
    pub name: &'static str,
    /// Value type.
    pub ty: Ty,
    /// Number of subscripts: `Some(0)` scalar, `Some(1)` `KEY(i)`, `Some(2)` `KEY(i,j)`;
    /// `None` any.
    pub dims: Option<u8>,
    /// Lowest index of the first subscript (1, or 0 for MFIX's cell and phase-0 arrays).
    pub base: i64,
    /// Dimension, for CGS decks.
    pub unit: Unit,
    /// What grainflow does with it.
    pub role: Role,
    /// MFIX's default.
    pub default: Dflt,
}

const fn used(name: &'static str, ty: Ty, dims: u8, unit: Unit, default: Dflt) -> Keyword {
    Keyword { name, ty, dims: Some(dims), base: 1, unit, role: Role::Used, default }
}

const fn checked(name: &'static str, ty: Ty, dims: u8, unit: Unit, default: Dflt) -> Keyword {
    Keyword { name, ty, dims: Some(dims), base: 1, unit, role: Role::Checked, default }
}

const fn ignored(name: &'static str, why: Why) -> Keyword {
    Keyword {
        name,
        ty: Ty::Any,
        dims: None,
        base: 0,
        unit: Unit::None,
        role: Role::Ignored(why),
        default: Dflt::Undefined,
    }
}

const fn grid(name: &'static str) -> Keyword {
    Keyword {
        name,
        ty: Ty::Any,
        dims: None,
        base: 0,
        unit: Unit::None,
        role: Role::Ignored(Why::Grid),
        default: Dflt::MfixRequired,
    }
}

const fn refused(name: &'static str, allow: Allow, why: &'static str) -> Keyword {
    let (ty, default) = match allow {
        Allow::False => (Ty::Bool, Dflt::Bool(false)),
        Allow::Zero => (Ty::Real, Dflt::Real(0.0)),
        Allow::Never => (Ty::Any, Dflt::Undefined),
    };
    let dims = if matches!(allow, Allow::Never) { None } else { Some(0) };
    Keyword { name, ty, dims, base: 1, unit: Unit::None, role: Role::Refused(allow, why), default }
}

use Dflt::*;
use Ty as T;
use Unit as U;

const NO_2D: &str = "axisymmetric 2-D runs are not supported, grainflow is Cartesian";
const NO_VDW: &str = "MFIX's van der Waals cohesion (Hamaker force with cut-offs and asperities) is not implemented; grainflow's cohesion is the JKR law, [contact] model = \"jkr\" in a TOML case, a different model";
const NO_IMPLICIT: &str = "implicit cut-cell geometry (quadrics, polygons, user functions) is not read; describe the walls as STL (USE_STL)";

/// Every keyword grainflow knows, with MFIX 21.3's default (see the module documentation).
pub const KEYWORDS: &[Keyword] = &[
    // Run control.
    used("RUN_NAME", T::Str, 0, U::None, MfixRequired),
    used("DESCRIPTION", T::Str, 0, U::None, Undefined),
    used("UNITS", T::Str, 0, U::None, Required),
    checked("RUN_TYPE", T::Str, 0, U::None, MfixRequired),
    used("TIME", T::Real, 0, U::None, Real(0.0)),
    used("TSTOP", T::Real, 0, U::None, Required),
    checked("DT", T::Real, 0, U::None, Undefined),
    checked("CALL_USR", T::Bool, 0, U::None, Bool(false)),
    // Physical parameters.
    used("GRAVITY", T::Real, 0, U::Acceleration, Rule("9.80665 m/s² (SI) or 980.665 cm/s² (CGS)")),
    used("GRAVITY_X", T::Real, 0, U::Acceleration, Rule("0; all three components 0 means GRAVITY along −y")),
    used("GRAVITY_Y", T::Real, 0, U::Acceleration, Rule("0; all three components 0 means GRAVITY along −y")),
    used("GRAVITY_Z", T::Real, 0, U::Acceleration, Rule("0; all three components 0 means GRAVITY along −y")),
    // Geometry.
    checked("COORDINATES", T::Str, 0, U::None, MfixRequired),
    used("X_MIN", T::Real, 0, U::Length, Rule("0, or X_MAX − XLENGTH")),
    used("X_MAX", T::Real, 0, U::Length, Rule("X_MIN + XLENGTH")),
    used("XLENGTH", T::Real, 0, U::Length, Rule("X_MAX − X_MIN")),
    used("Y_MIN", T::Real, 0, U::Length, Rule("0, or Y_MAX − YLENGTH")),
    used("Y_MAX", T::Real, 0, U::Length, Rule("Y_MIN + YLENGTH")),
    used("YLENGTH", T::Real, 0, U::Length, Rule("Y_MAX − Y_MIN")),
    used("Z_MIN", T::Real, 0, U::Length, Rule("0, or Z_MAX − ZLENGTH")),
    used("Z_MAX", T::Real, 0, U::Length, Rule("Z_MIN + ZLENGTH")),
    used("ZLENGTH", T::Real, 0, U::Length, Rule("Z_MAX − Z_MIN")),
    grid("IMAX"),
    grid("JMAX"),
    grid("KMAX"),
    ignored("DX", Why::Grid),
    ignored("DY", Why::Grid),
    ignored("DZ", Why::Grid),
    ignored("XMIN", Why::Grid),
    ignored("I_CYL_NUM", Why::Grid),
    ignored("I_CYL_TRANSITION", Why::Grid),
    ignored("NODESI", Why::Grid),
    ignored("NODESJ", Why::Grid),
    ignored("NODESK", Why::Grid),
    used("NO_K", T::Bool, 0, U::None, Bool(false)),
    used("CYCLIC_X", T::Bool, 0, U::None, Bool(false)),
    used("CYCLIC_X_PD", T::Bool, 0, U::None, Bool(false)),
    used("CYCLIC_Y", T::Bool, 0, U::None, Bool(false)),
    used("CYCLIC_Y_PD", T::Bool, 0, U::None, Bool(false)),
    used("CYCLIC_Z", T::Bool, 0, U::None, Bool(false)),
    used("CYCLIC_Z_PD", T::Bool, 0, U::None, Bool(false)),
    refused("CYLINDRICAL_2D", Allow::False, NO_2D),
    used("CARTESIAN_GRID", T::Bool, 0, U::None, Bool(false)),
    used("USE_STL", T::Bool, 0, U::None, Bool(false)),
    used("SCALE_STL", T::Real, 0, U::None, Real(1.0)),
    used("TX_STL", T::Real, 0, U::Length, Real(0.0)),
    used("TY_STL", T::Real, 0, U::Length, Real(0.0)),
    used("TZ_STL", T::Real, 0, U::Length, Real(0.0)),
    refused("USE_MSH", Allow::False, "Gmsh geometry (.msh) is not read; export the surface as STL (USE_STL)"),
    refused("USE_POLYGON", Allow::False, NO_IMPLICIT),
    refused("N_QUADRIC", Allow::Zero, NO_IMPLICIT),
    refused("QUADRIC_FORM", Allow::Never, NO_IMPLICIT),
    refused("N_USR_DEF", Allow::Zero, NO_IMPLICIT),
    used("TOL_SMALL_CELL", T::Real, 0, U::None, Real(0.01)),
    ignored("TOL_SMALL_AREA", Why::Grid),
    ignored("TOL_SNAP", Why::Grid),
    ignored("TOL_MERGE", Why::Grid),
    ignored("TOL_DELH", Why::Grid),
    ignored("TOL_STL", Why::Grid),
    ignored("TOL_STL_DP", Why::Grid),
    ignored("TOL_F", Why::Grid),
    ignored("TOL_POLYGON", Why::Grid),
    ignored("FAC_DIM_MAX_CUT_CELL", Why::Grid),
    ignored("DIM_FACETS_PER_CELL", Why::Grid),
    ignored("STL_SMALL_ANGLE", Why::Grid),
    ignored("OUT_STL_VALUE", Why::Grid),
    ignored("ITERMAX_INT", Why::Grid),
    ignored("SET_CORNER_CELLS", Why::Grid),
    ignored("PRINT_PROGRESS_BAR", Why::Grid),
    ignored("CG_*", Why::Grid),
    ignored("RE_INDEXING", Why::Grid),
    ignored("ADJUST_PROC_DOMAIN_SIZE", Why::Grid),
    ignored("REPORT_BEST_DOMAIN_SIZE", Why::Grid),
    ignored("MINIMIZE_SEND_RECV", Why::Grid),
    ignored("CG_SAFE_MODE", Why::Grid),
    ignored("STL_BC_ID", Why::Grid),
    // Gas phase.
    checked("RO_G0", T::Real, 0, U::Density, Rule("undefined: ideal-gas density, gas and particles coupled")),
    ignored("MU_G0", Why::Gas),
    ignored("K_G0", Why::Gas),
    ignored("C_PG0", Why::Gas),
    ignored("DIF_G0", Why::Gas),
    ignored("MW_AVG", Why::Gas),
    ignored("MW_G", Why::Gas),
    ignored("NMAX_G", Why::Gas),
    ignored("SPECIES_G", Why::Gas),
    ignored("SPECIES_ALIAS_G", Why::Gas),
    ignored("P_REF", Why::Gas),
    ignored("P_SCALE", Why::Gas),
    ignored("DRAG_TYPE", Why::Gas),
    ignored("DRAG_C1", Why::Gas),
    ignored("DRAG_D1", Why::Gas),
    ignored("LAM_HYS", Why::Gas),
    ignored("SPHERICITY_DG", Why::Gas),
    ignored("REF_LENGTH_DG", Why::Gas),
    ignored("SUBGRID_TYPE", Why::Gas),
    ignored("FILTER_SIZE_RATIO", Why::Gas),
    ignored("SUBGRID_WALL", Why::Gas),
    ignored("TURBULENCE_MODEL", Why::Gas),
    ignored("MU_GMAX", Why::Gas),
    ignored("MOMENTUM_X_EQ", Why::Gas),
    ignored("MOMENTUM_Y_EQ", Why::Gas),
    ignored("MOMENTUM_Z_EQ", Why::Gas),
    ignored("JACKSON", Why::Gas),
    ignored("ISHII", Why::Gas),
    ignored("MODEL_B", Why::Gas),
    ignored("NSCALAR", Why::Gas),
    ignored("PHASE4SCALAR", Why::Gas),
    ignored("DELP_X", Why::Gas),
    ignored("DELP_Y", Why::Gas),
    ignored("DELP_Z", Why::Gas),
    ignored("FLUX_G", Why::Gas),
    ignored("SHEAR", Why::Gas),
    ignored("V_SH", Why::Gas),
    ignored("DES_ONEWAY_COUPLED", Why::Gas),
    ignored("DES_EXPLICITLY_COUPLED", Why::Gas),
    ignored("DES_INTERP_*", Why::Gas),
    ignored("DES_DIFFUSE_WIDTH", Why::Gas),
    ignored("DES_REPORT_MASS_INTERP", Why::Gas),
    ignored("NFACTOR", Why::Gas),
    ignored("DTSOLID_UPDATE_DT", Why::Gas),
    // Initial and boundary conditions.
    used("GENER_PART_CONFIG", T::Bool, 0, U::None, Bool(false)),
    checked("IC_X_W", T::Real, 1, U::Length, Undefined),
    checked("IC_X_E", T::Real, 1, U::Length, Undefined),
    checked("IC_Y_S", T::Real, 1, U::Length, Undefined),
    checked("IC_Y_N", T::Real, 1, U::Length, Undefined),
    checked("IC_Z_B", T::Real, 1, U::Length, Undefined),
    checked("IC_Z_T", T::Real, 1, U::Length, Undefined),
    used("IC_EP_S", T::Real, 2, U::None, Real(0.0)),
    used("IC_U_S", T::Real, 2, U::Velocity, Real(0.0)),
    used("IC_V_S", T::Real, 2, U::Velocity, Real(0.0)),
    used("IC_W_S", T::Real, 2, U::Velocity, Real(0.0)),
    used("IC_PSD_TYPE", T::Str, 2, U::None, Str("MONO")),
    used("IC_PSD_MEAN_DP", T::Real, 2, U::Length, Undefined),
    used("IC_PSD_STDEV", T::Real, 2, U::Length, Undefined),
    used("IC_PSD_MIN_DP", T::Real, 2, U::Length, Undefined),
    used("IC_PSD_MAX_DP", T::Real, 2, U::Length, Undefined),
    used("IC_THETA_M", T::Real, 2, U::None, Real(0.0)),
    used("IC_DES_LATTICE", T::Str, 2, U::None, Str("HEXA")),
    used("IC_DES_SPACING", T::Real, 2, U::None, Real(0.05)),
    used("IC_DES_SPACE_FACTOR_X", T::Real, 2, U::None, Real(1.0)),
    used("IC_DES_SPACE_FACTOR_Y", T::Real, 2, U::None, Real(1.0)),
    used("IC_DES_SPACE_FACTOR_Z", T::Real, 2, U::None, Real(1.0)),
    used("IC_DES_RAND", T::Real, 2, U::None, Real(0.0)),
    used("IC_DES_RAND_FACTOR_X", T::Real, 2, U::None, Real(1.0)),
    used("IC_DES_RAND_FACTOR_Y", T::Real, 2, U::None, Real(1.0)),
    used("IC_DES_RAND_FACTOR_Z", T::Real, 2, U::None, Real(1.0)),
    used("IC_DES_CHECK_STL_OVERLAP", T::Bool, 2, U::None, Bool(true)),
    ignored("IC_*", Why::Fields),
    checked("BC_TYPE", T::Str, 1, U::None, Undefined),
    checked("BC_X_W", T::Real, 1, U::Length, Undefined),
    checked("BC_X_E", T::Real, 1, U::Length, Undefined),
    checked("BC_Y_S", T::Real, 1, U::Length, Undefined),
    checked("BC_Y_N", T::Real, 1, U::Length, Undefined),
    checked("BC_Z_B", T::Real, 1, U::Length, Undefined),
    checked("BC_Z_T", T::Real, 1, U::Length, Undefined),
    checked("BC_I_W", T::Int, 1, U::None, Undefined),
    checked("BC_I_E", T::Int, 1, U::None, Undefined),
    checked("BC_J_S", T::Int, 1, U::None, Undefined),
    checked("BC_J_N", T::Int, 1, U::None, Undefined),
    checked("BC_K_B", T::Int, 1, U::None, Undefined),
    checked("BC_K_T", T::Int, 1, U::None, Undefined),
    checked("BC_UW_S", T::Real, 2, U::Velocity, Real(0.0)),
    checked("BC_VW_S", T::Real, 2, U::Velocity, Real(0.0)),
    checked("BC_WW_S", T::Real, 2, U::Velocity, Real(0.0)),
    used("BC_EP_S", T::Real, 2, U::None, Undefined),
    used("BC_U_S", T::Real, 2, U::Velocity, Real(0.0)),
    used("BC_V_S", T::Real, 2, U::Velocity, Real(0.0)),
    used("BC_W_S", T::Real, 2, U::Velocity, Real(0.0)),
    used("BC_MASSFLOW_S", T::Real, 2, U::MassFlow, Undefined),
    used("BC_PSD_TYPE", T::Str, 2, U::None, Str("MONO")),
    used("BC_PSD_MEAN_DP", T::Real, 2, U::Length, Undefined),
    used("BC_PSD_STDEV", T::Real, 2, U::Length, Undefined),
    used("BC_PSD_MIN_DP", T::Real, 2, U::Length, Undefined),
    used("BC_PSD_MAX_DP", T::Real, 2, U::Length, Undefined),
    ignored("BC_*", Why::Fields),
    refused(
        "PS_*",
        Allow::Never,
        "point sources add mass and momentum; grainflow has none: remove the PS_ keywords",
    ),
    checked("IS_TYPE", T::Str, 1, U::None, Undefined),
    checked("IS_X_W", T::Real, 1, U::Length, Undefined),
    checked("IS_X_E", T::Real, 1, U::Length, Undefined),
    checked("IS_Y_S", T::Real, 1, U::Length, Undefined),
    checked("IS_Y_N", T::Real, 1, U::Length, Undefined),
    checked("IS_Z_B", T::Real, 1, U::Length, Undefined),
    checked("IS_Z_T", T::Real, 1, U::Length, Undefined),
    refused(
        "IS_*",
        Allow::Never,
        "internal surfaces' other settings (permeability, gas-side conditions) are not read; STL internal surfaces (IS_TYPE = 'STL') are read from their region alone",
    ),
    // Fluid solver.
    ignored("MAX_NIT", Why::FluidSolver),
    ignored("NORM_G", Why::FluidSolver),
    ignored("NORM_S", Why::FluidSolver),
    ignored("PPG_DEN", Why::FluidSolver),
    ignored("EPP_DEN", Why::FluidSolver),
    ignored("TOL_RESID*", Why::FluidSolver),
    ignored("TOL_DIVERGE", Why::FluidSolver),
    ignored("TOL_SUM_RESID_ABS", Why::FluidSolver),
    ignored("DETECT_STALL", Why::FluidSolver),
    ignored("LEQ_*", Why::FluidSolver),
    ignored("UR_*", Why::FluidSolver),
    ignored("DISCRETIZE", Why::FluidSolver),
    ignored("DEF_COR", Why::FluidSolver),
    ignored("CHI_SCHEME", Why::FluidSolver),
    ignored("CN_ON", Why::FluidSolver),
    ignored("MAX_INLET_VEL_FAC", Why::FluidSolver),
    ignored("DO_TRANSPOSE", Why::FluidSolver),
    ignored("ICHECK_BICGS", Why::FluidSolver),
    ignored("OPT_PARALLEL", Why::FluidSolver),
    ignored("USE_DOLOOP", Why::FluidSolver),
    ignored("IS_SERIAL", Why::FluidSolver),
    ignored("DIL_EP_S", Why::FluidSolver),
    ignored("ZERO_EP_S", Why::FluidSolver),
    ignored("ZERO_X_GS", Why::FluidSolver),
    ignored("TMIN", Why::FluidSolver),
    ignored("TMAX", Why::FluidSolver),
    ignored("DT_MAX", Why::FluidSolver),
    ignored("DT_MIN", Why::FluidSolver),
    ignored("DT_FAC", Why::FluidSolver),
    ignored("PERSISTENT_MODE", Why::FluidSolver),
    ignored("AUTO_RESTART", Why::FluidSolver),
    // Solids phases.
    used("MMAX", T::Int, 0, U::None, Int(1)),
    checked("SOLIDS_MODEL", T::Str, 1, U::None, Str("TFM")),
    used("D_P0", T::Real, 1, U::Length, Required),
    used("RO_S0", T::Real, 1, U::Density, Required),
    ignored("ENERGY_EQ", Why::Thermal),
    ignored("SPECIES_EQ", Why::Thermal),
    ignored("K_S0", Why::Thermal),
    ignored("C_PS0", Why::Thermal),
    ignored("KS_MODEL", Why::Thermal),
    ignored("DES_EM", Why::Thermal),
    ignored("NMAX_S", Why::Thermal),
    ignored("SPECIES_S", Why::Thermal),
    ignored("SPECIES_ALIAS_S", Why::Thermal),
    ignored("MW_S", Why::Thermal),
    ignored("X_S0", Why::Thermal),
    ignored("RO_XS0", Why::Thermal),
    ignored("INERT_SPECIES", Why::Thermal),
    ignored("DIL_INERT_X_VSD", Why::Thermal),
    ignored("DIL_FACTOR_VSD", Why::Thermal),
    ignored("DES_CONV_CORR", Why::Thermal),
    ignored("DES_MIN_COND_DIST", Why::Thermal),
    ignored("FLPC", Why::Thermal),
    ignored("E_YOUNG_ACTUAL", Why::Thermal),
    ignored("EW_YOUNG_ACTUAL", Why::Thermal),
    ignored("V_POISSON_ACTUAL", Why::Thermal),
    ignored("VW_POISSON_ACTUAL", Why::Thermal),
    ignored("NRR", Why::Thermal),
    refused("STIFF_CHEMISTRY", Allow::False, "chemistry changes particle mass and size; grainflow has none"),
    refused("USE_RRATES", Allow::False, "chemistry changes particle mass and size; grainflow has none"),
    ignored("KT_TYPE", Why::Continuum),
    ignored("FRICTION_MODEL", Why::Continuum),
    ignored("EP_STAR", Why::Continuum),
    ignored("EP_S_MAX", Why::Continuum),
    ignored("CLOSE_PACKED", Why::Continuum),
    ignored("C_E", Why::Continuum),
    ignored("C_F", Why::Continuum),
    ignored("PHI", Why::Continuum),
    ignored("PHI_W", Why::Continuum),
    ignored("E_W", Why::Continuum),
    ignored("MU_S0", Why::Continuum),
    ignored("YU_STANDISH", Why::Continuum),
    ignored("FEDORS_LANDEL", Why::Continuum),
    ignored("MPPIC_*", Why::Pic),
    ignored("PIC_*", Why::Pic),
    ignored("FRIC_EXP_PIC", Why::Pic),
    ignored("PSFAC_FRIC_PIC", Why::Pic),
    ignored("FRIC_NON_SING_FAC", Why::Pic),
    refused(
        "CGP_*",
        Allow::Never,
        "coarse-grained particles (CGP) are not supported; use SOLIDS_MODEL = 'DEM' with real particle sizes",
    ),
    // Discrete element simulation.
    used("PARTICLES", T::Int, 0, U::None, Int(1)),
    refused(
        "PART_IN_*",
        Allow::Never,
        "filters on particle_input.dat change which particles are read; grainflow reads every particle: remove the PART_IN_ keywords",
    ),
    used("DES_INTG_METHOD", T::Str, 0, U::None, Str("EULER")),
    used("DTSOLID_FACTOR", T::Real, 0, U::None, Real(50.0)),
    used("FACTOR_RLM", T::Real, 0, U::None, Real(1.2)),
    ignored("NEIGHBOR_SEARCH_N", Why::Neighbor),
    ignored("NEIGHBOR_SEARCH_RAD_RATIO", Why::Neighbor),
    ignored("DES_NEIGHBOR_SEARCH", Why::Neighbor),
    used(
        "DESGRIDSEARCH_IMAX",
        T::Int,
        0,
        U::None,
        Rule("⌊XLENGTH / min(3 largest diameters, the fluid cell)⌋, at least 1"),
    ),
    used(
        "DESGRIDSEARCH_JMAX",
        T::Int,
        0,
        U::None,
        Rule("⌊YLENGTH / min(3 largest diameters, the fluid cell)⌋, at least 1"),
    ),
    used(
        "DESGRIDSEARCH_KMAX",
        T::Int,
        0,
        U::None,
        Rule("⌊ZLENGTH / min(3 largest diameters, the fluid cell)⌋, at least 1"),
    ),
    ignored("MINIMIZE_DES_FACET_LIST", Why::Neighbor),
    refused(
        "USE_VDH_DEM_MODEL",
        Allow::False,
        "the van der Hoef rotation of the tangential history is not MFIX's default; grainflow's nearest option is history = \"rotate\" in a TOML case",
    ),
    // Discrete element model: collisions.
    used("DES_COLL_MODEL", T::Str, 0, U::None, Str("LSD")),
    used("KN", T::Real, 0, U::Stiffness, Rule("undefined; required by LSD")),
    used("KN_W", T::Real, 0, U::Stiffness, Rule("undefined; required by LSD")),
    used("KT_FAC", T::Real, 0, U::None, Real(2.0 / 7.0)),
    used("KT_W_FAC", T::Real, 0, U::None, Real(2.0 / 7.0)),
    used("DES_ETAT_FAC", T::Real, 0, U::None, Real(0.5)),
    used("DES_ETAT_W_FAC", T::Real, 0, U::None, Real(0.5)),
    used("MEW", T::Real, 0, U::None, Required),
    used("MEW_W", T::Real, 0, U::None, Required),
    used("MEW_R", T::Real, 0, U::Length, Real(0.0)),
    used("MEW_RW", T::Real, 0, U::Length, Real(0.0)),
    used("DES_EN_INPUT", T::Real, 1, U::None, Required),
    used("DES_EN_WALL_INPUT", T::Real, 1, U::None, Required),
    used("DES_ET_INPUT", T::Real, 1, U::None, Rule("undefined; required by HERTZIAN")),
    used("DES_ET_WALL_INPUT", T::Real, 1, U::None, Rule("undefined; required by HERTZIAN")),
    used("E_YOUNG", T::Real, 1, U::Modulus, Rule("undefined; required by HERTZIAN")),
    used("V_POISSON", T::Real, 1, U::None, Rule("undefined; required by HERTZIAN")),
    used("EW_YOUNG", T::Real, 0, U::Modulus, Rule("undefined; required by HERTZIAN")),
    used("VW_POISSON", T::Real, 0, U::None, Rule("undefined; required by HERTZIAN")),
    refused("USE_COHESION", Allow::False, NO_VDW),
    refused("VAN_DER_WAALS", Allow::False, NO_VDW),
    ignored("HAMAKER_CONSTANT", Why::Cohesion),
    ignored("WALL_HAMAKER_CONSTANT", Why::Cohesion),
    ignored("VDW_OUTER_CUTOFF", Why::Cohesion),
    ignored("VDW_INNER_CUTOFF", Why::Cohesion),
    ignored("WALL_VDW_OUTER_CUTOFF", Why::Cohesion),
    ignored("WALL_VDW_INNER_CUTOFF", Why::Cohesion),
    ignored("ASPERITIES", Why::Cohesion),
    // Output control.
    used("WRITE_VTK_FILES", T::Bool, 0, U::None, Bool(false)),
    used("VTK_DT", T::Real, 1, U::None, Undefined),
    used("VTK_DATA", T::Str, 1, U::None, Str("C")),
    ignored("VTK_*", Why::Output),
    ignored("PROJECT_VERSION", Why::Output),
    ignored("RES_DT", Why::Output),
    ignored("RES_BACKUP_DT", Why::Output),
    ignored("RES_BACKUPS", Why::Output),
    ignored("SPX_DT", Why::Output),
    ignored("OUT_DT", Why::Output),
    ignored("NLOG", Why::Output),
    ignored("FULL_LOG", Why::Output),
    ignored("USR_*", Why::Output),
    ignored("REPORT_MASS_BALANCE_DT", Why::Output),
    ignored("REPORT_SOLID_INVENTORY", Why::Output),
    ignored("REPORT_SOLID_INVENTORY_DT", Why::Output),
    ignored("PRINT_DES_DATA", Why::Output),
    ignored("DES_OUTPUT_TYPE", Why::Output),
    ignored("DEBUG_DES", Why::Output),
    ignored("FOCUS_PARTICLE", Why::Output),
    ignored("VTP_DIR", Why::Output),
    ignored("VTU_DIR", Why::Output),
    ignored("FRAME", Why::Output),
    ignored("TIME_DEPENDENT_FILENAME", Why::Output),
    ignored("MONITOR_*", Why::Output),
    ignored("WRITE_PART_OUT", Why::Output),
    ignored("PART_OUT_*", Why::Output),
    ignored("DES_USR_VAR_SIZE", Why::Output),
    ignored("MAX_PIP", Why::Output),
    ignored("DES_BUFF_RESIZE_FACTOR", Why::Output),
    ignored("REMOVE_ROGUE_PARTICLES", Why::Output),
    ignored("BATCH_WALLCLOCK", Why::Output),
    ignored("TERM_BUFFER", Why::Output),
    ignored("CHK_BATCHQ_END", Why::Output),
    ignored("ENABLE_DMP_LOG", Why::Output),
    ignored("DBGPRN_LAYOUT", Why::Output),
    ignored("BDIST_IO", Why::Output),
    ignored("BSTART_WITH_ONE_RES", Why::Output),
    ignored("DLB_*", Why::Output),
    ignored("WRITE_DASHBOARD", Why::Output),
    ignored("F_DASHBOARD", Why::Output),
];

/// The keyword of this (upper-case) name: an exact entry, else the longest matching prefix
/// entry.
pub fn lookup(name: &str) -> Option<&'static Keyword> {
    KEYWORDS.iter().find(|k| k.name == name).or_else(|| {
        KEYWORDS
            .iter()
            .filter(|k| k.name.ends_with('*') && name.starts_with(&k.name[..k.name.len() - 1]))
            .max_by_key(|k| k.name.len())
    })
}

/// The known keyword closest to an unknown one, for "did you mean".
pub fn closest(name: &str) -> Option<&'static str> {
    crate::error::closest(name, KEYWORDS.iter().filter(|k| !k.name.ends_with('*')).map(|k| k.name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_upper_case_and_prefixes_resolve() {
        let mut seen = std::collections::HashSet::new();
        for k in KEYWORDS {
            assert!(seen.insert(k.name), "{} twice", k.name);
            assert_eq!(k.name, k.name.to_ascii_uppercase());
        }
        assert_eq!(lookup("IS_SERIAL").map(|k| k.name), Some("IS_SERIAL"));
        assert_eq!(lookup("IS_GAMMA").map(|k| k.name), Some("IS_*"));
        assert_eq!(lookup("BC_TYPE").map(|k| k.name), Some("BC_TYPE"));
        assert_eq!(lookup("BC_EP_G").map(|k| k.name), Some("BC_*"));
        assert_eq!(lookup("VTK_DT").map(|k| k.name), Some("VTK_DT"));
        assert_eq!(lookup("VTK_X_W").map(|k| k.name), Some("VTK_*"));
        assert_eq!(lookup("FOO"), None);
        assert_eq!(closest("DES_EN_INPTU"), Some("DES_EN_INPUT"));
    }
}
