//! The mesh walls' outputs, from `grainflow run` as a user runs it: their loads in the time
//! series, the meshes in the VTK series (moving ones frame by frame), their contacts in the
//! force chains, a restart that continues them, and the folder's manifest.
//!
//! One case serves every test: a particle at rest on a fixed floor "floor, main" (z = 0; its
//! name needs sanitising for a column), and below it a plate "plate" turning about a tilted
//! axis, touched by nothing.

use base64::Engine as _;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn grainflow() -> Command {
    Command::new(env!("CARGO_BIN_EXE_grainflow"))
}

/// Half the floor's and the plate's side, m.
const HALF: f64 = 0.05;
/// Particle radius, m (diameter 0.01 m in the case).
const R: f64 = 0.005;
/// Particle mass, kg: 2600 kg/m³ · π d³/6.
const MASS: f64 = 2600.0 * std::f64::consts::PI / 6.0 * 1e-6;
const G: f64 = 9.80665;
/// Where the particle rests on the floor (x, y), m: off the origin, so that the torque about
/// the origin is not zero.
const AT: [f64; 2] = [0.01, 0.02];
/// Time step, s.
const DT: f64 = 2.0e-6;
/// The plate's angular velocity, rad/s, its axis (not normalised) and a point on it, m.
const OMEGA: f64 = 2.0;
const AXIS: [f64; 3] = [1.0, 1.0, 1.0];
const PLATE_Z: f64 = -0.05;

