//! The ranks of a run started by `mpirun`: MPI behind the engine's [`Comm`] (with the `mpi`
//! feature), and the rule that only rank 0 speaks to the terminal.

use grainflow::domain::Comm;
use mpi::datatype::{Partition, PartitionMut};
use mpi::traits::*;
use std::sync::Arc;

/// MPI's world as the engine's communicator.
pub struct MpiComm {
    world: mpi::topology::SimpleCommunicator,
    rank: usize,
    size: usize,
}

impl std::fmt::Debug for MpiComm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MPI rank {} of {}", self.rank, self.size)
    }
}

// SAFETY: MPI was initialised with at least MPI_THREAD_SERIALIZED (checked in `start`), under
// which any thread may call MPI as long as no two do at once; a rank's simulation calls its
// communicator from one thread at a time (the step runs on one thread of its pool).
#[allow(unsafe_code)]
unsafe impl Send for MpiComm {}
// SAFETY: as above; `&MpiComm` is only used by the one thread stepping the simulation.
#[allow(unsafe_code)]
unsafe impl Sync for MpiComm {}

impl Comm for MpiComm {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn exchange(&self, out: Vec<Vec<u64>>) -> Vec<Vec<u64>> {
        let counts: Vec<i32> = out.iter().map(|w| count(w.len())).collect();
        let mut got = vec![0i32; self.size];
        self.world.all_to_all_into(&counts[..], &mut got[..]);
        let send: Vec<u64> = out.concat();
        let displs = offsets(&counts);
        let (recv_displs, total) = (offsets(&got), got.iter().map(|&c| c as usize).sum());
        let mut recv = vec![0u64; total];
        {
            let send = Partition::new(&send[..], &counts[..], &displs[..]);
            let mut into = PartitionMut::new(&mut recv[..], &got[..], &recv_displs[..]);
            self.world.all_to_all_varcount_into(&send, &mut into);
        }
        split(&recv, &got)
    }

    /// MPI's own all-gathers (a count each, then the words): log₂ P steps on most MPI
    /// libraries, where an exchange sends to each rank on its own.
    fn all_gather(&self, mine: &[u64]) -> Vec<Vec<u64>> {
        let mut got = vec![0i32; self.size];
        self.world.all_gather_into(&count(mine.len()), &mut got[..]);
        let (displs, total) = (offsets(&got), got.iter().map(|&c| c as usize).sum());
        let mut recv = vec![0u64; total];
        {
            let mut into = PartitionMut::new(&mut recv[..], &got[..], &displs[..]);
            self.world.all_gather_varcount_into(mine, &mut into);
        }
        split(&recv, &got)
    }
}

/// `words` cut into consecutive parts of `counts` words each.
fn split(words: &[u64], counts: &[i32]) -> Vec<Vec<u64>> {
    let mut at = 0;
    counts
        .iter()
        .map(|&c| {
            let part = words[at..at + c as usize].to_vec();
            at += c as usize;
            part
        })
        .collect()
}

/// A message length as MPI counts it.
fn count(n: usize) -> i32 {
    i32::try_from(n).expect("a message of more than 2^31 words between two ranks")
}

/// Where each part starts in the concatenation of parts of `counts` words.
fn offsets(counts: &[i32]) -> Vec<i32> {
    counts
        .iter()
        .scan(0i32, |at, &c| {
            let start = *at;
            *at += c;
            Some(start)
        })
        .collect()
}

/// MPI, started for this process: the universe (MPI ends when it is dropped) and the world as
/// a communicator. A program started without `mpirun` is one rank.
pub struct Ranks {
    _universe: mpi::environment::Universe,
    pub comm: Arc<dyn Comm>,
}

impl Ranks {
    /// Ends every rank of the run with `code` (MPI_Abort): for a failure that may have struck
    /// this rank alone, while the others wait for it in a collective.
    pub fn abort(&self, code: u8) -> ! {
        self._universe.world().abort(i32::from(code))
    }
}

/// Starts MPI; on ranks other than 0 the terminal output goes to /dev/null, so that a
/// message is printed once.
pub fn start() -> Result<Ranks, String> {
    let (universe, threading) = mpi::initialize_with_threading(mpi::Threading::Serialized)
        .ok_or_else(|| "MPI was already initialised".to_string())?;
    if threading < mpi::Threading::Serialized {
        return Err(format!(
            "the MPI library offers threads only at level {threading:?}; grainflow needs Serialized"
        ));
    }
    let world = universe.world();
    let (rank, size) = (world.rank() as usize, world.size() as usize);
    abort_on_panic(rank);
    if rank > 0 {
        silence();
    }
    Ok(Ranks { _universe: universe, comm: Arc::new(MpiComm { world, rank, size }) })
}

/// Makes a panic (an internal error) on any rank end every rank through MPI_Abort, exit code
/// 101 as a panic's, instead of leaving the others waiting for it in a collective; a rank
/// other than 0 prints its message to the terminal it started with, named by its rank.
fn abort_on_panic(rank: usize) {
    use std::io::Write;
    use std::os::fd::{AsRawFd, FromRawFd};
    // SAFETY: dup of the open standard error gives a descriptor this process owns; the file
    // built from it is leaked into the hook, which lives as long as the process.
    #[allow(unsafe_code)]
    let terminal = unsafe {
        let fd = libc::dup(std::io::stderr().as_raw_fd());
        (fd >= 0).then(|| std::fs::File::from_raw_fd(fd))
    };
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        match (&terminal, rank) {
            (Some(t), r) if r > 0 => {
                let _ = writeln!(&*t, "grainflow rank {r}: internal error: {info}");
            }
            _ => default(info),
        }
        // SAFETY: MPI is initialised (this hook is set after it) and the world communicator
        // outlives every rank's work; MPI_Abort does not return.
        #[allow(unsafe_code)]
        unsafe {
            mpi::ffi::MPI_Abort(mpi::ffi::RSMPI_COMM_WORLD, 101);
        }
    }));
}

/// Points standard output and error at /dev/null.
fn silence() {
    use std::os::fd::AsRawFd;
    if let Ok(null) = std::fs::OpenOptions::new().write(true).open("/dev/null") {
        // SAFETY: dup2 on two valid descriptors; the standard streams are replaced in place.
        #[allow(unsafe_code)]
        unsafe {
            libc::dup2(null.as_raw_fd(), 1);
            libc::dup2(null.as_raw_fd(), 2);
        }
    }
}
