//! Runs that never silently lose or mislead, through the command line: a checkpoint bound to
//! its scenario, the output-directory lock, budgets on resume, help texts, replayable and
//! re-checked reachability, and results independent of the thread count.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_kinsynth");

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn paper_2d() -> PathBuf {
    root().join("examples/scenarios/paper-2d.toml")
}

/// A copy of paper-2d in `dir`, to edit.
fn scenario_copy(dir: &Path) -> PathBuf {
    let p = dir.join("scenario.toml");
    std::fs::copy(paper_2d(), &p).unwrap();
    p
}

fn optimize(scenario: &Path, out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(BIN);
    c.arg("optimize")
        .arg(scenario)
        .args(["--seed", "3", "--quiet", "--out"])
        .arg(out)
        .args(extra);
    c
}

fn resume(dir: &Path, extra: &[&str]) -> Output {
    Command::new(BIN)
        .args(["optimize", "--quiet", "--resume"])
        .arg(dir)
        .args(extra)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn ok(o: &Output) {
    assert!(o.status.success(), "{}", stderr(o));
}

/// A failure with exit code 1 (not a panic's 101) and a one-line error containing `needles`.
fn one_line_error(o: &Output, needles: &[&str]) {
    assert_eq!(o.status.code(), Some(1), "{}", stderr(o));
    let e = stderr(o);
    let lines: Vec<&str> = e.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "one line: {e}");
    assert!(lines[0].starts_with("error: "), "{e}");
    for n in needles {
        assert!(lines[0].contains(n), "`{n}` missing from: {e}");
    }
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// best.json without the wall-clock field.
fn best_without_time(dir: &Path) -> serde_json::Value {
    let mut v = json(&dir.join("best.json"));
    v.as_object_mut().unwrap().remove("elapsed_s");
    v
}

fn generations_in_checkpoint(dir: &Path) -> u64 {
    std::fs::read_to_string(dir.join("checkpoint.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["generation"].as_u64())
        .unwrap_or(0)
}

fn wait_for_checkpoint(dir: &Path) {
    let start = Instant::now();
    while generations_in_checkpoint(dir) < 1 {
        assert!(start.elapsed() < Duration::from_secs(120), "no checkpoint");
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn spawn_long_run(scenario: &Path, out: &Path) -> Child {
    optimize(
        scenario,
        out,
        &["--time-limit", "600", "--checkpoint-interval", "0"],
    )
    .stdout(Stdio::null())
    .stderr(Stdio::null())
    .spawn()
    .unwrap()
}

#[test]
fn resume_refuses_an_edited_or_another_scenario_saying_what_changed() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = scenario_copy(dir.path());
    let out = dir.path().join("run");
    ok(&optimize(
        &scenario,
        &out,
        &["--evaluations", "32", "--recheck-seeds", "1"],
    )
    .output()
    .unwrap());
    let best = std::fs::read(out.join("best.json")).unwrap();
    let original = std::fs::read_to_string(&scenario).unwrap();

    // Fewer links: the design space shrinks.
    std::fs::write(&scenario, original.replace("links = 8", "links = 6")).unwrap();
    one_line_error(
        &resume(&out, &[]),
        &["checkpoint.json", "robot.links was 8, now 6", "--resume"],
    );
    // A wider bound: same size, another variable.
    std::fs::write(
        &scenario,
        original.replace("a = [0.0, 0.25]", "a = [0.0, 0.3]"),
    )
    .unwrap();
    one_line_error(
        &resume(&out, &[]),
        &["free variable 0 was link1.a in [0, 0.25], now link1.a in [0, 0.3]"],
    );
    // Any other edit changes the contents hash.
    std::fs::write(
        &scenario,
        original.replace("clearance = 0.01", "clearance = 0.02"),
    )
    .unwrap();
    one_line_error(
        &resume(&out, &[]),
        &["has changed since the checkpoint", "fnv1a64:"],
    );
    // Another scenario given explicitly.
    let other = root().join("examples/scenarios/paper-3d.toml");
    let o = Command::new(BIN)
        .arg("optimize")
        .arg(&other)
        .args(["--quiet", "--resume"])
        .arg(&out)
        .output()
        .unwrap();
    one_line_error(&o, &["does not match the checkpoint"]);
    assert_eq!(
        std::fs::read(out.join("best.json")).unwrap(),
        best,
        "a refused resume writes nothing"
    );
    // The scenario as it was resumes.
    std::fs::write(&scenario, &original).unwrap();
    ok(&resume(&out, &[]));
}

#[test]
fn a_checkpoint_state_of_the_wrong_length_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    ok(&optimize(
        &paper_2d(),
        &out,
        &["--evaluations", "32", "--recheck-seeds", "1"],
    )
    .output()
    .unwrap());
    let path = out.join("checkpoint.json");
    let mut c = json(&path);
    // As an older checkpoint without the binding and the checksum, with one value too few in
    // an individual.
    let o = c.as_object_mut().unwrap();
    o.remove("scenario_hash");
    o.remove("scenario_shape");
    o.remove("checksum");
    let unbound = c.clone();
    c["state"]["population"][3]["x"]
        .as_array_mut()
        .unwrap()
        .pop();
    std::fs::write(&path, serde_json::to_string(&c).unwrap()).unwrap();
    // The error alone, on one line: the warning about the missing binding waits until the
    // checkpoint has loaded.
    one_line_error(
        &resume(&out, &[]),
        &["state.population[3].x has 7 values, the design space 8"],
    );
    std::fs::write(&path, serde_json::to_string(&unbound).unwrap()).unwrap();
    let o = resume(&out, &["--evaluations", "64"]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("warning:") && e.contains("records no scenario hash"),
        "{e}"
    );
    assert!(e.contains("records no checksum"), "{e}");
    // Planner settings out of their domain are refused too.
    ok(&optimize(
        &paper_2d(),
        &out,
        &["--evaluations", "32", "--recheck-seeds", "1"],
    )
    .output()
    .unwrap());
    let mut c = json(&path);
    c["planner"]["l_max"] = serde_json::json!(-1.0);
    std::fs::write(&path, serde_json::to_string(&c).unwrap()).unwrap();
    one_line_error(
        &resume(&out, &[]),
        &["checkpoint.json", "planner.l_max = -1"],
    );
    // A value of the wrong type is named by its path, in the checkpoint and in its state.
    let original = c.clone();
    c["planner"]["l_max"] = serde_json::json!(std::f64::consts::FRAC_PI_4);
    c["generation"] = serde_json::json!(1.5);
    std::fs::write(&path, serde_json::to_string(&c).unwrap()).unwrap();
    one_line_error(
        &resume(&out, &[]),
        &["checkpoint.json: generation: invalid type: floating point `1.5`"],
    );
    c["generation"] = original["generation"].clone();
    c["state"]["population"][2]["x"][1] = serde_json::json!({});
    std::fs::write(&path, serde_json::to_string(&c).unwrap()).unwrap();
    one_line_error(
        &resume(&out, &[]),
        &[
            "checkpoint.json",
            "state.population[2].x[1]: invalid type: map",
        ],
    );
    // Impossible values are refused, not carried into the history.
    c["state"]["population"][2]["x"][1] = original["state"]["population"][2]["x"][1].clone();
    c["state"]["population"][2]["cost"] = serde_json::json!(-1e308);
    std::fs::write(&path, serde_json::to_string(&c).unwrap()).unwrap();
    one_line_error(
        &resume(&out, &[]),
        &[
            "checkpoint.json",
            "state.population[2].cost = -1e308: must be finite and not negative",
        ],
    );
    c["state"]["population"][2]["cost"] = original["state"]["population"][2]["cost"].clone();
    // The time limit counts from the seconds already spent: a negative count would never
    // reach it (the run would not stop).
    for value in [-1e12, -1e-9] {
        let mut m = c.clone();
        m["elapsed_s"] = serde_json::json!(value);
        std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
        one_line_error(
            &resume(&out, &["--time-limit", "2"]),
            &[
                "checkpoint.json",
                "elapsed_s",
                "must be a finite, non-negative",
            ],
        );
    }
    // The run's options are named as the checkpoint holds them.
    let mut m = c.clone();
    m["options"]["checkpoint_interval"] = serde_json::json!(-1.0);
    std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
    one_line_error(
        &resume(&out, &[]),
        &["checkpoint.json", "options.checkpoint_interval = -1"],
    );
    // Its history, carried into the run's plots, is held to the ranges of its figures.
    for (field, value, says) in [
        ("elapsed_s", -3.0, "history[0].elapsed_s = -3"),
        (
            "best_reachability",
            2.0,
            "history[0].best_reachability = 2: must lie in [0, 1]",
        ),
        (
            "best_cost",
            -1.0,
            "history[0].best_cost = -1: must be finite and not negative",
        ),
    ] {
        let mut m = c.clone();
        m["history"][0][field] = serde_json::json!(value);
        std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
        one_line_error(&resume(&out, &[]), &["checkpoint.json", says]);
    }
    // The optimiser's own settings in the state are held to the scenario's rules: a
    // population of 2^31 − 1 asked for 51 GB at the next generation.
    for (field, value, says) in [
        (
            "population",
            serde_json::json!(2147483647u64),
            "must be at most 10000 (the limit)",
        ),
        (
            "elites",
            serde_json::json!(32),
            "must be less than the population (32)",
        ),
        (
            "crossover_rate",
            serde_json::json!(2.5),
            "must be a probability in [0, 1]",
        ),
    ] {
        let mut m = c.clone();
        m["state"]["params"][field] = value.clone();
        std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
        one_line_error(
            &resume(&out, &[]),
            &[
                "checkpoint.json",
                &format!("state.params.{field} = {value}: {says}"),
            ],
        );
    }
    // A scenario the checkpoint names but that cannot be read is named with where the name
    // comes from.
    let mut m = c.clone();
    m["scenario"] = serde_json::json!("/nonexistent/cylinder");
    std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
    one_line_error(
        &resume(&out, &[]),
        &[
            "checkpoint.json: scenario = /nonexistent/cylinder",
            "cannot read the scenario this checkpoint records",
        ],
    );
}

/// A checkpoint changed after the run wrote it is refused by its checksum, even where every
/// value stays in its domain (it would resume to another result without a word); values out
/// of the run's domain are named by themselves: design values outside the bounds, starting
/// designs other than the scenario's, a particle faster than the swarm allows, a negative
/// annealing time. The same content written another way resumes as written.
#[test]
fn a_changed_checkpoint_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut runs = Vec::new();
    for algorithm in ["ga", "pso", "asa"] {
        let out = dir.path().join(algorithm);
        ok(&optimize(
            &paper_2d(),
            &out,
            &[
                "--optimizer",
                algorithm,
                "--evaluations",
                "40",
                "--recheck-seeds",
                "1",
            ],
        )
        .output()
        .unwrap());
        runs.push(out);
    }
    let path = |out: &Path| out.join("checkpoint.json");
    let write = |out: &Path, v: &serde_json::Value| {
        std::fs::write(path(out), serde_json::to_string(v).unwrap()).unwrap()
    };
    let [ga, pso, asa] = [&runs[0], &runs[1], &runs[2]];
    let original = json(&path(ga));
    assert!(original["checksum"]
        .as_str()
        .is_some_and(|c| c.starts_with("fnv1a64:")));
    // Values in their domain, each changed alone: the evaluations done, the seed, a design
    // value within its bounds (-0 for 0), the generations without improvement.
    type Edit = fn(&mut serde_json::Value);
    let edits: [(&str, Edit); 4] = [
        ("evaluations", |c| c["evaluations"] = serde_json::json!(10)),
        ("seed", |c| c["options"]["seed"] = serde_json::json!(5)),
        ("-0", |c| {
            let population = c["state"]["population"].as_array_mut().unwrap();
            let zero = population
                .iter_mut()
                .flat_map(|e| e["x"].as_array_mut().unwrap())
                .find(|v| v.as_f64() == Some(0.0))
                .expect("a design value at 0");
            *zero = serde_json::json!(-0.0);
        }),
        ("stale", |c| c["stale"] = serde_json::json!(1000000)),
    ];
    for (what, edit) in edits {
        let mut c = original.clone();
        edit(&mut c);
        write(ga, &c);
        let o = resume(ga, &[]);
        assert_eq!(o.status.code(), Some(1), "{what}: {}", stderr(&o));
        one_line_error(
            &o,
            &[
                "checkpoint.json: checksum = fnv1a64:",
                "the content hashes to fnv1a64:",
                "was changed after the run wrote it",
            ],
        );
    }
    // The checkpoint's record of its scenario edited: named as a changed checkpoint, not as a
    // changed scenario (the scenario file is untouched).
    let mut c = original.clone();
    c["scenario_hash"] = serde_json::json!("fnv1a64:0000000000000000");
    write(ga, &c);
    one_line_error(
        &resume(ga, &[]),
        &[
            "checkpoint.json: checksum = fnv1a64:",
            "was changed after the run wrote it",
        ],
    );
    // Sealed anew after the edit (as by hand): counters that contradict each other are still
    // refused, each named.
    let reseal = |mut c: serde_json::Value| {
        c.as_object_mut().unwrap().remove("checksum");
        let sum = kinsynth::optimize::runner::fingerprint(c.to_string().as_bytes());
        c["checksum"] = serde_json::json!(sum);
        c
    };
    // Unchanged but for the seal: resumes.
    write(ga, &reseal(original.clone()));
    ok(&resume(ga, &[]));
    let generation = original["generation"].as_u64().unwrap();
    let made = original["evaluations"].as_u64().unwrap();
    for (edit, says) in [
        (
            ("stale", serde_json::json!(1000000)),
            format!("stale = 1000000: more generations without improvement than generations made ({generation})"),
        ),
        (
            ("generation", serde_json::json!(u64::MAX)),
            format!("generation = 18446744073709551615: more than the evaluations made ({made})"),
        ),
        (
            ("evaluations", serde_json::json!(1)),
            "the evaluations made (1)".to_string(),
        ),
    ] {
        let mut c = original.clone();
        c[edit.0] = edit.1;
        write(ga, &reseal(c));
        one_line_error(&resume(ga, &[]), &["checkpoint.json: ", &says]);
    }
    let mut c = original.clone();
    c["history"][0]["evaluations"] = serde_json::json!(made + 1);
    write(ga, &reseal(c));
    one_line_error(
        &resume(ga, &[]),
        &[&format!(
            "history[0].evaluations = {}: must lie between the row before's (0) and the evaluations made ({made})",
            made + 1
        )],
    );
    // A budget below the evaluations already made.
    write(ga, &original);
    one_line_error(
        &resume(ga, &["--evaluations", "20"]),
        &[&format!(
            "--evaluations = 20: the checkpoint has made {made} evaluations already"
        )],
    );
    // A checksum that is no string.
    let mut c = original.clone();
    c["checksum"] = serde_json::json!(5);
    write(ga, &c);
    one_line_error(
        &resume(ga, &[]),
        &["checkpoint.json: checksum = 5: must be a string"],
    );
    // An island job's checkpoint, which the command shares among the ranks before they read
    // it, is held to its checksum as well (and warned of without one).
    let islands = dir.path().join("islands");
    ok(&optimize(
        &paper_2d(),
        &islands,
        &[
            "--islands",
            "2",
            "--evaluations",
            "130",
            "--recheck-seeds",
            "1",
        ],
    )
    .output()
    .unwrap());
    let island_original = json(&path(&islands));
    let mut c = island_original.clone();
    c["planner"]["goal_tolerance"] = serde_json::json!(0.03);
    write(&islands, &c);
    let o = resume(&islands, &["--islands", "2", "--evaluations", "300"]);
    one_line_error(
        &o,
        &[
            "checkpoint.json: checksum = fnv1a64:",
            "was changed after the run wrote it",
        ],
    );
    let mut c = island_original.clone();
    c.as_object_mut().unwrap().remove("checksum");
    write(&islands, &c);
    let o = resume(&islands, &["--islands", "2", "--evaluations", "300"]);
    ok(&o);
    assert!(stderr(&o).contains("records no checksum"), "{}", stderr(&o));
    // Out of the domain: named by the value.
    let mut c = original.clone();
    c["state"]["population"][1]["x"][2] = serde_json::json!(-1e300);
    write(ga, &c);
    one_line_error(
        &resume(ga, &[]),
        &["state.population[1].x[2] = -1e300: outside the design space's [0, 0.25]"],
    );
    let mut c = original.clone();
    c["state"]["seeds"][0][3] = serde_json::json!(0.1);
    write(ga, &c);
    one_line_error(
        &resume(ga, &[]),
        &["state.seeds[0][3] = 0.1: the scenario's starting design has 0.25"],
    );
    let mut c = json(&path(pso));
    c["state"]["particles"][0]["v"][1] = serde_json::json!(0.2);
    write(pso, &c);
    one_line_error(
        &resume(pso, &[]),
        &["state.particles[0].v[1] = 0.2: beyond the largest velocity"],
    );
    let original_asa = json(&path(asa));
    for (field, index, value, says) in [
        ("k", Some(4), -3.0, "state.k[4] = -3: must not be negative"),
        (
            "k_accept",
            None,
            -1.0,
            "state.k_accept = -1: must not be negative",
        ),
        ("t0", Some(0), 0.0, "state.t0[0] = 0: must be positive"),
        (
            "t0_accept",
            None,
            -2.0,
            "state.t0_accept = -2: must be positive",
        ),
    ] {
        let mut c = original_asa.clone();
        let at = &mut c["state"][field];
        match index {
            Some(i) => at[i] = serde_json::json!(value),
            None => *at = serde_json::json!(value),
        }
        write(asa, &c);
        one_line_error(&resume(asa, &[]), &[says]);
    }
    // The same content, laid out another way: resumes, and to the result of the unchanged
    // checkpoint.
    let copy = dir.path().join("copy");
    std::fs::create_dir(&copy).unwrap();
    for f in ["checkpoint.json", "best.json", "history.csv"] {
        std::fs::copy(ga.join(f), copy.join(f)).unwrap();
    }
    std::fs::write(
        path(&copy),
        serde_json::to_string_pretty(&original).unwrap(),
    )
    .unwrap();
    write(ga, &original);
    ok(&resume(ga, &["--evaluations", "70"]));
    let o = resume(&copy, &["--evaluations", "70"]);
    ok(&o);
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    assert_eq!(best_without_time(ga), best_without_time(&copy));
}

/// A budget extended on resume reproduces the uninterrupted run only where nothing follows
/// the share of the budget spent: PSO's inertia does, so extending a swarm's run says that its
/// result will differ; a GA's does not, and says nothing. Resuming with the same budget (a
/// killed run) says nothing either.
#[test]
fn extending_a_budget_warns_where_the_schedule_follows_it() {
    let dir = tempfile::tempdir().unwrap();
    for (algorithm, warns) in [("pso", true), ("ga", false)] {
        let out = dir.path().join(algorithm);
        let args = ["--optimizer", algorithm, "--recheck-seeds", "1"];
        ok(&optimize(
            &paper_2d(),
            &out,
            &[&args[..], &["--evaluations", "40"]].concat(),
        )
        .output()
        .unwrap());
        let same = resume(&out, &[]);
        ok(&same);
        assert!(!stderr(&same).contains("warning"), "{}", stderr(&same));
        let extended = resume(&out, &["--evaluations", "70"]);
        ok(&extended);
        let e = stderr(&extended);
        assert_eq!(
            e.contains("warning:")
                && e.contains("the evaluation budget changes from 40 to 70")
                && e.contains("the swarm's inertia follows")
                && e.contains("differs from that of an uninterrupted run of 70 evaluations"),
            warns,
            "{algorithm}: {e}"
        );
    }
}

#[test]
fn a_second_run_on_the_same_directory_is_refused_naming_the_first() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("busy");
    let mut first = spawn_long_run(&paper_2d(), &out);
    wait_for_checkpoint(&out);
    let lock = out.join(".kinsynth.lock");
    assert!(lock.exists());
    let pid = format!("pid {}", first.id());
    let o = optimize(&paper_2d(), &out, &["--evaluations", "32"])
        .output()
        .unwrap();
    one_line_error(&o, &["busy", "in use by", &pid, "kinsynth", "optimize"]);
    let o = resume(&out, &[]);
    one_line_error(&o, &["in use by", &pid]);
    // The first run goes on, and its Ctrl-C path releases the lock.
    assert!(
        first.try_wait().unwrap().is_none(),
        "the first run is unharmed"
    );
    let status = Command::new("kill")
        .args(["-INT", &first.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    assert!(first.wait().unwrap().success());
    assert!(!lock.exists(), "the lock file is removed at exit");
    assert_eq!(json(&out.join("best.json"))["stopped"], "interrupted");
}

#[test]
fn a_killed_run_leaves_a_stale_lock_that_is_taken_over_and_its_temporary_files_removed() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("killed");
    let mut child = spawn_long_run(&paper_2d(), &out);
    wait_for_checkpoint(&out);
    let pid = child.id();
    child.kill().unwrap();
    child.wait().unwrap();
    let lock = out.join(".kinsynth.lock");
    assert!(lock.exists(), "kill -9 leaves the lock file");
    std::fs::create_dir_all(out.join("trajectories")).unwrap();
    for f in [".kinsynth-a1b2.tmp", "trajectories/.kinsynth-c3d4.tmp"] {
        std::fs::write(out.join(f), "half").unwrap();
    }
    let o = resume(&out, &["--time-limit", "0", "--recheck-seeds", "1"]);
    ok(&o);
    let e = stderr(&o);
    assert!(
        e.contains(&format!("taking over the lock of pid {pid}")),
        "{e}"
    );
    assert!(e.contains("removed 2 temporary file(s)"), "{e}");
    assert!(!out.join(".kinsynth-a1b2.tmp").exists());
    assert!(!out.join("trajectories/.kinsynth-c3d4.tmp").exists());
    assert!(!lock.exists());
}

#[test]
fn bad_budgets_are_refused_naming_the_flag_and_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never");
    for (flag, value, reason) in [
        (
            "--time-limit",
            "-1",
            "must be a finite, non-negative number of seconds",
        ),
        (
            "--time-limit",
            "nan",
            "must be a finite, non-negative number of seconds",
        ),
        (
            "--time-limit",
            "inf",
            "must be a finite, non-negative number of seconds",
        ),
        (
            "--checkpoint-interval",
            "-5",
            "must be a finite, non-negative",
        ),
        ("--lmax", "-1", "must be positive and at most 1000000"),
        ("--lmax", "inf", "must be positive and at most 1000000"),
        // As the scenario's planner.l_max.
        ("--lmax", "1e308", "must be positive and at most 1000000"),
        (
            "--recheck-seeds",
            "100000",
            "must be a whole number from 0 to 1000",
        ),
        (
            "--recheck-seeds",
            "-1",
            "must be a whole number from 0 to 1000",
        ),
        ("--evaluations", "-1", "must be a whole number from 1 to"),
        ("--evaluations", "0", "must be a whole number from 1 to"),
        ("--evaluations", "2.5", "must be a whole number from 1 to"),
        ("--evaluations", "nan", "must be a whole number from 1 to"),
    ] {
        let o = optimize(&paper_2d(), &out, &[flag, value])
            .output()
            .unwrap();
        let shown = value.replace("nan", "NaN");
        one_line_error(&o, &[&format!("{flag} = {shown}"), reason]);
    }
    assert!(!out.exists(), "nothing is written for a refused run");
    let o = Command::new(BIN)
        .arg("reach")
        .arg(paper_2d())
        .args(["--lmax", "-0.5"])
        .output()
        .unwrap();
    one_line_error(&o, &["--lmax = -0.5"]);
}

/// An experiment's evaluation budget is exact for each of its runs, and its summary line says
/// both budgets: one workspace of paper-2d with 8 evaluations per method makes 8 in every run.
#[test]
fn an_experiment_run_makes_exactly_its_evaluation_budget() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    let o = Command::new(BIN)
        .args([
            "experiment",
            "paper-2d",
            "--runs",
            "1",
            "--evaluations",
            "8",
        ])
        .args(["--time-limit", "30", "--seed", "3", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let said = stdout(&o);
    assert!(
        said.contains("6 runs of at most 30 s or 8 evaluations"),
        "{said}"
    );
    let runs = std::fs::read_to_string(out.join("runs.csv")).unwrap();
    let mut lines = runs.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = header.iter().position(|h| *h == "evaluations").unwrap();
    let counts: Vec<&str> = lines.map(|l| l.split(',').nth(at).unwrap()).collect();
    assert_eq!(counts, ["8"; 6], "{runs}");
}

#[test]
fn resume_with_a_larger_budget_extends_the_run_to_the_uninterrupted_result() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    let recheck = ["--recheck-seeds", "2"];
    ok(&optimize(
        &paper_2d(),
        &whole,
        &[&recheck[..], &["--evaluations", "150"]].concat(),
    )
    .output()
    .unwrap());
    let short = dir.path().join("short");
    ok(&optimize(
        &paper_2d(),
        &short,
        &[&recheck[..], &["--evaluations", "60"]].concat(),
    )
    .output()
    .unwrap());
    // The budgets are exact: 60 ends within the second generation (32 + 28 of 30), whose
    // points count for best.json; the checkpoint keeps the first, which the resume goes on
    // from.
    assert_eq!(json(&short.join("best.json"))["evaluations"], 60);
    assert_eq!(json(&short.join("checkpoint.json"))["evaluations"], 32);
    ok(&resume(&short, &["--evaluations", "150"]));
    assert_eq!(json(&short.join("best.json"))["evaluations"], 150);
    assert_eq!(best_without_time(&short), best_without_time(&whole));
    // A time limit given on resume is a new total: a spent one ends the run at once.
    let o = resume(&short, &["--time-limit", "0", "--evaluations", "1000"]);
    ok(&o);
    assert_eq!(
        json(&short.join("best.json"))["stopped"],
        "time limit reached"
    );
}

/// paper-2d with 600 designs per generation (about 2 s of evaluations here), in `dir`.
fn wide_scenario(dir: &Path) -> PathBuf {
    let scenario = scenario_copy(dir);
    let text = std::fs::read_to_string(&scenario).unwrap();
    assert!(text.contains("population = 32"));
    std::fs::write(
        &scenario,
        text.replace("population = 32", "population = 600"),
    )
    .unwrap();
    scenario
}

/// A time limit cuts a generation short instead of waiting for it: with 600 designs per
/// generation (about 2 s of evaluations here) and `--time-limit 0.3`, the run stops within the
/// first generation and its result is the best design evaluated by then. The checkpoint stays
/// at the last whole generation (here none), so a resume repeats the cut generation with the
/// same random streams and reaches the result of an uninterrupted run.
#[test]
fn a_time_limit_cuts_a_generation_short_and_resume_repeats_it() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = wide_scenario(dir.path());
    let recheck = ["--recheck-seeds", "2"];
    let cut = dir.path().join("cut");
    ok(&optimize(
        &scenario,
        &cut,
        &[&recheck[..], &["--time-limit", "0.3"]].concat(),
    )
    .output()
    .unwrap());
    let best = json(&cut.join("best.json"));
    assert_eq!(best["stopped"], "time limit reached");
    let evaluated = best["evaluations"].as_u64().unwrap();
    assert!(
        (1..600).contains(&evaluated),
        "the first generation is cut short: {evaluated} of 600 evaluated"
    );
    assert!(best["cost"].as_f64().unwrap().is_finite());
    // history.csv ends with the cut generation, as best.json does.
    let history = std::fs::read_to_string(cut.join("history.csv")).unwrap();
    let last: Vec<&str> = history.lines().last().unwrap().split(',').collect();
    assert_eq!(last[1], evaluated.to_string(), "{history}");
    let checkpoint = json(&cut.join("checkpoint.json"));
    assert_eq!(checkpoint["generation"], 0);
    assert_eq!(checkpoint["evaluations"], 0);
    let whole = dir.path().join("whole");
    ok(&optimize(
        &scenario,
        &whole,
        &[&recheck[..], &["--evaluations", "600"]].concat(),
    )
    .output()
    .unwrap());
    // The time limit is a total over the run: spent, it stops a resume before anything is
    // evaluated, and says so.
    one_line_error(
        &resume(&cut, &["--evaluations", "600"]),
        &[
            "checkpoint.json: options.time_limit = 0.3:",
            "was spent before any design was evaluated",
        ],
    );
    ok(&resume(
        &cut,
        &["--evaluations", "600", "--time-limit", "1000"],
    ));
    assert_eq!(best_without_time(&cut), best_without_time(&whole));
}

