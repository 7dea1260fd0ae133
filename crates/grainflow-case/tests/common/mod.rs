//! What the case-layer tests share.

/// A valid case with one inline particle; each test edits one thing of it.
pub const BASE: &str = r#"
version = 1
[domain]
min = [0.0, 0.0, 0.0]
max = [0.1, 0.1, 0.1]
[[phases]]
name = "glass"
diameter = 0.004
density = 2500.0
youngs_modulus = 6.0e10
poisson_ratio = 0.25
[[wall_materials]]
name = "steel"
youngs_modulus = 2.0e11
poisson_ratio = 0.3
[contact]
model = "lsd"
[contact.particle]
kn = 1000.0
en = 0.9
mu = 0.3
[contact.wall]
kn = 1000.0
en = 0.9
mu = 0.3
[time]
t_stop = 0.01
[[particles.list]]
phase = "glass"
position = [0.05, 0.05, 0.05]
"#;
