//! VTK XML output that ParaView and VTK read natively: particles as points (`.vtp`, with a
//! vertex cell each), contacts as line cells (force chains), walls as polygons clipped to the
//! domain box, and a `.pvd` collection per series with the physical time of every frame.
//!
//! Data arrays use VTK's inline `binary` format: base64 of a UInt64 byte count followed by the
//! little-endian values. Every file is written atomically.

use crate::output::write_atomic;
use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use grainflow::{ContactInfo, ContactPartner, Particles, Vec3, Wall};
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

/// Values of one data array.
pub enum Values<'a> {
    /// 64-bit floats.
    F64(&'a [f64]),
    /// 32-bit signed integers.
    I32(&'a [i32]),
    /// 64-bit signed integers.
    I64(&'a [i64]),
}

/// A named data array with its number of components.
pub struct Array<'a> {
    /// Name shown in ParaView.
    pub name: &'a str,
    /// Components per tuple (1 scalar, 3 vector).
    pub components: usize,
    /// The values, tuple after tuple.
    pub values: Values<'a>,
}

fn encode(bytes: &[u8]) -> String {
    let mut buf = Vec::with_capacity(8 + bytes.len());
    buf.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    buf.extend_from_slice(bytes);
    STANDARD.encode(buf)
}

fn data_array(out: &mut String, a: &Array) {
    let (ty, bytes): (&str, Vec<u8>) = match a.values {
        Values::F64(v) => ("Float64", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        Values::I32(v) => ("Int32", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        Values::I64(v) => ("Int64", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
    };
    let _ = writeln!(
        out,
        r#"<DataArray type="{ty}" Name="{}" NumberOfComponents="{}" format="binary">{}</DataArray>"#,
        a.name,
        a.components,
        encode(&bytes)
    );
}

fn flat(v: &[Vec3]) -> Vec<f64> {
    v.iter().flat_map(|x| x.to_array()).collect()
}

/// A `.vtp` file: points, one kind of cell (`Verts`, `Lines` or `Polys`) given by
/// connectivity and offsets, point data and cell data.
fn polydata(
    points: &[Vec3],
    cell_kind: &str,
    connectivity: &[i64],
    offsets: &[i64],
    point_data: &[Array],
    cell_data: &[Array],
) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<PolyData>\n",
    );
    let counts =
        ["Verts", "Lines", "Strips", "Polys"].map(|k| if k == cell_kind { offsets.len() } else { 0 });
    let _ = writeln!(
        s,
        r#"<Piece NumberOfPoints="{}" NumberOfVerts="{}" NumberOfLines="{}" NumberOfStrips="{}" NumberOfPolys="{}">"#,
        points.len(),
        counts[0],
        counts[1],
        counts[2],
        counts[3]
    );
    s.push_str("<PointData>\n");
    for a in point_data {
        data_array(&mut s, a);
    }
    s.push_str("</PointData>\n<CellData>\n");
    for a in cell_data {
        data_array(&mut s, a);
    }
    s.push_str("</CellData>\n<Points>\n");
    data_array(&mut s, &Array { name: "Points", components: 3, values: Values::F64(&flat(points)) });
    let _ = writeln!(s, "</Points>\n<{cell_kind}>");
    data_array(&mut s, &Array { name: "connectivity", components: 1, values: Values::I64(connectivity) });
    data_array(&mut s, &Array { name: "offsets", components: 1, values: Values::I64(offsets) });
    let _ = writeln!(s, "</{cell_kind}>\n</Piece>\n</PolyData>\n</VTKFile>");
    s
}

/// Particles as points with a vertex cell each. Point data: `id`, `phase` (1-based), `radius`
/// (m), `velocity` (m/s), `angular_velocity` (rad/s), `force` (N, contact forces of the last
/// evaluation), `contacts` (count). In ParaView, a Glyph filter with a sphere scaled by
/// `radius` (scale factor 2: the glyph has diameter 1) shows the spheres.
pub fn particles_vtp(p: &Particles, contacts: &[ContactInfo]) -> String {
    let n = p.len();
    let mut count = vec![0i32; n];
    for c in contacts {
        count[c.particle] += 1;
        if let ContactPartner::Particle(j) = c.other {
            count[j] += 1;
        }
    }
    let ids: Vec<i64> = p.id.iter().map(|&i| i as i64).collect();
    let phase: Vec<i32> = p.phase.iter().map(|&k| k as i32 + 1).collect();
    let cells: Vec<i64> = (0..n as i64).collect();
    let offsets: Vec<i64> = (1..=n as i64).collect();
    polydata(
        &p.position,
        "Verts",
        &cells,
        &offsets,
        &[
            Array { name: "id", components: 1, values: Values::I64(&ids) },
            Array { name: "phase", components: 1, values: Values::I32(&phase) },
            Array { name: "radius", components: 1, values: Values::F64(&p.radius) },
            Array { name: "velocity", components: 3, values: Values::F64(&flat(&p.velocity)) },
            Array { name: "angular_velocity", components: 3, values: Values::F64(&flat(&p.omega)) },
            Array { name: "force", components: 3, values: Values::F64(&flat(&p.force)) },
            Array { name: "contacts", components: 1, values: Values::I32(&count) },
        ],
        &[],
    )
}

/// Contacts as line cells: particle centre to particle centre, or particle centre to the
/// contact point on a wall. Cell data: `normal_force`, `tangential_force` (N), `overlap` (m).
pub fn contacts_vtp(p: &Particles, contacts: &[ContactInfo]) -> String {
    let mut points = Vec::with_capacity(2 * contacts.len());
    for c in contacts {
        points.push(p.position[c.particle]);
        points.push(match c.other {
            ContactPartner::Particle(j) => p.position[j],
            ContactPartner::Wall(_) => c.point,
        });
    }
    let conn: Vec<i64> = (0..points.len() as i64).collect();
    let offsets: Vec<i64> = (1..=contacts.len() as i64).map(|k| 2 * k).collect();
    let fnorm: Vec<f64> = contacts.iter().map(|c| c.normal_force).collect();
    let ftan: Vec<f64> = contacts.iter().map(|c| c.tangential_force).collect();
    let overlap: Vec<f64> = contacts.iter().map(|c| c.overlap).collect();
    polydata(
        &points,
        "Lines",
        &conn,
        &offsets,
        &[],
        &[
            Array { name: "normal_force", components: 1, values: Values::F64(&fnorm) },
            Array { name: "tangential_force", components: 1, values: Values::F64(&ftan) },
            Array { name: "overlap", components: 1, values: Values::F64(&overlap) },
        ],
    )
}

/// The part of an infinite plane inside the box [lo, hi], as a convex polygon (empty if the
/// plane misses the box).
pub fn clip_plane_to_box(wall: &Wall, lo: Vec3, hi: Vec3) -> Vec<Vec3> {
    let corner = |k: usize| {
        Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let scale = (hi - lo).length();
    let eps = 1e-12 * scale;
    let mut pts: Vec<Vec3> = Vec::new();
    let mut add = |x: Vec3| {
        if !pts.iter().any(|q| (*q - x).length() <= 1e-9 * scale) {
            pts.push(x);
        }
    };
    for a in 0..8 {
        for bit in [1, 2, 4] {
            if a & bit != 0 {
                continue;
            }
            let (pa, pb) = (corner(a), corner(a | bit));
            let (da, db) = (wall.distance(pa), wall.distance(pb));
            if da.abs() <= eps {
                add(pa);
            }
            if db.abs() <= eps {
                add(pb);
            }
            if (da < -eps && db > eps) || (da > eps && db < -eps) {
                add(pa + (pb - pa) * (da / (da - db)));
            }
        }
    }
    if pts.len() < 3 {
        return Vec::new();
    }
    let centre = pts.iter().copied().sum::<Vec3>() / pts.len() as f64;
    let u = (pts[0] - centre).normalize();
    let v = wall.normal.cross(u);
    pts.sort_by(|a, b| {
        let (da, db) = (*a - centre, *b - centre);
        da.dot(v).atan2(da.dot(u)).total_cmp(&db.dot(v).atan2(db.dot(u)))
    });
    pts
}

/// Walls as polygons clipped to the box [lo, hi]. Cell data: `wall` (index), `material`.
pub fn walls_vtp(walls: &[Wall], lo: Vec3, hi: Vec3) -> String {
    let mut points = Vec::new();
    let mut offsets = Vec::new();
    let mut index = Vec::new();
    let mut material = Vec::new();
    for (k, w) in walls.iter().enumerate() {
        let poly = clip_plane_to_box(w, lo, hi);
        if poly.is_empty() {
            continue;
        }
        points.extend(poly);
        offsets.push(points.len() as i64);
        index.push(k as i32);
        material.push(w.material as i32);
    }
    let conn: Vec<i64> = (0..points.len() as i64).collect();
    polydata(
        &points,
        "Polys",
        &conn,
        &offsets,
        &[],
        &[
            Array { name: "wall", components: 1, values: Values::I32(&index) },
            Array { name: "material", components: 1, values: Values::I32(&material) },
        ],
    )
}

/// A `.pvd` collection: frames (time in s, file relative to the collection's folder).
pub fn pvd(frames: &[(f64, String)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    for (t, file) in frames {
        let _ = writeln!(s, r#"<DataSet timestep="{t:e}" group="" part="0" file="{file}"/>"#);
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    s
}

/// Writes a VTK series into a folder: `particles_<step>.vtp`, `contacts_<step>.vtp`, one
/// `walls.vtp`, and `particles.pvd`, `contacts.pvd` (rewritten after every frame, so a run
/// stopped early still leaves readable collections).
pub struct VtkSeries {
    dir: PathBuf,
    particles: Vec<(f64, String)>,
    contacts: Vec<(f64, String)>,
}

impl VtkSeries {
    /// Starts a series in `dir` (created if needed) and writes the walls once.
    pub fn create(dir: &Path, walls: &[Wall], lo: Vec3, hi: Vec3) -> io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        write_atomic(&dir.join("walls.vtp"), walls_vtp(walls, lo, hi).as_bytes())?;
        Ok(VtkSeries { dir: dir.to_path_buf(), particles: Vec::new(), contacts: Vec::new() })
    }

    /// Continues a series from an earlier run in `dir`: frames before `step` are kept in the
    /// collections (a restarted run continues where the checkpoint was written).
    pub fn resume(dir: &Path, walls: &[Wall], lo: Vec3, hi: Vec3, step: u64) -> io::Result<Self> {
        let mut series = Self::create(dir, walls, lo, hi)?;
        let keep = |collection: &str| -> Vec<(f64, String)> {
            let Ok(text) = std::fs::read_to_string(dir.join(collection)) else { return Vec::new() };
            text.lines()
                .filter_map(|l| {
                    let attr = |name: &str| {
                        let start = l.find(&format!("{name}=\""))? + name.len() + 2;
                        l[start..].split('"').next()
                    };
                    let file = attr("file")?.to_string();
                    let t: f64 = attr("timestep")?.parse().ok()?;
                    let s: u64 = file.rsplit('_').next()?.trim_end_matches(".vtp").parse().ok()?;
                    (s < step).then_some((t, file))
                })
                .collect()
        };
        series.particles = keep("particles.pvd");
        series.contacts = keep("contacts.pvd");
        Ok(series)
    }

    /// Adds one frame.
    pub fn write(&mut self, step: u64, time: f64, p: &Particles, contacts: &[ContactInfo]) -> io::Result<()> {
        let pf = format!("particles_{step:09}.vtp");
        let cf = format!("contacts_{step:09}.vtp");
        write_atomic(&self.dir.join(&pf), particles_vtp(p, contacts).as_bytes())?;
        write_atomic(&self.dir.join(&cf), contacts_vtp(p, contacts).as_bytes())?;
        self.particles.push((time, pf));
        self.contacts.push((time, cf));
        write_atomic(&self.dir.join("particles.pvd"), pvd(&self.particles).as_bytes())?;
        write_atomic(&self.dir.join("contacts.pvd"), pvd(&self.contacts).as_bytes())
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}