/// Ctrl-C cuts a generation short as a time limit does: a run of 600 designs per generation
/// (about 2 s each here) interrupted within its first generation ends cleanly, at once, with
/// the best design evaluated by then.
#[test]
fn ctrl_c_cuts_a_generation_short() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = wide_scenario(dir.path());
    let out = dir.path().join("out");
    let mut child = optimize(
        &scenario,
        &out,
        &["--time-limit", "600", "--recheck-seeds", "2"],
    )
    .stdout(Stdio::null())
    .stderr(Stdio::null())
    .spawn()
    .unwrap();
    // The lock is taken just before the Ctrl-C handler is set and the run starts.
    let start = Instant::now();
    while !out.join(".kinsynth.lock").exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no lock");
        std::thread::sleep(Duration::from_millis(5));
    }
    std::thread::sleep(Duration::from_millis(300));
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    assert!(child.wait().unwrap().success());
    let best = json(&out.join("best.json"));
    assert_eq!(best["stopped"], "interrupted");
    let evaluated = best["evaluations"].as_u64().unwrap();
    assert!(
        (1..600).contains(&evaluated),
        "the first generation is cut short: {evaluated} of 600 evaluated"
    );
    assert_eq!(json(&out.join("checkpoint.json"))["generation"], 0);
}

