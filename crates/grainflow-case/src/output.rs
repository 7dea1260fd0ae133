//! Output writers. Every file is written atomically: into a temporary file beside it, renamed
//! over the target only when complete, so a crash never leaves a half-written file in place of
//! an earlier good one.

use grainflow::{Diagnostics, Particles};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically (temporary file + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Streams what `write` writes to `path` atomically (temporary file + rename): the content
/// never has to be in memory as a whole. On an error the temporary file is removed and any
/// earlier file at `path` is left as it was.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut w = BufWriter::new(File::create(&tmp)?);
        write(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn temp_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(format!(".partial-{}", std::process::id()));
    path.with_file_name(name)
}

/// Header of the time-series CSV.
pub const TIMESERIES_HEADER: &str =
    "step,time,kinetic_translational,kinetic_rotational,potential,elastic,contacts,max_overlap_ratio";

/// The time-series CSV, streamed into a temporary file and renamed into place by
/// [`finish`](Self::finish).
pub struct TimeSeriesWriter {
    path: PathBuf,
    tmp: PathBuf,
    out: BufWriter<File>,
}

impl TimeSeriesWriter {
    /// Starts `path`.
    pub fn create(path: &Path) -> io::Result<Self> {
        let tmp = temp_path(path);
        let mut out = BufWriter::new(File::create(&tmp)?);
        writeln!(out, "{TIMESERIES_HEADER}")?;
        Ok(TimeSeriesWriter { path: path.to_path_buf(), tmp, out })
    }

    /// Appends one row (units: s, J, count, dimensionless).
    pub fn write(&mut self, d: &Diagnostics) -> io::Result<()> {
        writeln!(
            self.out,
            "{},{:e},{:e},{:e},{:e},{:e},{},{:e}",
            d.step,
            d.time,
            d.kinetic_translational,
            d.kinetic_rotational,
            d.potential,
            d.elastic,
            d.contacts,
            d.max_overlap_ratio
        )
    }

    /// Appends rows already formatted (an earlier run's, kept across a restart).
    pub fn write_raw_rows(&mut self, rows: &[String]) -> io::Result<()> {
        for r in rows {
            writeln!(self.out, "{r}")?;
        }
        Ok(())
    }

    /// Completes the file and moves it into place.
    pub fn finish(self) -> io::Result<()> {
        let f = self.out.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&self.tmp, &self.path)
    }
}

/// Header of a particle snapshot CSV (also readable as a CSV particle file).
pub const SNAPSHOT_HEADER: &str = "id,phase,x,y,z,radius,u,v,w,wx,wy,wz";

/// The particle snapshot as CSV text; `phase` is 1-based, as in particle files.
pub fn snapshot_csv(p: &Particles) -> String {
    let mut s = String::with_capacity(64 + p.len() * 200);
    s.push_str(SNAPSHOT_HEADER);
    s.push('\n');
    for i in 0..p.len() {
        let (x, v, w) = (p.position[i], p.velocity[i], p.omega[i]);
        s.push_str(&format!(
            "{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
            p.id[i],
            p.phase[i] + 1,
            x.x,
            x.y,
            x.z,
            p.radius[i],
            v.x,
            v.y,
            v.z,
            w.x,
            w.y,
            w.z
        ));
    }
    s
}
