//! Output writers. Every file but the time series is written atomically: into a temporary file
//! beside it, renamed over the target only when complete, so a crash never leaves a
//! half-written file in place of an earlier good one. The time series grows row by row in
//! place, so a crash keeps the rows written before it.

use grainflow::{Diagnostics, Particles};
use std::fs::File;
use std::io::{self, BufWriter, Read, Write};
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

/// The time-series CSV, written as the run goes: every row reaches the file as it is written
/// (a crash loses no row written before it), and [`sync`](Self::sync) makes the rows durable
/// (at checkpoints), so a restart from a checkpoint finds every row up to its step.
pub struct TimeSeriesWriter {
    path: PathBuf,
    out: BufWriter<File>,
}

/// The longest row kept from an earlier time series (ours are under 200 bytes): a longer line
/// is not one of ours, and ends what is kept.
const MAX_ROW: usize = 4096;

impl TimeSeriesWriter {
    /// Starts `path` afresh (the header only), replacing any file there.
    pub fn create(path: &Path) -> io::Result<Self> {
        let mut out = BufWriter::new(File::create(path)?);
        writeln!(out, "{TIMESERIES_HEADER}")?;
        out.flush()?;
        Ok(TimeSeriesWriter { path: path.to_path_buf(), out })
    }

    /// Continues the series in `path` at `step`: its rows before `step` are kept (if it is a
    /// time series with this header), those from `step` on are dropped, and the rows written
    /// next follow them. The file is replaced atomically.
    pub fn resume(path: &Path, step: u64) -> io::Result<Self> {
        let kept = earlier_rows(path, step);
        write_atomic_with(path, |w| {
            writeln!(w, "{TIMESERIES_HEADER}")?;
            kept.iter().try_for_each(|r| writeln!(w, "{r}"))
        })?;
        let out = BufWriter::new(std::fs::OpenOptions::new().append(true).open(path)?);
        Ok(TimeSeriesWriter { path: path.to_path_buf(), out })
    }

    /// Appends one row (units: s, J, count, dimensionless) and hands it to the file.
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
        )?;
        self.out.flush()
    }

    /// Makes the rows written so far durable (on the disk, not only in the system's cache).
    pub fn sync(&mut self) -> io::Result<()> {
        self.out.flush()?;
        self.out.get_ref().sync_data()
    }

    /// Completes the file.
    pub fn finish(mut self) -> io::Result<()> {
        self.sync()
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The rows of the time series in `path` before `step`, in order; none if it is not a time
/// series of this format. Read a line at a time, each line at most [`MAX_ROW`] bytes: an
/// outsized file costs no memory. A last row without its line end (cut off by a crash) is
/// dropped.
fn earlier_rows(path: &Path, step: u64) -> Vec<String> {
    use std::io::BufRead;
    let regular = std::fs::symlink_metadata(path).is_ok_and(|m| m.is_file());
    let Some(file) = regular.then(|| File::open(path).ok()).flatten() else { return Vec::new() };
    let mut r = io::BufReader::new(file);
    let mut line = Vec::new();
    let mut next_line = |line: &mut Vec<u8>| -> Option<String> {
        line.clear();
        (&mut r).take(MAX_ROW as u64 + 1).read_until(b'\n', line).ok()?;
        line.pop_if(|c| *c == b'\n')?;
        String::from_utf8(std::mem::take(line)).ok()
    };
    if next_line(&mut line).as_deref() != Some(TIMESERIES_HEADER) {
        return Vec::new();
    }
    let mut rows = Vec::new();
    while let Some(row) = next_line(&mut line) {
        let row_step = row.split(',').next().and_then(|s| s.parse::<u64>().ok());
        if row_step.is_none_or(|s| s >= step) {
            break;
        }
        rows.push(row);
    }
    rows
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