#[test]
fn every_help_lists_the_files_its_command_writes() {
    let help = |cmd: &str| {
        let o = Command::new(BIN).args([cmd, "--help"]).output().unwrap();
        ok(&o);
        stdout(&o)
    };
    let h = help("optimize");
    for f in [
        "best.json",
        "history.csv",
        "reach.json",
        "convergence.svg",
        "robot.urdf",
        "trajectories/",
        "checkpoint.json",
        ".kinsynth.lock",
    ] {
        assert!(h.contains(f), "optimize --help lacks {f}");
    }
    let h = help("experiment");
    for f in [
        "runs.csv",
        "curves.csv",
        "curves.svg",
        "scenario.toml",
        "method{k}",
    ] {
        assert!(h.contains(f), "experiment --help lacks {f}");
    }
    let h = help("reach");
    for f in ["--json FILE", "task_{i}.csv", "task_{i}.json", "--seeds"] {
        assert!(h.contains(f), "reach --help lacks {f}");
    }
    for cmd in ["urdf", "scenario"] {
        assert!(help(cmd).contains("Writes the file given by -o"), "{cmd}");
    }
    for cmd in ["check", "edges"] {
        assert!(
            help(cmd).to_lowercase().contains("writes no files"),
            "{cmd}"
        );
    }
}

