//! VTK XML output that ParaView and VTK read natively: particles as points (`.vtp`, with a
//! vertex cell each), contacts as line cells (force chains), the walls' surfaces as polygons
//! (as their contact sources describe them, [`grainflow::surface`]: no kind of wall is named
//! here), and a `.pvd` collection per series with the physical time of every frame.
//!
//! Data arrays use VTK's inline `binary` format: base64 of a UInt64 byte count followed by the
//! little-endian values. Every file is written atomically.

use crate::output::write_atomic;
use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use grainflow::surface::CellValues;
use grainflow::{ContactInfo, ContactPartner, Particles, Surface, SurfaceKind, Vec3};
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
/// contact point on a wall, mesh or cylinder. Cell data: `normal_force`, `tangential_force`
/// (N), `overlap` (m), `particle` (the id of the particle the line starts at), `partner_kind`
/// (0 another particle, 1 a plane wall, 2 a mesh wall, 3 a cylinder wall), `partner` (that
/// particle's id, or the wall's, mesh's or cylinder's index, 0-based in the case's order) and `triangle` (the mesh
/// triangle that owns the contact, −1 for the others).
pub fn contacts_vtp(p: &Particles, contacts: &[ContactInfo]) -> String {
    let mut points = Vec::with_capacity(2 * contacts.len());
    for c in contacts {
        points.push(p.position[c.particle]);
        points.push(match c.other {
            ContactPartner::Particle(j) => p.position[j],
            ContactPartner::Wall(_) | ContactPartner::Mesh { .. } | ContactPartner::Cylinder(_) => c.point,
        });
    }
    let conn: Vec<i64> = (0..points.len() as i64).collect();
    let offsets: Vec<i64> = (1..=contacts.len() as i64).map(|k| 2 * k).collect();
    let fnorm: Vec<f64> = contacts.iter().map(|c| c.normal_force).collect();
    let ftan: Vec<f64> = contacts.iter().map(|c| c.tangential_force).collect();
    let overlap: Vec<f64> = contacts.iter().map(|c| c.overlap).collect();
    let particle: Vec<i64> = contacts.iter().map(|c| i64::from(p.id[c.particle])).collect();
    let (mut kind, mut partner, mut triangle) = (Vec::new(), Vec::new(), Vec::new());
    for c in contacts {
        let (k, other, t) = match c.other {
            ContactPartner::Particle(j) => (0, i64::from(p.id[j]), -1),
            ContactPartner::Wall(w) => (1, w as i64, -1),
            ContactPartner::Mesh { mesh, triangle } => (2, mesh as i64, triangle as i64),
            ContactPartner::Cylinder(m) => (3, m as i64, -1),
        };
        kind.push(k);
        partner.push(other);
        triangle.push(t);
    }
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
            Array { name: "particle", components: 1, values: Values::I64(&particle) },
            Array { name: "partner_kind", components: 1, values: Values::I32(&kind) },
            Array { name: "partner", components: 1, values: Values::I64(&partner) },
            Array { name: "triangle", components: 1, values: Values::I64(&triangle) },
        ],
    )
}

/// A wall's surface (see [`grainflow::surface`]) as polygons, with its cell data as the
/// source gives it: the plane walls clipped to the domain box (`wall`, `material`), the meshes'
/// triangles (`mesh`, `triangle`, `normal`), the cylinders' tubes (`cylinder`, `material`).
pub fn surface_vtp(surface: &Surface) -> String {
    let conn: Vec<i64> = surface.corners.iter().map(|&k| k as i64).collect();
    let offsets: Vec<i64> = surface.ends.iter().map(|&k| k as i64).collect();
    let vectors: Vec<Vec<f64>> = surface
        .cell_data
        .iter()
        .map(|d| if let CellValues::Vector(v) = &d.values { flat(v) } else { Vec::new() })
        .collect();
    let cell_data: Vec<Array> = surface
        .cell_data
        .iter()
        .zip(&vectors)
        .map(|(d, flat)| match &d.values {
            CellValues::Int(v) => Array { name: d.name, components: 1, values: Values::I32(v) },
            CellValues::Real(v) => Array { name: d.name, components: 1, values: Values::F64(v) },
            CellValues::Vector(_) => Array { name: d.name, components: 3, values: Values::F64(flat) },
        })
        .collect();
    polydata(&surface.points, "Polys", &conn, &offsets, &[], &cell_data)
}