/// A square [−HALF, HALF]² at height z, two triangles wound counter-clockwise seen from above.
fn square_stl(z: f64) -> String {
    let (a, b, c, d) = ([-HALF, -HALF, z], [HALF, -HALF, z], [HALF, HALF, z], [-HALF, HALF, z]);
    let mut s = String::from("solid square\n");
    for t in [[a, b, c], [a, c, d]] {
        s.push_str("  facet normal 0 0 0\n    outer loop\n");
        for v in t {
            s.push_str(&format!("      vertex {:e} {:e} {:e}\n", v[0], v[1], v[2]));
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s + "endsolid square\n"
}

/// The case, run to `t_stop`, with VTK frames every `vtk` s; the meshes' files written beside it.
fn write_case(dir: &Path, t_stop: f64, vtk: f64) -> PathBuf {
    std::fs::write(dir.join("floor.stl"), square_stl(0.0)).expect("write mesh");
    std::fs::write(dir.join("plate.stl"), square_stl(PLATE_Z)).expect("write mesh");
    let text = format!(
        r#"version = 1
[domain]
min = [-0.1, -0.1, -0.1]
max = [0.1, 0.1, 0.1]
walls = false

[physics]
gravity = [0.0, 0.0, -{G}]

[[phases]]
name = "grain"
diameter = 0.01
density = 2600.0

[contact.particle]
kn = 1.0e5

[contact.wall]
kn = 1.0e5
en = 0.9
mu = 0.3

[time]
t_stop = {t_stop}
dt = {DT:e}

[output]
interval = 2.0e-5
snapshots = false
vtk_interval = {vtk}

[[particles.list]]
phase = "grain"
position = [{x}, {y}, {R}]

[[meshes]]
name = "floor, main"
file = "floor.stl"

[[meshes]]
name = "plate"
file = "plate.stl"
[meshes.motion]
kind = "rotate"
axis = [{ax}, {ay}, {az}]
origin = [0.0, 0.0, {PLATE_Z}]
omega = {OMEGA}
"#,
        x = AT[0],
        y = AT[1],
        ax = AXIS[0],
        ay = AXIS[1],
        az = AXIS[2],
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, text).expect("write case");
    path
}

fn run(args: &[&dyn AsRef<std::ffi::OsStr>]) -> Output {
    let mut cmd = grainflow();
    cmd.arg("run");
    for a in args {
        cmd.arg(a);
    }
    let out = cmd.arg("-q").output().expect("runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    out
}

/// The time series: its header and rows.
fn series(out: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let ts = std::fs::read_to_string(out.join("timeseries.csv")).expect("time series");
    let mut lines = ts.lines();
    let header = lines.next().expect("header").split(',').map(str::to_string).collect();
    let rows = lines.map(|l| l.split(',').map(|f| f.parse().expect("number")).collect()).collect();
    (header, rows)
}

/// The values of the data array `name` of a `.vtp` file: base64 of a UInt64 byte count, then
/// the little-endian values (8 bytes each: Float64 and Int64; 4 bytes: Int32, as f64).
fn array(vtp: &str, name: &str) -> Vec<f64> {
    let tag = vtp.find(&format!("Name=\"{name}\"")).unwrap_or_else(|| panic!("no array {name}"));
    let element = &vtp[vtp[..tag].rfind("<DataArray").expect("element start")..];
    let ty = element.split("type=\"").nth(1).and_then(|s| s.split('"').next()).expect("type");
    let text = &element[element.find('>').expect("tag end") + 1..element.find("</DataArray>").expect("end")];
    let bytes = base64::engine::general_purpose::STANDARD.decode(text).expect("base64");
    let count = u64::from_le_bytes(bytes[..8].try_into().expect("8 bytes")) as usize;
    let data = &bytes[8..];
    assert_eq!(count, data.len(), "{name}: the byte count");
    match ty {
        "Float64" => data.chunks(8).map(|c| f64::from_le_bytes(c.try_into().expect("8"))).collect(),
        "Int64" => data.chunks(8).map(|c| i64::from_le_bytes(c.try_into().expect("8")) as f64).collect(),
        "Int32" => data.chunks(4).map(|c| f64::from(i32::from_le_bytes(c.try_into().expect("4")))).collect(),
        other => panic!("{name}: type {other}"),
    }
}

/// `v` turned by `angle` about the unit axis `k` through `o` (Rodrigues' formula).
fn rotate(v: [f64; 3], o: [f64; 3], k: [f64; 3], angle: f64) -> [f64; 3] {
    let r = [v[0] - o[0], v[1] - o[1], v[2] - o[2]];
    let (c, s) = (angle.cos(), angle.sin());
    let kxr = [k[1] * r[2] - k[2] * r[1], k[2] * r[0] - k[0] * r[2], k[0] * r[1] - k[1] * r[0]];
    let kr = k[0] * r[0] + k[1] * r[1] + k[2] * r[2];
    std::array::from_fn(|i| o[i] + r[i] * c + kxr[i] * s + k[i] * kr * (1.0 - c))
}

fn unit_axis() -> [f64; 3] {
    let n = AXIS.iter().map(|a| a * a).sum::<f64>().sqrt();
    AXIS.map(|a| a / n)
}

/// Every file below `dir` (relative path → bytes) but the ones that record when and how the
/// run went (run-info.toml, the manifest, the lock, checkpoints).
fn outputs(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("folder") {
            let path = e.expect("entry").path();
            let rel = path.strip_prefix(dir).expect("below").to_path_buf();
            let name = rel.to_string_lossy();
            if path.is_dir() {
                stack.push(path);
            } else if !["run-info.toml", "manifest.toml", ".grainflow.lock"].contains(&name.as_ref())
                && !name.ends_with(".gfc")
            {
                files.insert(rel, std::fs::read(&path).expect("read"));
            }
        }
    }
    files
}

/// The paths the manifest lists.
fn manifest(dir: &Path) -> Vec<PathBuf> {
    let text = std::fs::read_to_string(dir.join("manifest.toml")).expect("manifest");
    let value: toml::Value = text.parse().expect("the manifest is TOML");
    value["file"]
        .as_array()
        .expect("[[file]] entries")
        .iter()
        .map(|f| PathBuf::from(f["path"].as_str().expect("path")))
        .collect()
}

/// The particle settles on the floor: the floor's force is its weight, −m·g along z, and its
/// torque about the origin (no `torque_about`, no rotation) is r × F with r the contact point.
/// The mesh name's comma and space become `_` in the columns; the plate turns, so it has a
/// `_t_axis` column too. The last force chain runs from the centre to the contact point and
/// names the floor.
#[test]
fn the_time_series_holds_each_meshs_force_and_torque() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = write_case(dir.path(), 0.06, 0.01);
    let out = dir.path().join("out");
    run(&[&case, &"--out", &out]);
    let (header, rows) = series(&out);
    let floor: Vec<String> =
        ["fx", "fy", "fz", "tx", "ty", "tz"].iter().map(|c| format!("mesh_floor__main_{c}")).collect();
    let plate: Vec<String> =
        ["fx", "fy", "fz", "tx", "ty", "tz", "t_axis"].iter().map(|c| format!("mesh_plate_{c}")).collect();
    assert_eq!(header[8..], [floor, plate].concat()[..], "{header:?}");
    let last = rows.last().expect("rows");
    assert_eq!(last.len(), header.len());
    let col = |name: &str| header.iter().position(|h| h == name).expect("column");
    let f =
        [col("mesh_floor__main_fx"), col("mesh_floor__main_fy"), col("mesh_floor__main_fz")].map(|k| last[k]);
    let t =
        [col("mesh_floor__main_tx"), col("mesh_floor__main_ty"), col("mesh_floor__main_tz")].map(|k| last[k]);
    // Released at rest touching the floor, the particle oscillates on the wall spring
    // (ω = √(k/m) = 8571 rad/s) with the damping of e_n = 0.9: ζ = |ln e|/√(π² + ln² e) =
    // 0.0335, so the force's swing (m·g at first) decays as exp(−ζω t) = exp(−287 t): 6e-8 of
    // it is left at t = 0.06 s. Euler's rest point is the exact balance k·δ = m·g, and the
    // load sums round to 2⁻⁴¹ of the peak. 1e-6 of m·g covers the transient tenfold.
    let weight = MASS * G;
    println!("floor force {f:?} N, torque {t:?} N·m, m·g = {weight:e} N");
    assert!((f[2] + weight).abs() < 1e-6 * weight, "fz = {} N, −m·g = {} N", f[2], -weight);
    // The floor is flat and the particle has no tangential velocity: no friction force, to the
    // roundings of the normal (exactly +z) and the sums.
    assert!(f[0].abs() < 1e-12 * weight && f[1].abs() < 1e-12 * weight, "{f:?}");
    // r × F about the origin with r = (x, y, 0), the contact point: the engine sums the
    // particle's centre × force and its couple, so they agree to the roundings, 1e-12.
    let r = [AT[0], AT[1], 0.0];
    let want = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]];
    for k in 0..3 {
        assert!((t[k] - want[k]).abs() <= 1e-12 * weight * HALF, "torque {t:?}, r × F = {want:?}");
    }
    // The plate is touched by nothing: its columns are zero.
    for c in header.iter().filter(|h| h.starts_with("mesh_plate_")) {
        assert_eq!(last[col(c)], 0.0, "{c}");
    }
    // The last force chain: the particle (id 1) to its contact point on mesh 0, triangle 0 or 1.
    let last_step = last[0] as u64;
    assert_eq!(last_step, 30_000, "the last row is the last step's");
    let chains =
        std::fs::read_to_string(out.join(format!("vtk/contacts_{last_step:09}.vtp"))).expect("contacts");
    assert_eq!(array(&chains, "partner_kind"), [2.0]);
    assert_eq!(array(&chains, "partner"), [0.0]);
    assert_eq!(array(&chains, "particle"), [1.0]);
    assert!(array(&chains, "triangle")[0] >= 0.0);
    let points = array(&chains, "Points");
    assert_eq!(points.len(), 6);
    // From the centre (AT, R − δ) to the contact point (AT, 0) below it; δ = m·g/k = 1.3e-7 m.
    assert!((points[0] - AT[0]).abs() < 1e-15 && (points[1] - AT[1]).abs() < 1e-15);
    assert!((points[2] - (R - weight / 1e5)).abs() < 1e-12, "centre z {}", points[2]);
    assert!(
        (points[3] - AT[0]).abs() < 1e-15 && (points[4] - AT[1]).abs() < 1e-15 && points[5].abs() < 1e-15
    );
}

