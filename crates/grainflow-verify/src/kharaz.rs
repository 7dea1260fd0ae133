//! Kharaz, Gorham & Salman (2001) oblique-impact measurements: a 5 mm Al₂O₃ sphere on a thick
//! glass anvil at 3.9 m/s. Three independent digitizations of the paper's figures (MFIX, Lethe,
//! Kratos), shipped in `data/kharaz2001/` (see its README).

/// Which digitization.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// MFIX's DEM05 post-processing (MFIX's `tests/dem/DEM05`).
    Mfix,
    /// Lethe's oblique-wall-impact example.
    Lethe,
    /// Kratos DEM benchmark 4.
    Kratos,
}

impl Source {
    /// Lower-case name.
    pub fn name(&self) -> &'static str {
        match self {
            Source::Mfix => "mfix",
            Source::Lethe => "lethe",
            Source::Kratos => "kratos",
        }
    }
}

/// A measured quantity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Tangential restitution of the centre-of-mass velocity.
    TangentialRestitution,
    /// Spin after impact, rad/s.
    AngularVelocity,
    /// Rebound angle of the centre-of-mass velocity, degrees.
    ReboundAngle,
    /// Rebound angle of the contact point, signed degrees.
    ReboundAngleContactPoint,
}

fn text(q: Quantity, s: Source) -> Option<&'static str> {
    use Quantity::*;
    use Source::*;
    Some(match (q, s) {
        (TangentialRestitution, Mfix) => include_str!("../data/kharaz2001/et_cm__mfix.csv"),
        (TangentialRestitution, Lethe) => include_str!("../data/kharaz2001/et_cm__lethe.csv"),
        (TangentialRestitution, Kratos) => include_str!("../data/kharaz2001/et_cm__kratos.csv"),
        (AngularVelocity, Mfix) => include_str!("../data/kharaz2001/omega__mfix.csv"),
        (AngularVelocity, Lethe) => include_str!("../data/kharaz2001/omega__lethe.csv"),
        (AngularVelocity, Kratos) => include_str!("../data/kharaz2001/omega__kratos.csv"),
        (ReboundAngle, Mfix) => include_str!("../data/kharaz2001/rebound_angle_cm__mfix.csv"),
        (ReboundAngle, Lethe) => include_str!("../data/kharaz2001/rebound_angle_cm__lethe.csv"),
        (ReboundAngleContactPoint, Kratos) => {
            include_str!("../data/kharaz2001/rebound_angle_contact_point__kratos.csv")
        }
        _ => return None,
    })
}

/// The (impact angle in degrees, value) points of one digitization, if it exists.
pub fn points(q: Quantity, s: Source) -> Option<Vec<(f64, f64)>> {
    let t = text(q, s)?;
    Some(
        t.lines()
            .skip(1)
            .filter_map(|l| {
                let mut it = l.split(',').map(|f| f.trim().parse::<f64>());
                match (it.next(), it.next()) {
                    (Some(Ok(a)), Some(Ok(b))) => Some((a, b)),
                    _ => None,
                }
            })
            .collect(),
    )
}
