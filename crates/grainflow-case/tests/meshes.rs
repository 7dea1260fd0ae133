//! `[[meshes]]` tables: the transform, the material, the case hash over the mesh files, and the
//! table's own checks.

use std::path::Path;

/// A case in `dir` with one particle high above z = 0 and the given `[[meshes]]` (and other)
/// tables; `extra` is appended as written.
fn write_case(dir: &Path, extra: &str) -> std::path::PathBuf {
    let text = format!(
        r#"version = 1
[domain]
min = [-0.1, -0.1, -0.1]
max = [0.1, 0.1, 0.1]
walls = false
[[phases]]
name = "grain"
diameter = 0.01
density = 2600.0
[[wall_materials]]
name = "steel"
[[wall_materials]]
name = "glass"
[contact.particle]
kn = 1.0e4
[contact.wall]
kn = 1.0e4
[time]
t_stop = 0.001
[[particles.list]]
phase = "grain"
position = [0.0, 0.0, 0.05]
{extra}
"#
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, text).expect("write case");
    path
}

/// A 100 mm square in the file's x-y plane, corners at 0 and 100 (millimetres), as one OBJ
/// quad (split into two triangles) wound counter-clockwise seen from +z.
const SQUARE_MM: &str = "# square\nv 0 0 0\nv 100 0 0\nv 100 100 0\nv 0 100 0\nf 1 2 3 4\n";

#[test]
fn the_transform_scales_rotates_and_translates_in_that_order() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("square.obj"), SQUARE_MM).expect("write mesh");
    let case = write_case(
        dir.path(),
        "[[meshes]]\nname = \"plate\"\nfile = \"square.obj\"\nmaterial = \"glass\"\nscale = 1e-3\n\
         rotate = [0.0, 0.0, 90.0]\ntranslate = [0.05, -0.05, -0.02]\nflip_normals = true\n",
    );
    let c = grainflow_case::load(&case).expect("valid case");
    assert_eq!(c.config.meshes.len(), 1);
    let m = &c.config.meshes[0];
    // "glass" is the second wall material.
    assert_eq!(m.material, 1);
    // Scaled to [0, 0.1]² m, turned a quarter about z ((x, y) → (−y, x)) to x ∈ [−0.1, 0],
    // y ∈ [0, 0.1], then moved by (0.05, −0.05, −0.02): [−0.05, 0.05]² at z = −0.02. A quarter
    // turn is exact; 1e-3 · 100 rounds, hence 1e-15 m.
    let (lo, hi) = m.mesh.bounds();
    for (got, want) in lo.to_array().into_iter().zip([-0.05, -0.05, -0.02]) {
        assert!((got - want).abs() < 1e-15, "lower corner {lo:?}");
    }
    for (got, want) in hi.to_array().into_iter().zip([0.05, 0.05, -0.02]) {
        assert!((got - want).abs() < 1e-15, "upper corner {hi:?}");
    }
    // Two triangles of the quad, wound from +z in the file: flipped, their normals point −z.
    assert_eq!(m.mesh.triangle_count(), 2);
    for n in m.mesh.normals() {
        assert!((n.z + 1.0).abs() < 1e-15, "normal {n:?}");
    }
}

#[test]
fn the_material_defaults_to_the_first_wall_material() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("square.obj"), SQUARE_MM).expect("write mesh");
    let case = write_case(dir.path(), "[[meshes]]\nname = \"plate\"\nfile = \"square.obj\"\nscale = 1e-3\n");
    let c = grainflow_case::load(&case).expect("valid case");
    assert_eq!(c.config.meshes[0].material, 0);
    // Both wall materials are kept for the mesh (no plane walls: without the mesh they would
    // be dropped, as they are for a case with no walls at all).
    assert_eq!(c.config.wall_materials.len(), 2);
    // Unflipped, the normals follow the file's winding: +z.
    assert!(c.config.meshes[0].mesh.normals().iter().all(|n| n.z == 1.0));
}