/// Significant digits of a frame time in a `.pvd` file: a time is step·Δt with rounding
/// error in the last digits (0.6 arrives as 0.6000000000000001); 12 digits drop that error
/// and still tell apart frames up to 10¹¹ steps apart in the same run.
const TIME_DIGITS: usize = 12;

/// `t` rounded to [`TIME_DIGITS`] significant digits, written as briefly as that rounded value
/// allows: positional from 1e-3 s up ("0.6", "0.0025", "12.5"), with an exponent below
/// ("2.5e-5"). A value that does not differ in 12 digits is written in full instead (see
/// [`pvd`]).
fn time_text(t: f64) -> String {
    let rounded: f64 = format!("{t:.prec$e}", prec = TIME_DIGITS - 1).parse().unwrap_or(t);
    shortest(rounded)
}

/// The shortest text that reads back as `t` exactly.
fn shortest(t: f64) -> String {
    if t == 0.0 || (1e-3..1e15).contains(&t.abs()) { format!("{t}") } else { format!("{t:e}") }
}

/// A `.pvd` collection: frames (time in s, file relative to the collection's folder). Times
/// are written to 12 significant digits; should two successive frames round to the same text
/// (or out of order), the later one is written in full, so the order of the times never
/// changes.
pub fn pvd(frames: &[(f64, String)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    let mut previous: Option<(f64, f64)> = None; // (exact time, time as written)
    for (t, file) in frames {
        let mut text = time_text(*t);
        let written: f64 = text.parse().unwrap_or(*t);
        if let Some((exact, shown)) = previous
            && *t > exact
            && written <= shown
        {
            text = shortest(*t);
        }
        previous = Some((*t, text.parse().unwrap_or(*t)));
        let _ = writeln!(s, r#"<DataSet timestep="{text}" group="" part="0" file="{file}"/>"#);
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    s
}

/// The files of a VTK series other than its frames, for the walls' `surfaces`: the collections
/// `particles.pvd` and `contacts.pvd`, then each surface's, in their order: `<stem>.vtp` for
/// one that does not move (written once), the collection `<stem>.pvd` for one that does.
pub fn series_files(surfaces: &[Surface]) -> Vec<String> {
    let mut files = vec!["particles.pvd".to_string(), "contacts.pvd".to_string()];
    files.extend(surfaces.iter().map(|s| collection_or_file(s.kind)));
    files
}

/// The file a fixed surface of `kind` is written to, or the collection of a moving one's
/// frames.
pub fn collection_or_file(kind: SurfaceKind) -> String {
    format!("{}.{}", kind.stem, if kind.moves { "pvd" } else { "vtp" })
}

/// The frames of step `step`: `particles_<step>.vtp`, `contacts_<step>.vtp`, then
/// `<stem>_<step>.vtp` for each of the `moving` surfaces.
pub fn frame_files(step: u64, moving: &[Surface]) -> Vec<String> {
    ["particles", "contacts"]
        .into_iter()
        .chain(moving.iter().map(|s| s.kind.stem))
        .map(|stem| format!("{stem}_{step:09}.vtp"))
        .collect()
}

/// Writes a VTK series into a folder: `particles_<step>.vtp`, `contacts_<step>.vtp` and
/// `particles.pvd`, `contacts.pvd` (rewritten after every frame, so a run stopped early still
/// leaves readable collections); each wall surface that does not move once, in `<stem>.vtp`
/// (`walls.vtp`, `meshes_fixed.vtp`, `cylinders.vtp`), and each that moves in
/// `<stem>_<step>.vtp` with `<stem>.pvd` (`meshes`).
pub struct VtkSeries {
    dir: PathBuf,
    /// The files other than the frames ([`series_files`]).
    files: Vec<String>,
    particles: Vec<(f64, String)>,
    contacts: Vec<(f64, String)>,
    /// The frames of each moving surface, by stem.
    moving: Vec<(&'static str, Vec<(f64, String)>)>,
}

impl VtkSeries {
    /// Starts a series in `dir` (created if needed) for the walls' `surfaces`, writing those
    /// that do not move once.
    pub fn create(dir: &Path, surfaces: &[Surface]) -> io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let mut moving = Vec::new();
        for s in surfaces {
            if s.kind.moves {
                moving.push((s.kind.stem, Vec::new()));
            } else {
                write_atomic(&dir.join(collection_or_file(s.kind)), surface_vtp(s).as_bytes())?;
            }
        }
        Ok(VtkSeries {
            dir: dir.to_path_buf(),
            files: series_files(surfaces),
            particles: Vec::new(),
            contacts: Vec::new(),
            moving,
        })
    }

    /// Continues a series from an earlier run in `dir`: frames before `step` are kept in the
    /// collections (a restarted run continues where the checkpoint was written).
    pub fn resume(dir: &Path, surfaces: &[Surface], step: u64) -> io::Result<Self> {
        let mut series = Self::create(dir, surfaces)?;
        let keep = |collection: &str| -> Vec<(f64, String)> {
            // Our own file, at most a line per frame; anything else (not a regular file, or
            // larger than any collection of a million frames) is not continued.
            let path = dir.join(collection);
            let ours = std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_file() && m.len() < 1 << 28);
            let Some(text) = ours.then(|| std::fs::read_to_string(&path).ok()).flatten() else {
                return Vec::new();
            };
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
        for (stem, frames) in &mut series.moving {
            *frames = keep(&format!("{stem}.pvd"));
        }
        Ok(series)
    }

    /// Adds one frame; `moving` are the moving surfaces where they are now
    /// ([`grainflow::surface::Which::Moving`]), each written in its own frame file.
    pub fn write(
        &mut self,
        step: u64,
        time: f64,
        p: &Particles,
        contacts: &[ContactInfo],
        moving: &[Surface],
    ) -> io::Result<()> {
        let names = frame_files(step, moving);
        let (pf, cf) = (names[0].clone(), names[1].clone());
        write_atomic(&self.dir.join(&pf), particles_vtp(p, contacts).as_bytes())?;
        write_atomic(&self.dir.join(&cf), contacts_vtp(p, contacts).as_bytes())?;
        self.particles.push((time, pf));
        self.contacts.push((time, cf));
        for (s, file) in moving.iter().zip(names.into_iter().skip(2)) {
            write_atomic(&self.dir.join(&file), surface_vtp(s).as_bytes())?;
            let k = match self.moving.iter().position(|(stem, _)| *stem == s.kind.stem) {
                Some(k) => k,
                None => {
                    self.moving.push((s.kind.stem, Vec::new()));
                    self.moving.len() - 1
                }
            };
            let frames = &mut self.moving[k].1;
            frames.push((time, file));
            write_atomic(&self.dir.join(collection_or_file(s.kind)), pvd(frames).as_bytes())?;
        }
        write_atomic(&self.dir.join("particles.pvd"), pvd(&self.particles).as_bytes())?;
        write_atomic(&self.dir.join("contacts.pvd"), pvd(&self.contacts).as_bytes())
    }

    /// The files of the series other than its frames ([`series_files`]), relative to its
    /// folder.
    pub fn files(&self) -> &[String] {
        &self.files
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn times(pvd_text: &str) -> Vec<String> {
        pvd_text
            .lines()
            .filter_map(|l| l.split("timestep=\"").nth(1)?.split('"').next().map(str::to_string))
            .collect()
    }

    /// Frame times are step·Δt with rounding error; the collection shows the intended value.
    #[test]
    fn pvd_times_read_cleanly() {
        let dt = 0.1;
        let frames: Vec<(f64, String)> =
            [0u32, 1, 3, 6, 25, 100].iter().map(|&k| (f64::from(k) * dt, format!("p_{k}.vtp"))).collect();
        // In binary floating point 3 · 0.1 is 0.30000000000000004 and 6 · 0.1 is
        // 0.6000000000000001.
        assert_eq!(
            (frames[2].0.to_string(), frames[3].0.to_string()),
            ("0.30000000000000004".into(), "0.6000000000000001".into())
        );
        assert_eq!(times(&pvd(&frames)), ["0", "0.1", "0.3", "0.6", "2.5", "10"]);
        // Short runs (DEM05-like steps of 1.7e-7 s): below 1 ms an exponent.
        let dt = 1.733345e-7;
        assert_eq!(
            times(&pvd(&[(3.0 * dt, "a".into()), (14_423.0 * dt, "b".into())])),
            ["5.200035e-7", "0.0025000034935"]
        );
    }

    /// Two frames 1e-13 s apart at 1 s round to the same 12 digits: the later one is written
    /// in full, so the collection keeps them apart and in order; every time reads back within
    /// 12 digits of its exact value.
    #[test]
    fn pvd_times_keep_their_order() {
        let a = 1.0;
        let b = 1.0 + 1e-13;
        let c = 2.0;
        let t = times(&pvd(&[(a, "a".into()), (b, "b".into()), (c, "c".into())]));
        assert_eq!(t[0], "1");
        assert_eq!(t[1].parse::<f64>().unwrap(), b);
        assert_eq!(t[2], "2");
        let back: Vec<f64> = t.iter().map(|s| s.parse().unwrap()).collect();
        assert!(back[0] < back[1] && back[1] < back[2], "{t:?}");
    }

    /// A restart reads the collection of the earlier run, whether it was written in the old
    /// full exponent form (`6.000000000000001e-1`) or in the new one, keeps the frames before
    /// the restart step and continues the series.
    #[test]
    fn resume_reads_old_and_new_collections() {
        let dir = tempfile::tempdir().unwrap();
        // The format of earlier versions: `{:e}` of the exact f64.
        let old = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n<Collection>\n\
<DataSet timestep=\"0e0\" group=\"\" part=\"0\" file=\"particles_000000000.vtp\"/>\n\
<DataSet timestep=\"6.000000000000001e-1\" group=\"\" part=\"0\" file=\"particles_000000060.vtp\"/>\n\
<DataSet timestep=\"1.2e0\" group=\"\" part=\"0\" file=\"particles_000000120.vtp\"/>\n\
</Collection>\n</VTKFile>\n";
        std::fs::write(dir.path().join("particles.pvd"), old).unwrap();
        // Restart at step 100: the frame of step 120 is dropped (the run writes it again).
        let mut series = VtkSeries::resume(dir.path(), &[], 100).unwrap();
        let p = Particles::default();
        series.write(100, 100.0 * 0.01, &p, &[], &[]).unwrap();
        let text = std::fs::read_to_string(dir.path().join("particles.pvd")).unwrap();
        assert_eq!(times(&text), ["0", "0.6", "1"]);
        assert!(text.contains("particles_000000060.vtp") && !text.contains("particles_000000120.vtp"));
        // And a second restart reads what this one wrote.
        let series = VtkSeries::resume(dir.path(), &[], 200).unwrap();
        assert_eq!(series.particles.iter().map(|f| f.0).collect::<Vec<_>>(), [0.0, 0.6, 1.0]);
    }
}