/// `torque_about` moves the point of the torque columns; `_t_axis` stays the torque about the
/// rotation axis (here the floor's surface turning about the x axis through the origin, which
/// at the contact point moves along the normal only: it is removed, and the particle settles
/// as before).
#[test]
fn torque_about_moves_the_torque_and_t_axis_is_about_the_axis() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = write_case(dir.path(), 0.06, 0.06);
    let text = std::fs::read_to_string(&case).expect("case").replace(
        "file = \"floor.stl\"\n",
        "file = \"floor.stl\"\ntorque_about = [0.0, 0.05, 0.0]\n[meshes.surface]\naxis = [1.0, 0.0, 0.0]\nomega = 3.0\n",
    );
    assert!(text.contains("torque_about"), "the case changed: update this test");
    std::fs::write(&case, text).expect("write case");
    let out = dir.path().join("out");
    run(&[&case, &"--out", &out]);
    let (header, rows) = series(&out);
    let last = rows.last().expect("rows");
    let col = |name: &str| last[header.iter().position(|h| h == name).unwrap_or_else(|| panic!("{name}"))];
    let (fz, tx, ty, t_axis) = (
        col("mesh_floor__main_fz"),
        col("mesh_floor__main_tx"),
        col("mesh_floor__main_ty"),
        col("mesh_floor__main_t_axis"),
    );
    println!("fz = {fz:e} N, tx = {tx:e}, ty = {ty:e}, t_axis = {t_axis:e} N·m");
    let weight = MASS * G;
    // As in the test above: the weight, to the decayed transient.
    assert!((fz + weight).abs() < 1e-6 * weight, "fz = {fz}");
    // About a = (0, 0.05, 0): (p − a) × F with p − a = (0.01, −0.03, 0) and F = (0, 0, fz).
    let scale = weight * HALF;
    assert!((tx - (-0.03 * fz)).abs() < 1e-12 * scale, "tx = {tx}, want {}", -0.03 * fz);
    assert!((ty - (-0.01 * fz)).abs() < 1e-12 * scale, "ty = {ty}, want {}", -0.01 * fz);
    // About the x axis through the origin: x̂ · (p × F) = p_y·F_z.
    assert!((t_axis - AT[1] * fz).abs() < 1e-12 * scale, "t_axis = {t_axis}, want {}", AT[1] * fz);
}