#[test]
fn the_case_hash_follows_the_mesh_files_contents() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mesh = dir.path().join("square.obj");
    std::fs::write(&mesh, SQUARE_MM).expect("write mesh");
    let case = write_case(dir.path(), "[[meshes]]\nname = \"plate\"\nfile = \"square.obj\"\nscale = 1e-3\n");
    let h1 = grainflow_case::load(&case).expect("valid").hash;
    // The same inputs, the same hash.
    assert_eq!(grainflow_case::load(&case).expect("valid").hash, h1);
    // The same case text with a different square (99 mm): another hash.
    std::fs::write(&mesh, SQUARE_MM.replace("100", "99")).expect("write mesh");
    let h2 = grainflow_case::load(&case).expect("valid").hash;
    assert_ne!(h1, h2, "the hash must change with the mesh file");
    // A comment only changes the bytes, not the mesh: still another hash (the hash is of the
    // inputs, not of their meaning).
    std::fs::write(&mesh, format!("# edited\n{SQUARE_MM}")).expect("write mesh");
    let h3 = grainflow_case::load(&case).expect("valid").hash;
    assert!(h3 != h1 && h3 != h2);
}

fn refused(extra: &str, files: &[(&str, &str)], expect: &[&str]) {
    let dir = tempfile::tempdir().expect("temp dir");
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).expect("write");
    }
    let case = write_case(dir.path(), extra);
    let e = grainflow_case::load(&case).expect_err("must be refused").to_string();
    for x in expect {
        assert!(e.contains(x), "expected `{x}` in: {e}");
    }
}

#[test]
fn the_table_checks_its_keys() {
    let sq = [("square.obj", SQUARE_MM)];
    refused("[[meshes]]\nfile = \"square.obj\"\n", &sq, &["[[meshes]] #1", "missing required key `name`"]);
    refused("[[meshes]]\nname = \"a\"\n", &sq, &["[[meshes]] 'a'", "missing required key `file`"]);
    refused(
        "[[meshes]]\nname = \"a\"\nfile = \"square.obj\"\nscale = 1e-3\n\
         [[meshes]]\nname = \"a\"\nfile = \"square.obj\"\nscale = 1e-3\n",
        &sq,
        &["[[meshes]] 'a'", "mesh names must be unique"],
    );
    refused(
        "[[meshes]]\nname = \"a\"\nfile = \"square.ply\"\n",
        &[("square.ply", "ply\n")],
        &["[[meshes]] 'a': `file`: square.ply: unknown mesh format"],
    );
    refused(
        "[[meshes]]\nname = \"a\"\nfile = \"square.obj\"\nrotate = [0.0, nan, 0.0]\n",
        &sq,
        &["[[meshes]] 'a'", "`rotate`", "finite"],
    );
    // A file that parses but is not a valid mesh: the library's message, with its line.
    refused(
        "[[meshes]]\nname = \"a\"\nfile = \"bad.obj\"\n",
        &[("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n")],
        &["[[meshes]] 'a': `file`: bad.obj", "vertex index 3 is out of range"],
    );
}

#[test]
fn elastic_models_need_the_mesh_materials_moduli() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("square.obj"), SQUARE_MM).expect("write mesh");
    let text = std::fs::read_to_string(write_case(dir.path(), "")).expect("read");
    // The Hertz model with phase moduli, no wall moduli, no plane walls, one mesh: the mesh's
    // contacts need the wall material's E and ν.
    let text = text
        .replace("density = 2600.0", "density = 2600.0\nyoungs_modulus = 1e8\npoisson_ratio = 0.3")
        .replace(
            "[contact.particle]\nkn = 1.0e4",
            "[contact]\nmodel = \"hertz\"\n[contact.particle]\net = 0.9",
        )
        .replace("[contact.wall]\nkn = 1.0e4", "[contact.wall]\net = 0.9");
    let case = dir.path().join("hertz.toml");
    std::fs::write(&case, format!("{text}[[meshes]]\nname = \"a\"\nfile = \"square.obj\"\nscale = 1e-3\n"))
        .expect("write");
    let e = grainflow_case::load(&case).expect_err("no wall moduli").to_string();
    assert!(e.contains("[[wall_materials]] 'steel'") && e.contains("youngs_modulus"), "{e}");
    // Without the mesh the same case runs: no walls, so no wall moduli are needed.
    std::fs::write(&case, &text).expect("write");
    grainflow_case::load(&case).expect("no walls, no wall moduli needed");
}