#[test]
fn best_json_replays_its_evaluation_and_records_the_recheck() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = optimize(
        &paper_2d(),
        &out,
        &["--evaluations", "96", "--recheck-seeds", "3"],
    )
    .output()
    .unwrap();
    ok(&o);
    assert!(
        stdout(&o).contains("re-checked with 3 seeds"),
        "{}",
        stdout(&o)
    );
    let best = json(&out.join("best.json"));
    let robust = &best["robust_reachability"];
    assert_eq!(robust["seeds"], 3);
    let values: Vec<f64> = robust["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(values.len(), 3);
    let min = values.iter().copied().fold(f64::INFINITY, f64::min);
    assert_eq!(robust["min"].as_f64().unwrap(), min);
    assert!(robust["candidates"].as_u64().unwrap() >= 1);
    assert!(best["robust_cost"].as_f64().unwrap() >= best["cost"].as_f64().unwrap() - 1e-12);
    assert!(best["stream"].as_u64().is_some());
    assert_eq!(best["planner"]["checker"], "certified");

    // reach without --seed replays the producing evaluation: same R and paths as reach.json.
    let replay = dir.path().join("replay.json");
    let o = Command::new(BIN)
        .arg("reach")
        .arg(paper_2d())
        .arg("--design")
        .arg(out.join("best.json"))
        .arg("--json")
        .arg(&replay)
        .output()
        .unwrap();
    ok(&o);
    assert!(
        stdout(&o).contains("replaying the evaluation"),
        "{}",
        stdout(&o)
    );
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    let (a, b) = (json(&replay), json(&out.join("reach.json")));
    assert_eq!(a["reachability"], best["reachability"]);
    assert_eq!(a["stream"], best["stream"]);
    assert_eq!(a["targets"], b["targets"]);
    assert_eq!(a["nodes"], b["nodes"]);
    // A best.json whose recorded R its replay does not give is not as the run wrote it.
    let mut edited = best.clone();
    edited["reachability"] = serde_json::json!(0.25);
    let file = dir.path().join("edited.json");
    std::fs::write(&file, edited.to_string()).unwrap();
    let o = Command::new(BIN)
        .arg("reach")
        .arg(paper_2d())
        .arg("--design")
        .arg(&file)
        .output()
        .unwrap();
    ok(&o);
    assert!(
        stderr(&o)
            .contains("edited.json: records R = 0.25, and this replay of its evaluation gives"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn reach_reports_the_spread_of_r_over_seeds() {
    // A design that reaches task 9 only at the edge of the goal tolerance: R = 1 for four
    // seeds of 0-9 only.
    let design = root().join("tests/fixtures/edge-of-tolerance.json");
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("spread.json");
    let o = Command::new(BIN)
        .arg("reach")
        .arg(paper_2d())
        .arg("--design")
        .arg(&design)
        .args(["--seeds", "10", "--seed", "0", "--json"])
        .arg(&report)
        .output()
        .unwrap();
    ok(&o);
    assert!(
        stdout(&o).contains("R over 10 seeds (0–9): min 0.900, mean 0.940, max 1.000"),
        "{}",
        stdout(&o)
    );
    let v = json(&report);
    let spread = &v["spread"];
    assert_eq!(spread["seeds"].as_array().unwrap().len(), 10);
    assert_eq!(spread["min"], 0.9);
    assert_eq!(spread["max"], 1.0);
    assert!((spread["mean"].as_f64().unwrap() - 0.94).abs() < 1e-12);
    assert_eq!(v["seed"], 0, "the report is the first seed's");
    let o = Command::new(BIN)
        .arg("reach")
        .arg(paper_2d())
        .args(["--seeds", "0"])
        .output()
        .unwrap();
    one_line_error(&o, &["--seeds = 0"]);
}

#[test]
fn one_seed_fixes_the_result_whatever_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let mut bests = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("threads{threads}"));
        ok(&optimize(
            &paper_2d(),
            &out,
            &["--evaluations", "96", "--recheck-seeds", "4"],
        )
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .unwrap());
        bests.push(best_without_time(&out));
    }
    assert_eq!(bests[0], bests[1]);
}

