//! Files a case names, read once over ranks: rank 0 opens each (particles, meshes, key
//! frames) and passes its bytes to the others a chunk at a time; they never open it. Every
//! rank reads the same case text, so every rank asks for the same files in the same order and
//! takes the same chunks: each chunk is one collective exchange, which the readers make in
//! step. A file rank 0 cannot open or read fails on every rank.
//!
//! ```text
//! message to each other rank: [kind, bytes, words...]  kind: 0 data, 1 end, 2 failure
//! ```

use grainflow::domain::Comm;
use grainflow_case::CaseError;
use grainflow_case::input::OpenHere;
use std::io::{BufRead, Read};
use std::sync::Arc;

/// Bytes passed on in one exchange.
const CHUNK: usize = 1 << 20;

const DATA: u64 = 0;
const END: u64 = 1;
const FAILED: u64 = 2;

/// A [`grainflow_case::input::Relay`] over the ranks of `comm`: rank 0 opens every file, the
/// others take its bytes. With one rank, each file is opened as in one process.
pub fn over_ranks(
    comm: Arc<dyn Comm>,
) -> impl Fn(&str, &OpenHere<'_>) -> Result<Box<dyn BufRead>, CaseError> {
    move |name, open| {
        if comm.size() == 1 {
            return open();
        }
        // First whether rank 0 could open it (and if not, why).
        let (opened, failure) = if comm.rank() == 0 {
            match open() {
                Ok(r) => (Some(r), None),
                Err(e) => (None, Some(e)),
            }
        } else {
            (None, None)
        };
        let said = failure.as_ref().map(|e| e.to_string());
        let got = pass(&*comm, said.map_or((END, Vec::new()), |m| (FAILED, m.into_bytes())));
        if let Some(e) = failure {
            return Err(e);
        }
        if got.0 == FAILED {
            return Err(failed(name, got.1));
        }
        Ok(Box::new(std::io::BufReader::with_capacity(
            CHUNK,
            Passed { comm: comm.clone(), source: opened, name: name.to_string(), ended: false },
        )))
    }
}

/// One exchange: rank 0 sends (`kind`, `bytes`) to every other rank; every rank returns
/// rank 0's (its own on rank 0).
fn pass(comm: &dyn Comm, (kind, bytes): (u64, Vec<u8>)) -> (u64, Vec<u8>) {
    let ranks = comm.size();
    let mut out = vec![Vec::new(); ranks];
    if comm.rank() == 0 {
        let mut words = Vec::with_capacity(2 + bytes.len().div_ceil(8));
        words.extend([kind, bytes.len() as u64]);
        words.extend(words_of(&bytes));
        for o in out.iter_mut().skip(1) {
            o.clone_from(&words);
        }
        comm.exchange(out);
        return (kind, bytes);
    }
    let got = comm.exchange(out).swap_remove(0);
    (got[0], bytes_of(&got[2..], got[1]))
}

/// `bytes` as little-endian words, the last padded with zeros.
pub(crate) fn words_of(bytes: &[u8]) -> impl Iterator<Item = u64> + '_ {
    bytes.chunks(8).map(|c| {
        let mut w = [0u8; 8];
        w[..c.len()].copy_from_slice(c);
        u64::from_le_bytes(w)
    })
}

/// The first `len` bytes of `words` ([`words_of`] undone).
pub(crate) fn bytes_of(words: &[u64], len: u64) -> Vec<u8> {
    let mut b: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    b.truncate(len as usize);
    b
}

fn failed(name: &str, why: Vec<u8>) -> CaseError {
    let why = String::from_utf8_lossy(&why).into_owned();
    CaseError::Read { path: name.into(), source: std::io::Error::other(format!("on rank 0: {why}")) }
}

/// A file as rank 0 reads it (`source` there, none on the others).
struct Passed {
    comm: Arc<dyn Comm>,
    source: Option<Box<dyn BufRead>>,
    name: String,
    ended: bool,
}