/// `[meshes.motion]` and `[meshes.surface]` become the engine's motions: rpm in rad/s
/// (60 rpm = 2π rad/s, to rounding), the axis normalised, the origin as given.
#[test]
fn motion_and_surface_tables_become_the_engines() {
    use grainflow::Vec3;
    use grainflow::mesh::{MeshMotion, SurfaceMotion};
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("square.obj"), SQUARE_MM).expect("write mesh");
    let case = write_case(
        dir.path(),
        "[[meshes]]\nname = \"drum\"\nfile = \"square.obj\"\nscale = 1e-3\n\
         [meshes.motion]\nkind = \"rotate\"\naxis = [0.0, 2.0, 0.0]\norigin = [0.0, 0.0, 0.01]\nrpm = 60.0\nramp = 0.5\n\
         [[meshes]]\nname = \"belt\"\nfile = \"square.obj\"\nscale = 1e-3\ntranslate = [0.0, 0.0, -0.05]\n\
         [meshes.surface]\nvelocity = [0.2, 0.0, 0.0]\n\
         [[meshes]]\nname = \"shaker\"\nfile = \"square.obj\"\nscale = 1e-3\ntranslate = [0.0, 0.0, -0.08]\n\
         [meshes.motion]\nkind = \"oscillate\"\namplitude = [0.0, 0.0, 0.002]\nfrequency = 10.0\n",
    );
    let c = grainflow_case::load(&case).expect("valid case");
    let m = &c.config.meshes;
    match m[0].motion {
        MeshMotion::Rotate { origin, axis, omega, ramp } => {
            assert_eq!((origin, axis, ramp), (Vec3::new(0.0, 0.0, 0.01), Vec3::Y, 0.5));
            assert!((omega - std::f64::consts::TAU).abs() < 1e-15);
        }
        other => panic!("not a rotation: {other:?}"),
    }
    assert_eq!(m[1].surface, SurfaceMotion::Translate { velocity: Vec3::new(0.2, 0.0, 0.0) });
    assert_eq!(m[1].motion, MeshMotion::Fixed);
    assert_eq!(m[2].motion, MeshMotion::Oscillate { amplitude: Vec3::new(0.0, 0.0, 0.002), frequency: 10.0 });
    assert_eq!(c.mesh_names, ["drum", "belt", "shaker"]);
}

#[test]
fn motion_tables_check_their_keys() {
    let sq = [("square.obj", SQUARE_MM)];
    let mesh = "[[meshes]]\nname = \"a\"\nfile = \"square.obj\"\nscale = 1e-3\n";
    let with = |t: &str| format!("{mesh}{t}");
    refused(&with("[meshes.motion]\nvelocity = [1.0, 0.0, 0.0]\n"), &sq, &["'a' [motion]", "`kind`"]);
    refused(
        &with("[meshes.motion]\nkind = \"spin\"\n"),
        &sq,
        &["`kind`", "\"translate\", \"rotate\", \"oscillate\""],
    );
    refused(
        &with("[meshes.motion]\nkind = \"translate\"\nvelocity = [1.0, 0.0, 0.0]\nrpm = 3.0\n"),
        &sq,
        &["`rpm`", "is not a key of kind \"translate\""],
    );
    refused(
        &with("[meshes.motion]\nkind = \"rotate\"\naxis = [0.0, 0.0, 0.0]\nrpm = 3.0\n"),
        &sq,
        &["`axis`", "non-zero"],
    );
    refused(
        &with("[meshes.motion]\nkind = \"rotate\"\naxis = [0.0, 0.0, 1.0]\nrpm = 3.0\nomega = 1.0\n"),
        &sq,
        &["not both"],
    );
    refused(&with("[meshes.motion]\nkind = \"rotate\"\naxis = [0.0, 0.0, 1.0]\n"), &sq, &["`omega`"]);
    refused(
        &with("[meshes.motion]\nkind = \"rotate\"\naxis = [0.0, 0.0, 1.0]\nomega = 1.0\nramp = -1.0\n"),
        &sq,
        &["`ramp`"],
    );
    refused(
        &with("[meshes.motion]\nkind = \"oscillate\"\namplitude = [0.0, 0.0, 1e-3]\nfrequency = 0.0\n"),
        &sq,
        &["`frequency`", "positive"],
    );
    refused(
        &with("[meshes.surface]\nvelocity = [1.0, 0.0, 0.0]\nrpm = 2.0\n"),
        &sq,
        &["[surface]", "not both"],
    );
    refused(&with("[meshes.surface]\n"), &sq, &["[surface]", "`velocity`"]);
    refused(
        &with("[meshes.motion]\nkind = \"rotate\"\naxis = [0.0, 0.0, 1.0]\nomega = 1.0\nspeed = 2.0\n"),
        &sq,
        &["speed"],
    );
    refused(
        &with("[meshes.motion]\nkind = \"translate\"\nvelocity = [1.0, 0.0, 0.0]\nstart = -0.1\n"),
        &sq,
        &["`start`", "t_start = 0"],
    );
    refused(
        &with("[meshes.motion]\nkind = \"translate\"\nvelocity = [1.0, 0.0, 0.0]\nstart = 0.2\nstop = 0.2\n"),
        &sq,
        &["`stop`", "after the motion's start 0.2"],
    );
}