#[test]
fn confirmation_runs_keep_a_lucky_planner_run_from_scoring_r_1() {
    use kinsynth::optimize::Objective;
    let s = kinsynth::Scenario::load(&paper_2d()).unwrap();
    let design =
        kinsynth::Design::load(&root().join("tests/fixtures/edge-of-tolerance.json")).unwrap();
    let x = s.space.encode(&design);
    assert_eq!(s.space.decode(&x), design);
    // Planner seed 3, stream 0 reaches every task; its first confirmation run does not.
    let lucky = Objective::new(&s, s.planner.clone(), 3);
    assert_eq!(lucky.plan_once(&x, 0, 0.0).0.reachability, 1.0);
    let e = Objective::new(&s, s.planner.clone(), 3)
        .with_confirmation(2)
        .evaluate_confirmed(&x, 0, 0.0);
    assert_eq!(e.breakdown.reachability, 0.9);
    assert!(e.planner_runs >= 2);
    assert_ne!(e.stream, 0, "the run that fell short is the one to replay");
    assert_eq!(lucky.plan_once(&x, e.stream, 0.0).0, e.report);
}

/// An output name taken by a folder (or the trajectories folder by a file) fails the run before
/// it starts: found after the run, it left the results written before it beside the failure.
#[test]
fn output_names_taken_by_the_wrong_kind_fail_the_run_before_it_starts() {
    let dir = tempfile::tempdir().unwrap();
    for (name, folder) in [("report.html", true), ("trajectories", false)] {
        let out = dir.path().join(format!("run-{name}"));
        std::fs::create_dir_all(&out).unwrap();
        if folder {
            std::fs::create_dir(out.join(name)).unwrap();
        } else {
            std::fs::write(out.join(name), "a file").unwrap();
        }
        let o = optimize(&paper_2d(), &out, &["--evaluations", "32"])
            .output()
            .unwrap();
        one_line_error(&o, &[name, "cannot write"]);
        assert!(!out.join("best.json").exists(), "nothing may be written");
        assert!(
            !out.join("checkpoint.json").exists(),
            "nothing may be written"
        );
    }
}

