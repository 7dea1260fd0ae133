//! The VTK series writes every wall's surface by looping over the contact sources: a case with
//! plane walls, a fixed mesh, a moving mesh and cylinders writes exactly the files each kind
//! asks for (`walls.vtp`, `meshes_fixed.vtp`, `cylinders.vtp` once; `meshes_<step>.vtp` in
//! every frame with `meshes.pvd`), and each surface has the polygons its geometry closes on.

use base64::Engine as _;
use grainflow_run::run::{RunOptions, run_case};
use std::collections::BTreeSet;
use std::path::Path;

/// The domain box is [−H, H]³, m.
const H: f64 = 0.1;

/// A triangle list as an ASCII STL.
fn stl(triangles: &[[[f64; 3]; 3]]) -> String {
    let mut s = String::from("solid s\n");
    for t in triangles {
        s.push_str("  facet normal 0 0 0\n    outer loop\n");
        for v in t {
            s.push_str(&format!("      vertex {:e} {:e} {:e}\n", v[0], v[1], v[2]));
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s + "endsolid s\n"
}

/// The square [−a, a]² at height z as `fan` triangles: 2 (one diagonal) or 4 (about its
/// centre). Vertices: 4 or 5.
fn square(a: f64, z: f64, fan: bool) -> Vec<[[f64; 3]; 3]> {
    let (p, q, r, s) = ([-a, -a, z], [a, -a, z], [a, a, z], [-a, a, z]);
    if fan {
        let c = [0.0, 0.0, z];
        vec![[p, q, c], [q, r, c], [r, s, c], [s, p, c]]
    } else {
        vec![[p, q, r], [p, r, s]]
    }
}

/// Writes the case: the box's six faces, a plane through the box's centre with normal
/// (1, 1, 1), a plane beyond the box (z = 2H, facing down), a fixed floor mesh, a turning
/// plate mesh and two cylinders (a drum about z, a rod along x); one particle at rest on
/// nothing in particular. Δt = 5e-6 s to t = 5e-4 s (100 steps), a frame every 2e-4 s.
fn write_case(dir: &Path) -> std::path::PathBuf {
    std::fs::write(dir.join("floor.stl"), stl(&square(0.05, -0.05, false))).unwrap();
    std::fs::write(dir.join("plate.stl"), stl(&square(0.04, -0.08, true))).unwrap();
    let text = format!(
        r#"version = 1
[domain]
min = [-{H}, -{H}, -{H}]
max = [{H}, {H}, {H}]
[physics]
gravity = [0.0, 0.0, 0.0]
[[phases]]
name = "grain"
diameter = 0.01
density = 2600.0
[[wall_materials]]
name = "steel"
[contact.particle]
kn = 1.0e5
[contact.wall]
kn = 1.0e5
[time]
t_stop = 5.0e-4
dt = 5.0e-6
[output]
interval = 2.0e-4
snapshots = false
vtk_interval = 2.0e-4
[[particles.list]]
phase = "grain"
position = [0.05, 0.05, 0.05]
[[walls]]
name = "diagonal"
point = [0.0, 0.0, 0.0]
normal = [1.0, 1.0, 1.0]
[[walls]]
name = "beyond"
point = [0.0, 0.0, {beyond}]
normal = [0.0, 0.0, -1.0]
[[meshes]]
name = "floor"
file = "floor.stl"
[[meshes]]
name = "plate"
file = "plate.stl"
[meshes.motion]
kind = "rotate"
axis = [0.0, 0.0, 1.0]
origin = [0.0, 0.0, 0.0]
omega = 1.0
[[cylinders]]
name = "drum"
origin = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
radius = 0.095
side = "inside"
material = "steel"
[[cylinders]]
name = "rod"
origin = [0.0, -0.06, -0.06]
axis = [1.0, 0.0, 0.0]
radius = 0.01
side = "outside"
material = "steel"
"#,
        beyond = 2.0 * H,
    );
    let path = dir.join("case.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// An attribute of a `.vtp` file's `<Piece>` element, as a count.
fn piece(vtp: &str, name: &str) -> usize {
    let at = vtp.find(&format!("{name}=\"")).unwrap_or_else(|| panic!("no {name}")) + name.len() + 2;
    vtp[at..].split('"').next().unwrap().parse().unwrap()
}

/// The Int32 cell-data array `name` of a `.vtp` file (inline binary: base64 of a u64 byte
/// count and the little-endian values).
fn ints(vtp: &str, name: &str) -> Vec<i32> {
    let tag = format!("Name=\"{name}\"");
    let line = vtp.lines().find(|l| l.contains(&tag)).unwrap_or_else(|| panic!("no array {name}"));
    let data = line.split('>').nth(1).unwrap().split('<').next().unwrap();
    let bytes = base64::engine::general_purpose::STANDARD.decode(data).unwrap();
    bytes[8..].chunks(4).map(|c| i32::from_le_bytes(c.try_into().unwrap())).collect()
}

#[test]
fn every_wall_kind_writes_its_files_and_closes_on_its_polygons() {
    let dir = tempfile::tempdir().unwrap();
    let case = write_case(dir.path());
    let out = dir.path().join("out");
    let options = RunOptions { threads: Some(1), ..RunOptions::default() };
    let summary = run_case(grainflow_case::load(&case).unwrap(), &out, &options, |_| {}).unwrap();
    let vtk = out.join("vtk");

    // Frames at every 2e-4 s / 5e-6 s = 40 steps and at the last step, 100.
    let steps = [0u64, 40, 80, 100];
    let mut want: BTreeSet<String> = ["particles.pvd", "contacts.pvd", "walls.vtp", "meshes_fixed.vtp"]
        .into_iter()
        .chain(["meshes.pvd", "cylinders.vtp"])
        .map(String::from)
        .collect();
    for s in steps {
        for kind in ["particles", "contacts", "meshes"] {
            want.insert(format!("{kind}_{s:09}.vtp"));
        }
    }
    let have: BTreeSet<String> = std::fs::read_dir(&vtk)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(have, want);
    // The manifest lists each of them, and the summary the collections and fixed surfaces.
    let manifest = std::fs::read_to_string(out.join("manifest.toml")).unwrap();
    for f in &want {
        assert!(manifest.contains(&format!("path = \"vtk/{f}\"")), "{f} not in the manifest");
    }
    for f in ["particles.pvd", "contacts.pvd", "walls.vtp", "meshes_fixed.vtp", "meshes.pvd", "cylinders.vtp"]
    {
        assert!(summary.files.contains(&vtk.join(f)), "{f} not in the summary");
    }
    let read = |f: &str| std::fs::read_to_string(vtk.join(f)).unwrap();

    // Plane walls: the six faces (4 corners each), the plane x + y + z = 0 through the box's
    // centre (the regular hexagon through six edge midpoints), and nothing of the plane
    // beyond the box: 7 polygons of 6·4 + 6 = 30 corners, walls 0 to 6 (the box's faces come
    // first, then the `[[walls]]` tables).
    let walls = read("walls.vtp");
    assert_eq!((piece(&walls, "NumberOfPolys"), piece(&walls, "NumberOfPoints")), (7, 30));
    assert_eq!(ints(&walls, "wall"), (0..7).collect::<Vec<i32>>());
    // The fixed floor (2 triangles on 4 vertices) once; the turning plate (4 on 5) in every
    // frame, listed in meshes.pvd at the frames' times.
    let fixed = read("meshes_fixed.vtp");
    assert_eq!((piece(&fixed, "NumberOfPolys"), piece(&fixed, "NumberOfPoints")), (2, 4));
    assert_eq!((ints(&fixed, "mesh"), ints(&fixed, "triangle")), (vec![0, 0], vec![0, 1]));
    for s in steps {
        let frame = read(&format!("meshes_{s:09}.vtp"));
        assert_eq!((piece(&frame, "NumberOfPolys"), piece(&frame, "NumberOfPoints")), (4, 5), "step {s}");
        assert_eq!((ints(&frame, "mesh"), ints(&frame, "triangle")), (vec![1; 4], vec![0, 1, 2, 3]));
    }
    let collection = read("meshes.pvd");
    let files: Vec<&str> =
        collection.lines().filter_map(|l| l.split("file=\"").nth(1)?.split('"').next()).collect();
    assert_eq!(files, steps.map(|s| format!("meshes_{s:09}.vtp")));
    // Two cylinders, 64 quadrilaterals on 128 points each.
    let cylinders = read("cylinders.vtp");
    assert_eq!((piece(&cylinders, "NumberOfPolys"), piece(&cylinders, "NumberOfPoints")), (128, 256));
    let index = ints(&cylinders, "cylinder");
    assert_eq!(
        (index.iter().filter(|&&k| k == 0).count(), index.iter().filter(|&&k| k == 1).count()),
        (64, 64)
    );
}