/// `start` and `stop` of any kind of motion become the engine's window; without them the
/// motion acts over the whole run.
#[test]
fn a_motions_start_and_stop_become_its_window() {
    use grainflow::mesh::MotionWindow;
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("square.obj"), SQUARE_MM).expect("write mesh");
    let case = write_case(
        dir.path(),
        "[[meshes]]\nname = \"gate\"\nfile = \"square.obj\"\nscale = 1e-3\n\
         [meshes.motion]\nkind = \"translate\"\nvelocity = [0.5, 0.0, 0.0]\nstart = 0.0004\nstop = 0.0009\n\
         [[meshes]]\nname = \"drum\"\nfile = \"square.obj\"\nscale = 1e-3\ntranslate = [0.0, 0.0, -0.05]\n\
         [meshes.motion]\nkind = \"rotate\"\naxis = [0.0, 0.0, 1.0]\nomega = 1.0\n",
    );
    let c = grainflow_case::load(&case).expect("valid case");
    let m = &c.config.meshes;
    assert_eq!(m[0].window, MotionWindow { start: 0.0004, stop: 0.0009 });
    assert_eq!(m[1].window, MotionWindow::ALWAYS);
}

/// docs/case-file.md: a byte-order mark before an ASCII STL is skipped (it was refused as "not
/// an STL file").
#[test]
fn an_ascii_stl_with_a_byte_order_mark_is_read() {
    let dir = tempfile::tempdir().expect("temp dir");
    let stl = "solid s\nfacet normal 0 0 1\nouter loop\nvertex -0.05 -0.05 0\nvertex 0.05 -0.05 0\n\
               vertex 0.05 0.05 0\nendloop\nendfacet\nendsolid s\n";
    std::fs::write(dir.path().join("plain.stl"), stl).expect("write mesh");
    std::fs::write(dir.path().join("marked.stl"), format!("\u{feff}{stl}")).expect("write mesh");
    let load = |file: &str| {
        let case = write_case(dir.path(), &format!("[[meshes]]\nname = \"plate\"\nfile = \"{file}\"\n"));
        grainflow_case::load(&case).map(|c| c.config.meshes[0].mesh.clone())
    };
    let plain = load("plain.stl").expect("valid");
    let marked = load("marked.stl").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(marked.vertices(), plain.vertices());
    assert_eq!(marked.triangles(), plain.triangles());
}

