//! `kinsynth optimize --islands [N]`: an island job, one island per MPI rank (built with the
//! cargo feature `mpi`, started by `mpirun` or `srun`), or `N` islands in this one process.
//! Rank 0 reads the command line, the scenario and the checkpoint, holds the output lock and
//! hands the job to the other ranks; all of them then run it, and rank 0 writes the results.

use super::optimize::{prepare, Args, Prepared};
use super::progress;
use kinsynth::optimize::islands::{
    agree, share_job, Comm, IslandJob, IslandOutcome, JobError, JobSpec,
};
use kinsynth::optimize::runner::{fingerprint, Quiet, Runner};
use kinsynth::Scenario;

/// True when this process was started by an MPI launcher (Open MPI, or a PMI/PMIx one such as
/// `srun`).
#[cfg(not(feature = "mpi"))]
fn under_mpi_launcher() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
}

/// Runs `optimize` with `--islands`; `islands` is its value (`None`: one island per rank).
pub fn run(args: Args, islands: Option<usize>) -> Result<(), kinsynth::Error> {
    #[cfg(feature = "mpi")]
    let comm = kinsynth::optimize::islands::mpi::MpiComm::init()?;
    #[cfg(not(feature = "mpi"))]
    let comm = {
        if under_mpi_launcher() {
            return Err(kinsynth::Error::invalid(
                "--islands",
                "mpirun",
                "this kinsynth was built without MPI, so every rank would run the whole job alone: build it with `cargo build --release --features mpi`",
            ));
        }
        kinsynth::optimize::islands::SingleProcess
    };
    match job(&args, islands, &comm) {
        Ok(()) => Ok(()),
        // Every rank knows: rank 0 reports it, the others just end.
        Err(JobError {
            error,
            on_every_rank: true,
        }) => {
            if comm.size() == 1 {
                return Err(error);
            }
            // Rank 0 reports it before any rank ends: the launcher kills the job as soon as
            // one rank exits with a failure, which could be before rank 0 has printed it.
            if comm.rank() == 0 {
                eprintln!("error: {}", kinsynth::error::shorten(&error.to_string()));
            }
            comm.barrier();
            // Finalise MPI before this process ends.
            #[cfg(feature = "mpi")]
            drop(comm);
            std::process::exit(1)
        }
        // This rank failed alone while the others may wait for it: end the whole job.
        Err(JobError { error, .. }) => {
            if comm.size() > 1 {
                let error_text = error.to_string();
                eprintln!(
                    "error: rank {}: {}",
                    comm.rank(),
                    kinsynth::error::shorten(&error_text)
                );
                comm.abort(1);
            }
            Err(error)
        }
    }
}

fn job(args: &Args, islands: Option<usize>, comm: &dyn Comm) -> Result<(), JobError> {
    let root = comm.rank() == 0;
    let islands = islands.unwrap_or(comm.size());
    let mut held = None;
    let spec = if root {
        let prepared = prepare(args).and_then(|p| {
            let Prepared {
                scenario,
                scenario_path,
                planner,
                options,
                checkpoint,
                out,
                lock,
            } = p;
            held = Some(lock);
            let migration = checkpoint
                .as_ref()
                .and_then(|c| c.islands.as_ref().map(|i| i.migration))
                .unwrap_or(scenario.optimizer.migration);
            Ok(JobSpec {
                scenario_hash: hash_of(&scenario_path)?,
                scenario: std::fs::canonicalize(&scenario_path).unwrap_or(scenario_path),
                planner,
                options,
                out,
                islands,
                migration,
                checkpoint,
            })
        });
        match prepared {
            Ok(spec) => Some(Ok(spec)),
            Err(e) => {
                // Tell the other ranks, then report it.
                share_job(comm, Some(Err(e.to_string())))?;
                return Err(JobError {
                    error: e,
                    on_every_rank: true,
                });
            }
        }
    } else {
        None
    };
    let spec = share_job(comm, spec)?;
    let scenario = agree(comm, Scenario::load(&spec.scenario))?;
    let runner = Runner::new(
        &scenario,
        &spec.scenario,
        spec.planner.clone(),
        spec.options.clone(),
        &spec.out,
    );
    let job = IslandJob::new(&runner, spec.islands, spec.migration)
        .expect_scenario_hash(spec.scenario_hash.clone());
    let stop = super::optimize::stop_on_ctrl_c();
    let outcome = if root {
        let mut bar = progress::Bar::new(&spec.options, args.quiet);
        job.run(comm, spec.checkpoint, &stop, &mut bar)?
    } else {
        job.run(comm, spec.checkpoint, &stop, &mut Quiet)?
    };
    if let Some(IslandOutcome { summary, timings }) = outcome {
        super::optimize::report(&spec.out, &summary);
        let g = timings.generations.max(1) as f64;
        let m = timings.migrations.max(1) as f64;
        say!(
            "{} {}, migration every {} generations ({} designs); best before the re-check from island {}; per generation {:.2} ms of status exchange, per migration {:.2} ms (after {:.2} ms waiting for the slowest island)",
            count(spec.islands, "island"),
            if comm.size() == 1 {
                "in one process".to_string()
            } else {
                format!("over {}", count(comm.size(), "MPI rank"))
            },
            spec.migration.interval,
            spec.migration.count,
            summary.islands.as_ref().map_or(0, |i| i.best_island),
            1e3 * timings.sync_s / g,
            1e3 * timings.migration_s / m,
            1e3 * timings.wait_s / m,
        );
    }
    drop(held);
    Ok(())
}

fn hash_of(path: &std::path::Path) -> Result<String, kinsynth::Error> {
    let bytes = kinsynth::limits::read_file(path, kinsynth::limits::MAX_TEXT_FILE_BYTES).map_err(
        |source| kinsynth::Error::Read {
            path: path.to_path_buf(),
            source,
        },
    )?;
    Ok(fingerprint(&bytes))
}

/// `n` and `what`, plural unless `n` is 1 ("1 island", "2 MPI ranks").
fn count(n: usize, what: &str) -> String {
    if n == 1 {
        format!("1 {what}")
    } else {
        format!("{n} {what}s")
    }
}
