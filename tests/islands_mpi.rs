//! `kinsynth optimize --islands` over MPI (`cargo test --features mpi --test islands_mpi`;
//! needs Open MPI's `mpirun`): 2- and 3-rank jobs on this machine (`--oversubscribe`), the
//! same `best.json` for the same seed and number of ranks, migration in `islands.csv`, resume
//! after `kill -9` to the uninterrupted result, and a different number of ranks refused.
#![cfg(feature = "mpi")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_kinsynth");

/// paper-3d with islands that migrate every 2 generations, written into `dir`.
fn scenario(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios/paper-3d.toml"),
    )
    .unwrap();
    let default = "\n[optimizer.migration]\ninterval = 10\ncount = 2\n";
    assert!(text.contains(default));
    let text = text.replace(
        default,
        "\n[optimizer.migration]\ninterval = 2\ncount = 2\n",
    );
    let path = dir.join("paper-3d-islands.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// `mpirun -np N kinsynth ARGS…` (allowed as root, several ranks per core, one thread each).
fn mpirun(ranks: usize, args: &[&str]) -> Command {
    let mut c = Command::new("mpirun");
    c.args(["--oversubscribe", "-np", &ranks.to_string()])
        .args(["-x", "RAYON_NUM_THREADS=1"])
        .arg(BIN)
        .args(args)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_rmaps_base_oversubscribe", "1")
        .stdin(Stdio::null());
    c
}

fn optimize(ranks: usize, scenario: &Path, out: &Path, extra: &[&str]) -> Command {
    let mut args = vec![
        "optimize",
        scenario.to_str().unwrap(),
        "--islands",
        "--seed",
        "3",
        "--evaluations",
        "384",
        "--recheck-seeds",
        "2",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    mpirun(ranks, &args)
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "status {:?}\nstdout: {}\nstderr: {}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// best.json (which holds no wall-clock time).
fn best(dir: &Path) -> serde_json::Value {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("best.json")).unwrap()).unwrap();
    assert!(
        v.get("elapsed_s").is_none(),
        "wall-clock time is kept out of best.json"
    );
    v
}

/// islands.csv as (generation, island, evaluations, best_cost).
fn islands_csv(dir: &Path) -> Vec<(u64, usize, u64, f64)> {
    let text = std::fs::read_to_string(dir.join("islands.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("generation,island,evaluations,best_cost,best_reachability")
    );
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 5, "{l}");
            (
                f[0].parse().unwrap(),
                f[1].parse().unwrap(),
                f[2].parse().unwrap(),
                f[3].parse().unwrap(),
            )
        })
        .collect()
}

fn checkpoint_generation(dir: &Path) -> u64 {
    std::fs::read_to_string(dir.join("checkpoint.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["generation"].as_u64())
        .unwrap_or(0)
}

#[test]
fn two_ranks_give_the_same_result_twice_migrate_and_resume_after_kill_9() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = scenario(dir.path());
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    ok(&optimize(2, &scenario, &a, &[]).output().unwrap());
    ok(&optimize(2, &scenario, &b, &[]).output().unwrap());
    assert_eq!(best(&a), best(&b));
    // The same file, byte for byte.
    let bytes = |d: &Path| std::fs::read(d.join("best.json")).unwrap();
    assert_eq!(bytes(&a), bytes(&b));
    assert_eq!(best(&a)["islands"]["islands"], 2);
    for f in ["history.csv", "reach.json", "robot.urdf", "robot.srdf"] {
        assert!(a.join(f).is_file(), "{f}");
    }

    // 384 evaluations of 2 islands of 32 (GA: 32, then 30 children per generation): 6 whole
    // generations (364 evaluations), a row per island each, and 10 designs of each island's
    // seventh step, where the budget cuts it (they count for best.json only); migration after
    // generations 2, 4, 6 leaves both islands with the better of their bests, and at least
    // once that is a design the other island found.
    let rows = islands_csv(&a);
    assert_eq!(rows, islands_csv(&b));
    assert_eq!(best(&a)["evaluations"], 384);
    assert_eq!(rows.len(), 12);
    for (k, r) in rows.iter().enumerate() {
        let g = k as u64 / 2 + 1;
        assert_eq!((r.0, r.1, r.2), (g, k % 2, 32 + 30 * (g - 1)));
    }
    let cost = |g: u64, i: usize| rows[(g as usize - 1) * 2 + i].3;
    let mut moved = 0;
    for g in [2, 4, 6] {
        assert_eq!(cost(g, 0), cost(g, 1), "generation {g}: {rows:?}");
        if cost(g - 1, 0) != cost(g - 1, 1) {
            moved += 1;
        }
    }
    assert!(
        moved > 0,
        "no migrant ever changed an island's best: {rows:?}"
    );

    // kill -9 rank 0 (its pid is in the lock file) after its third checkpoint; mpirun ends the
    // job, and the last checkpoint resumes it to the uninterrupted result.
    let killed = dir.path().join("killed");
    let job = optimize(2, &scenario, &killed, &["--checkpoint-interval", "0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while checkpoint_generation(&killed) < 3 {
        assert!(start.elapsed() < Duration::from_secs(300), "no checkpoint");
        std::thread::sleep(Duration::from_millis(20));
    }
    let lock: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(killed.join(".kinsynth.lock")).unwrap())
            .unwrap();
    let pid = lock["pid"].as_u64().unwrap().to_string();
    let status = Command::new("kill").args(["-9", &pid]).status().unwrap();
    assert!(status.success());
    let out = job.wait_with_output().unwrap();
    assert!(!out.status.success(), "the job ended well after a kill -9");
    let at_kill = checkpoint_generation(&killed);
    assert!(
        at_kill < 6,
        "killed before the end (generation {at_kill} of 6)"
    );
    assert!(!killed.join("best.json").exists());

    // Another number of ranks is refused, naming both.
    let other = mpirun(
        3,
        &[
            "optimize",
            "--resume",
            killed.to_str().unwrap(),
            "--islands",
            "--quiet",
        ],
    )
    .output()
    .unwrap();
    assert!(!other.status.success());
    let err = String::from_utf8_lossy(&other.stderr);
    assert!(
        err.contains("holds 2 islands, this job has 3"),
        "stderr: {err}"
    );

    let resumed = mpirun(
        2,
        &[
            "optimize",
            "--resume",
            killed.to_str().unwrap(),
            "--islands",
            "--quiet",
        ],
    )
    .output()
    .unwrap();
    ok(&resumed);
    assert_eq!(best(&killed), best(&a));
    assert_eq!(islands_csv(&killed), rows);
}

#[test]
fn three_ranks_migrate_around_the_ring_and_repeat() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = scenario(dir.path());
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let extra = ["--optimizer", "pso"];
    ok(&optimize(3, &scenario, &a, &extra).output().unwrap());
    ok(&optimize(3, &scenario, &b, &extra).output().unwrap());
    assert_eq!(best(&a), best(&b));
    let rows = islands_csv(&a);
    // 384 evaluations by 3 islands of 32: 4 generations.
    assert_eq!(rows.len(), 12);
    let cost = |g: u64, i: usize| rows[(g as usize - 1) * 3 + i].3;
    // After generations 2 and 4, island i+1 holds island i's best of that generation, no
    // worse than island i's best of the generation before.
    for g in [2, 4] {
        for i in 0..3 {
            assert!(
                cost(g, (i + 1) % 3) <= cost(g - 1, i),
                "generation {g}, island {}: {rows:?}",
                (i + 1) % 3
            );
        }
    }
    assert_eq!(best(&a)["islands"]["islands"], 3);
}