/// A mesh whose fastest point moves more than a tenth of the smallest radius a step is refused
/// (issue 38); with `[time] force_dt = true` the case loads with the same text as a warning.
/// Here the particles' diameter is 0.01 m and MFIX's rule gives dt = TCOLL/50.
#[test]
fn a_mesh_too_fast_for_the_step_is_refused_unless_forced() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("square.obj"), SQUARE_MM).expect("write mesh");
    let mesh = "[[meshes]]\nname = \"plate\"\nfile = \"square.obj\"\nscale = 1e-3\ntranslate = [-0.05, -0.05, -0.05]\n\
                [meshes.motion]\nkind = \"translate\"\nvelocity = [0.0, 0.0, 500.0]\n";
    let e = grainflow_case::load(&write_case(dir.path(), mesh)).expect_err("refused").to_string();
    // TCOLL = π/√(k/m_eff − …) with m_eff = m/2; dt = TCOLL/50; the travel is 500·dt.
    let c = grainflow_case::load(&write_case(dir.path(), "")).expect("valid without the mesh");
    let dt = grainflow::timestep::choose(
        c.config.time_step,
        &c.config.law,
        &c.config.phases,
        &grainflow::contact::CoeffTable::build(
            &c.config.law,
            &c.config.phases,
            &c.config.wall_materials,
            &c.config.pair_params,
            &c.config.wall_params,
        )
        .unwrap(),
        0.001,
        &(1.0, String::new()),
    )
    .unwrap()
    .dt;
    for part in [
        "[[meshes]] 'plate': motion: mesh 'plate' is translating at 5.0000e2 m/s".to_string(),
        format!("{:.4e} m in a step of dt = {dt:.4e} s", 500.0 * dt),
        format!("{:.3} of the smallest particle radius 5.0000e-3 m", 500.0 * dt / 0.005),
        format!("a safe time step is dt <= {:.4e} s", 0.1 * 0.005 / 500.0),
    ] {
        assert!(e.contains(&part), "'{part}' not in: {e}");
    }
    let forced = write_case(dir.path(), mesh);
    let text = std::fs::read_to_string(&forced)
        .unwrap()
        .replace("t_stop = 0.001", "t_stop = 0.001\nforce_dt = true");
    std::fs::write(&forced, text).unwrap();
    let c = grainflow_case::load(&forced).expect("forced");
    assert!(
        c.warnings.iter().any(|w| w.contains("mesh 'plate' is translating") && w.contains("running anyway")),
        "{:?}",
        c.warnings
    );
}

/// Meshes have no periodic images (issue 38): one that comes within the largest radius of a
/// periodic face, where it is or where its motion takes it, is refused, naming it and the axis.
/// The plate is 0.14 m square about the z axis: its sides at x = ±0.07 m are 0.025 m clear of
/// the faces x = ±0.1 m, but turning about z its corners, 0.07·√2 = 0.099 m from the axis,
/// sweep to within 0.001 m of them, less than the radius 0.005 m.
#[test]
fn a_mesh_reaching_a_periodic_face_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("square.obj"), SQUARE_MM).expect("write mesh");
    let plate = "[[meshes]]\nname = \"plate\"\nfile = \"square.obj\"\nscale = 1.4e-3\ntranslate = [-0.07, -0.07, 0.0]\n";
    let periodic = |text: String| text.replace("walls = false", "walls = false\nperiodic = [\"x\"]");
    let case = |extra: &str| {
        let path = write_case(dir.path(), extra);
        std::fs::write(&path, periodic(std::fs::read_to_string(&path).unwrap())).unwrap();
        grainflow_case::load(&path)
    };
    case(plate).expect("a fixed plate clear of the faces");
    let turning = format!("{plate}[meshes.motion]\nkind = \"rotate\"\naxis = [0.0, 0.0, 1.0]\nomega = 1.0\n");
    let e = case(&turning).expect_err("its corners sweep to the faces").to_string();
    for part in [
        "[[meshes]] 'plate': mesh 'plate' reaches across or within 5e-3 m",
        "of the periodic faces x = -1e-1 and x = 1e-1 m",
        "meshes have no periodic images",
    ] {
        assert!(e.contains(part), "'{part}' not in: {e}");
    }
    // Its swept extent: the corners' circle, radius 0.07·√2 (to rounding: 1e-12 m).
    let from: f64 =
        e.split("spans x from ").nth(1).and_then(|t| t.split(' ').next()).unwrap().parse().unwrap();
    assert!((from + 0.07 * std::f64::consts::SQRT_2).abs() < 1e-12, "{from}");
    // A plate across the whole period (a floor) is refused as it stands.
    let floor =
        "[[meshes]]\nname = \"floor\"\nfile = \"square.obj\"\nscale = 2e-3\ntranslate = [-0.1, -0.1, 0.0]\n";
    let e = case(floor).expect_err("a floor to the faces").to_string();
    assert!(e.contains("mesh 'floor' reaches across") && e.contains("[[walls]] plane"), "{e}");
}