/// The VTK series: the fixed floor once in meshes_fixed.vtp, the turning plate in every frame
/// at its pose: frame k's vertices are the loaded ones turned by ω·t_k about the axis, to
/// 1e-12 of the plate's size; its normals likewise; meshes.pvd lists the frames with their
/// times.
#[test]
fn vtk_frames_show_the_moving_mesh_where_it_is() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = write_case(dir.path(), 0.02, 0.002);
    let out = dir.path().join("out");
    run(&[&case, &"--out", &out]);
    let vtk = out.join("vtk");
    let fixed = std::fs::read_to_string(vtk.join("meshes_fixed.vtp")).expect("fixed meshes");
    assert_eq!(array(&fixed, "mesh"), [0.0, 0.0]);
    assert!(array(&fixed, "Points").chunks(3).all(|p| p[2] == 0.0));
    let loaded = grainflow_case::load(&case).expect("case");
    let plate = &loaded.config.meshes[1].mesh;
    let collection = std::fs::read_to_string(vtk.join("meshes.pvd")).expect("meshes.pvd");
    let frames: Vec<(f64, String)> = collection
        .lines()
        .filter_map(|l| {
            let attr = |n: &str| Some(l.split(&format!("{n}=\"")).nth(1)?.split('"').next()?.to_string());
            Some((attr("timestep")?.parse().ok()?, attr("file")?))
        })
        .collect();
    // Frames every 0.002 s = 1000 steps over 10 000 steps, the first and last included.
    assert_eq!(frames.len(), 11, "{collection}");
    let (o, k) = ([0.0, 0.0, PLATE_Z], unit_axis());
    let mut worst: f64 = 0.0;
    for (time, file) in &frames {
        let step: u64 = file.trim_start_matches("meshes_").trim_end_matches(".vtp").parse().expect("step");
        let t = step as f64 * DT;
        // The collection writes 12 significant digits.
        assert!((time - t).abs() <= 1e-11 * t.max(1e-300), "{file}: time {time}, step·Δt = {t}");
        let vtp = std::fs::read_to_string(vtk.join(file)).expect("frame");
        assert_eq!(array(&vtp, "mesh"), [1.0, 1.0], "{file}: only the plate moves");
        let points = array(&vtp, "Points");
        assert_eq!(points.len(), 3 * plate.vertices().len());
        for (p, v) in points.chunks(3).zip(plate.vertices()) {
            let want = rotate(v.to_array(), o, k, OMEGA * t);
            for i in 0..3 {
                worst = worst.max((p[i] - want[i]).abs() / HALF);
            }
        }
        let normals = array(&vtp, "normal");
        for (n, n0) in normals.chunks(3).zip(plate.normals()) {
            let want = rotate(n0.to_array(), [0.0; 3], k, OMEGA * t);
            for i in 0..3 {
                worst = worst.max((n[i] - want[i]).abs());
            }
        }
        let conn = array(&vtp, "connectivity");
        let tris: Vec<f64> = plate.triangles().iter().flatten().map(|&v| f64::from(v)).collect();
        assert_eq!(conn, tris, "{file}");
    }
    // The engine turns by a quaternion, the test by Rodrigues' formula: they differ by a few
    // roundings of values of order 1.
    println!("largest deviation of a vertex or normal from the rotation: {worst:e} (relative)");
    assert!(worst < 1e-12, "a vertex or normal is {worst:e} (relative) from where the rotation puts it");
    // The last frame turned the plate by ω·t_stop = 0.04 rad: it did move.
    let last = std::fs::read_to_string(vtk.join(&frames[10].1)).expect("frame");
    let moved = array(&last, "Points")[..3]
        .iter()
        .zip(plate.vertices()[0].to_array())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(moved > 1e-3, "the plate's first corner moved only {moved} m");
}

