//! [`Comm`] over MPI (rsmpi on the system's Open MPI; cargo feature `mpi`): one process per
//! rank of `MPI_COMM_WORLD`. Messages are byte strings, each sent as its length and then its
//! bytes. MPI is initialised with `MPI_THREAD_FUNNELED`: rayon's threads evaluate designs, only
//! the main thread calls MPI.

use super::Comm;
use crate::error::{Error, Result};
use mpi::environment::Universe;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use mpi::Threading;

/// Tags of the three kinds of point-to-point message.
const TAG_RING_LENGTH: mpi::Tag = 11;
const TAG_RING_BYTES: mpi::Tag = 12;
const TAG_GATHER: mpi::Tag = 13;

/// The largest message (bytes): MPI counts are 32-bit, and no island message comes near it.
const MAX_MESSAGE: usize = i32::MAX as usize;

/// `MPI_COMM_WORLD` of an initialised MPI environment; dropping it finalises MPI.
pub struct MpiComm {
    world: SimpleCommunicator,
    rank: usize,
    size: usize,
    // Last: finalises MPI after the communicator is gone.
    _universe: Universe,
}

impl MpiComm {
    /// Initialises MPI (under `mpirun`/`srun` every rank joins the job; started alone, the
    /// process is a job of one rank). Fails when MPI was initialised already.
    pub fn init() -> Result<Self> {
        let (universe, _) =
            mpi::initialize_with_threading(Threading::Funneled).ok_or_else(|| Error::Island {
                rank: 0,
                message: "MPI is initialised already".into(),
            })?;
        let world = universe.world();
        let (rank, size) = (world.rank() as usize, world.size() as usize);
        Ok(MpiComm {
            world,
            rank,
            size,
            _universe: universe,
        })
    }

    /// The processor (node) name of this rank.
    pub fn processor_name(&self) -> String {
        mpi::environment::processor_name().unwrap_or_else(|_| "unknown".into())
    }

    fn too_long(&self, n: usize) -> Error {
        Error::Island {
            rank: self.rank,
            message: format!("a message of {n} bytes exceeds the limit of {MAX_MESSAGE}"),
        }
    }
}

impl Comm for MpiComm {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn ring_shift(&self, bytes: &[u8]) -> Result<Vec<u8>> {
        if bytes.len() > MAX_MESSAGE {
            return Err(self.too_long(bytes.len()));
        }
        let next = self
            .world
            .process_at_rank(((self.rank + 1) % self.size) as i32);
        let previous = self
            .world
            .process_at_rank(((self.rank + self.size - 1) % self.size) as i32);
        let length = bytes.len() as u64;
        let (incoming, _): (u64, _) = mpi::point_to_point::send_receive_with_tags(
            &length,
            &next,
            TAG_RING_LENGTH,
            &previous,
            TAG_RING_LENGTH,
        );
        let incoming = usize::try_from(incoming)
            .ok()
            .filter(|&n| n <= MAX_MESSAGE)
            .ok_or_else(|| self.too_long(incoming as usize))?;
        let mut buffer = vec![0u8; incoming];
        mpi::point_to_point::send_receive_into_with_tags(
            bytes,
            &next,
            TAG_RING_BYTES,
            &mut buffer[..],
            &previous,
            TAG_RING_BYTES,
        );
        Ok(buffer)
    }

    fn gather(&self, bytes: &[u8]) -> Result<Option<Vec<Vec<u8>>>> {
        if bytes.len() > MAX_MESSAGE {
            return Err(self.too_long(bytes.len()));
        }
        if self.rank != 0 {
            self.world
                .process_at_rank(0)
                .send_with_tag(bytes, TAG_GATHER);
            return Ok(None);
        }
        let mut all = Vec::with_capacity(self.size);
        all.push(bytes.to_vec());
        for r in 1..self.size {
            let (v, _) = self
                .world
                .process_at_rank(r as i32)
                .receive_vec_with_tag::<u8>(TAG_GATHER);
            all.push(v);
        }
        Ok(Some(all))
    }

    fn broadcast(&self, bytes: &[u8]) -> Result<Vec<u8>> {
        let root = self.world.process_at_rank(0);
        let mut length = bytes.len() as u64;
        root.broadcast_into(&mut length);
        let length = usize::try_from(length)
            .ok()
            .filter(|&n| n <= MAX_MESSAGE)
            .ok_or_else(|| self.too_long(length as usize))?;
        let mut buffer = if self.rank == 0 {
            bytes.to_vec()
        } else {
            vec![0u8; length]
        };
        root.broadcast_into(&mut buffer[..]);
        Ok(buffer)
    }

    fn barrier(&self) {
        self.world.barrier();
    }

    fn abort(&self, code: i32) {
        self.world.abort(code)
    }
}