impl Read for Passed {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.ended || buf.is_empty() {
            return Ok(0);
        }
        let want = buf.len().min(CHUNK);
        let mine = match &mut self.source {
            Some(r) => {
                let mut chunk = vec![0u8; want];
                match read_some(r, &mut chunk) {
                    Ok(0) => (END, Vec::new()),
                    Ok(n) => {
                        chunk.truncate(n);
                        (DATA, chunk)
                    }
                    Err(e) => (FAILED, e.to_string().into_bytes()),
                }
            }
            None => (END, Vec::new()),
        };
        let (kind, bytes) = pass(&*self.comm, mine);
        match kind {
            DATA => {
                // Rank 0 sends at most what every rank asked for: the same buffer sizes.
                let n = bytes.len().min(buf.len());
                buf[..n].copy_from_slice(&bytes[..n]);
                Ok(n)
            }
            END => {
                self.ended = true;
                Ok(0)
            }
            _ => {
                self.ended = true;
                let why = String::from_utf8_lossy(&bytes).into_owned();
                Err(std::io::Error::other(format!("{}: {why}", self.name)))
            }
        }
    }
}

/// A read that retries when interrupted.
fn read_some(r: &mut dyn BufRead, buf: &mut [u8]) -> std::io::Result<usize> {
    loop {
        match r.read(buf) {
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            other => return other,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainflow::domain::LocalComm;

    /// Every rank of `ranks` reads `files` through the relay (rank 0 from `disk`, the others
    /// only from it), each to the end, as their text or the failure.
    fn read_on_ranks(
        ranks: usize,
        files: &[&str],
        disk: &(dyn Fn(&str) -> Option<Vec<u8>> + Sync),
    ) -> Vec<Vec<Result<Vec<u8>, String>>> {
        std::thread::scope(|s| {
            let handles: Vec<_> = LocalComm::team(ranks)
                .into_iter()
                .map(|comm| {
                    s.spawn(move || {
                        let comm: Arc<dyn Comm> = Arc::new(comm);
                        let rank = comm.rank();
                        let relay = over_ranks(comm);
                        files
                            .iter()
                            .map(|&name| {
                                let open = || -> Result<Box<dyn BufRead>, CaseError> {
                                    assert_eq!(rank, 0, "rank {rank} opened {name}");
                                    let bytes = disk(name).ok_or_else(|| CaseError::Read {
                                        path: name.into(),
                                        source: std::io::Error::from(std::io::ErrorKind::NotFound),
                                    })?;
                                    Ok(Box::new(std::io::Cursor::new(bytes)))
                                };
                                let mut r = relay(name, &open).map_err(|e| e.to_string())?;
                                let mut got = Vec::new();
                                r.read_to_end(&mut got).map_err(|e| e.to_string())?;
                                Ok(got)
                            })
                            .collect()
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().expect("rank")).collect()
        })
    }

    #[test]
    fn every_rank_reads_the_bytes_rank_0_opened_and_its_failures() {
        // Over several chunks, with a length that is not a whole number of words; empty.
        let big: Vec<u8> = (0..(2 * CHUNK + 13)).map(|k| (k * 7 + k / 255) as u8).collect();
        let disk = |name: &str| match name {
            "big.stl" => Some(big.clone()),
            "empty.csv" => Some(Vec::new()),
            _ => None,
        };
        let files = ["big.stl", "missing.csv", "empty.csv"];
        let got = read_on_ranks(3, &files, &disk);
        assert_eq!(got[0][0].as_deref(), Ok(&big[..]));
        assert_eq!(got[0][2].as_deref(), Ok(&[][..]));
        for (r, rank) in got.iter().enumerate() {
            assert_eq!(rank[0].as_deref(), Ok(&big[..]), "rank {r}");
            assert!(rank[1].is_err(), "rank {r} read a file rank 0 could not open");
            assert_eq!(rank[2].as_deref(), Ok(&[][..]), "rank {r}");
        }
        // One rank opens its files itself.
        let one = read_on_ranks(1, &files, &disk);
        assert_eq!(one[0][0].as_deref(), Ok(&big[..]));
    }
}