/// A run restarted from its checkpoint at an output step rewrites the rows and frames after it
/// as the uninterrupted run wrote them, byte for byte: the mesh columns of the checkpoint's
/// own row (loads of the force evaluation before it, which a checkpoint does not hold) are the
/// ones the run wrote before the checkpoint. Every file is in the manifest, and --overwrite
/// removes the mesh frames of an earlier run.
#[test]
fn a_restart_continues_the_mesh_outputs_and_the_manifest_lists_them() {
    let dir = tempfile::tempdir().expect("temp dir");
    let case = write_case(dir.path(), 0.02, 0.002);
    let full = dir.path().join("full");
    run(&[&case, &"--out", &full]);
    let part = dir.path().join("part");
    // Checkpoints every 3000 steps, the run stopped (as by SIGINT) at step 9000, an output
    // step (every 10 steps) and a VTK frame's (every 1000), whose checkpoint it writes.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let options = grainflow_run::run::RunOptions {
        checkpoint_every: Some(grainflow_run::run::CheckpointEvery::Steps(3000)),
        stop: Some(stop.clone()),
        ..Default::default()
    };
    let stopped =
        grainflow_run::run::run_case(grainflow_case::load(&case).expect("case"), &part, &options, |sim| {
            if sim.step_index() >= 9000 {
                stop.store(true, std::sync::atomic::Ordering::SeqCst);
            }
        })
        .expect("runs");
    assert!(stopped.interrupted && stopped.start_step + stopped.steps == 9000, "{stopped:?}");
    let ckpt = part.join("checkpoint.gfc");
    // Rows after the checkpoint, spoilt, and a stray later frame: the restart rewrites them.
    let ts = std::fs::read_to_string(part.join("timeseries.csv")).expect("time series");
    std::fs::write(part.join("timeseries.csv"), ts.clone() + "9010,0e0\n9500,garbage\n").expect("write");
    let ts = std::fs::read_to_string(part.join("timeseries.csv")).expect("time series");
    let keep: Vec<&str> = ts.lines().take_while(|l| !l.starts_with("9500,")).collect();
    std::fs::write(part.join("timeseries.csv"), keep.join("\n") + "\n9500,garbage\n").expect("write");
    // The stray frame is listed, as the attempt that wrote it would have (a frame the
    // manifest does not list is not the run's, and is left alone).
    std::fs::write(part.join("vtk/meshes_000009500.vtp"), "stray").expect("write");
    let listed = std::fs::read_to_string(part.join("manifest.toml")).expect("manifest");
    std::fs::write(part.join("manifest.toml"), listed + "[[file]]\npath = \"vtk/meshes_000009500.vtp\"\n")
        .expect("write");
    run(&[&case, &"--restart", &ckpt]);
    let (a, b) = (outputs(&full), outputs(&part));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>(), "different files");
    for (name, bytes) in &a {
        assert!(bytes == &b[name], "{} differs from the uninterrupted run's", name.display());
    }
    // The checkpoint's row carries the floor's load (the kept row is not a row of zeros).
    let (header, rows) = series(&part);
    let fz = header.iter().position(|h| h == "mesh_floor__main_fz").expect("column");
    let row = rows.iter().find(|r| r[0] == 9000.0).expect("row of step 9000");
    assert!((row[fz] + MASS * G).abs() < 1e-2 * MASS * G, "fz at the checkpoint {}", row[fz]);
    // The manifest lists every file, the mesh files among them.
    let listed = manifest(&part);
    for f in b.keys() {
        assert!(listed.contains(f), "{} is not in the manifest", f.display());
    }
    for f in
        ["vtk/meshes_fixed.vtp", "vtk/meshes.pvd", "vtk/meshes_000000000.vtp", "vtk/meshes_000010000.vtp"]
    {
        assert!(listed.contains(&PathBuf::from(f)), "{f} is not in the manifest");
    }
    // --overwrite with a case whose meshes do not move: no frame of the turning plate is left.
    let still = dir.path().join("still.toml");
    let text = std::fs::read_to_string(&case).expect("case");
    let cut = text.find("[meshes.motion]").expect("motion table");
    std::fs::write(&still, &text[..cut]).expect("write");
    run(&[&still, &"--out", &part, &"--overwrite"]);
    let left: Vec<_> =
        outputs(&part).into_keys().filter(|f| f.to_string_lossy().contains("meshes_0")).collect();
    assert!(left.is_empty(), "frames of the earlier run left: {left:?}");
    assert!(!part.join("vtk/meshes.pvd").exists());
    let (header, _) = series(&part);
    assert!(!header.contains(&"mesh_plate_t_axis".to_string()), "{header:?}");
}