/// The scenario's mesh files are bound to the checkpoint as its file is: a mesh changed
/// between a run and its resume (the scenario file untouched) is refused, naming the scenario
/// and the mesh hashes, and the mesh restored resumes.
#[test]
fn a_mesh_changed_since_the_checkpoint_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(paper_2d()).unwrap();
    let tet = |z: f64| {
        format!(
            "v 5 5 {z}\nv 6 5 {z}\nv 5 6 {z}\nv 5 5 {}\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
            z + 1.0
        )
    };
    let obj = dir.path().join("tet.obj");
    std::fs::write(&obj, tet(0.0)).unwrap();
    let scenario = dir.path().join("meshed.toml");
    std::fs::write(
        &scenario,
        format!("{text}\n[[obstacle]]\nshape = \"mesh\"\nfile = \"tet.obj\"\nposition = [0.0, 0.0, 0.0]\n"),
    )
    .unwrap();
    let out = dir.path().join("run");
    ok(&optimize(
        &scenario,
        &out,
        &["--evaluations", "40", "--recheck-seeds", "1"],
    )
    .output()
    .unwrap());
    let c = json(&out.join("checkpoint.json"));
    assert!(
        c["meshes_hash"]
            .as_str()
            .is_some_and(|h| h.starts_with("fnv1a64:")),
        "{c}"
    );
    std::fs::write(&obj, tet(0.5)).unwrap();
    one_line_error(
        &resume(&out, &["--evaluations", "60"]),
        &[
            "meshed.toml: its mesh files have changed since the checkpoint: their contents hash fnv1a64:",
            "--resume needs the meshes the run started with",
        ],
    );
    std::fs::write(&obj, tet(0.0)).unwrap();
    ok(&resume(&out, &["--evaluations", "60"]));
}

/// `--resume` of a folder without a checkpoint (a run killed before its first) says so.
#[test]
fn resuming_a_folder_without_a_checkpoint_says_why() {
    let dir = tempfile::tempdir().unwrap();
    one_line_error(
        &resume(dir.path(), &[]),
        &["holds no checkpoint.json: the run there was stopped before its first checkpoint"],
    );
}
