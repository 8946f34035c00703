//! Mutation fuzzing of every input kind: scenario TOML, binary and ASCII STL, OBJ, design JSON,
//! URDF and checkpoint JSON. The bundled files are mutated with a fixed seed (byte flips,
//! truncation, duplication and deletion of slices, numbers replaced by NaN, infinities, 1e308,
//! -1, 0 and huge integers) and every mutant is read through the library, in a thread with a
//! time limit, and a sample through the `kinsynth` binary. Whatever the input, there must be
//! no panic, no hang and either success or a one-line error naming the file. Inputs that are
//! accepted are also used (planning, hulls, export), so that nothing downstream panics either.
//!
//! A failing case prints its mutations and saves the input under the system's temporary
//! directory; crash cases found so far are kept as the named regression tests at the end.

use kinsynth::collision::CollisionScene;
use kinsynth::optimize::runner::Runner;
use kinsynth::planning::reach::reachability_of;
use kinsynth::planning::{reachability, PlannerConfig};
use kinsynth::world::mesh::load_mesh;
use kinsynth::{Design, Scenario};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_kinsynth");

/// Longest a single library case may take before it counts as a hang.
const CASE_LIMIT: Duration = Duration::from_secs(20);
/// Longest a single run of the binary may take before it counts as a hang.
const RUN_LIMIT: Duration = Duration::from_secs(60);

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Replacement numbers: non-finite, huge, negative, zero and integers beyond 64 bits.
const NUMBERS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "-1",
    "0",
    "1e9",
    "1000000000",
    "18446744073709551616",
    "4294967296",
    "1e-320",
    "-0",
    "99999999999999999999999",
];

/// Seeded mutations of a file's bytes.
struct Mutator {
    rng: ChaCha8Rng,
}

impl Mutator {
    fn new(seed: u64) -> Self {
        Mutator {
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    fn pos(&mut self, len: usize) -> usize {
        if len == 0 {
            0
        } else {
            self.rng.random_range(0..len)
        }
    }

    /// Spans of number tokens in text.
    fn numbers(bytes: &[u8]) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let mut i = 0;
        while i < bytes.len() {
            let starts = bytes[i].is_ascii_digit()
                || (bytes[i] == b'-' && bytes.get(i + 1).is_some_and(|b| b.is_ascii_digit()));
            if starts && (i == 0 || !bytes[i - 1].is_ascii_alphanumeric()) {
                let mut j = i + 1;
                while j < bytes.len() && (bytes[j].is_ascii_digit() || b".eE+-".contains(&bytes[j]))
                {
                    j += 1;
                }
                out.push((i, j));
                i = j;
            } else {
                i += 1;
            }
        }
        out
    }

    /// One to three mutations of `input`; `text` keeps flipped bytes printable or structural,
    /// `stl` adds float and count overwrites in a binary STL's records.
    fn mutate(&mut self, input: &[u8], text: bool, stl: bool) -> (Vec<u8>, String) {
        let mut b = input.to_vec();
        let mut what = Vec::new();
        let n = self.rng.random_range(1..=3);
        for _ in 0..n {
            let op = self.rng.random_range(0..if stl { 7 } else { 6 });
            match op {
                0 => {
                    let k = self.rng.random_range(1..=4);
                    for _ in 0..k {
                        let p = self.pos(b.len());
                        if p < b.len() {
                            b[p] = if text {
                                *b"[]{}=,.\"'\n#<>/ -0123456789eaz"
                                    .get(self.rng.random_range(0..29))
                                    .unwrap_or(&b'x')
                            } else {
                                self.rng.random()
                            };
                        }
                    }
                    what.push(format!("flip {k} bytes"));
                }
                1 => {
                    let p = self.pos(b.len());
                    b.truncate(p);
                    what.push(format!("truncate at {p}"));
                }
                2 => {
                    let a = self.pos(b.len());
                    let len = self.rng.random_range(1..=400).min(b.len() - a.min(b.len()));
                    let slice = b[a..a + len].to_vec();
                    let at = self.pos(b.len() + 1);
                    let times = if self.rng.random_range(0..8) == 0 {
                        50
                    } else {
                        1
                    };
                    for _ in 0..times {
                        b.splice(at..at, slice.iter().copied());
                    }
                    what.push(format!("duplicate {len} bytes from {a} at {at} ×{times}"));
                }
                3 => {
                    let a = self.pos(b.len());
                    let len = self.rng.random_range(1..=200).min(b.len() - a.min(b.len()));
                    b.drain(a..a + len);
                    what.push(format!("delete {len} bytes at {a}"));
                }
                4 | 5 => {
                    let spans = Self::numbers(&b);
                    if spans.is_empty() {
                        continue;
                    }
                    let (s, e) = spans[self.rng.random_range(0..spans.len())];
                    let v = NUMBERS[self.rng.random_range(0..NUMBERS.len())];
                    let old = String::from_utf8_lossy(&b[s..e]).into_owned();
                    b.splice(s..e, v.bytes());
                    what.push(format!("number {old} at {s} -> {v}"));
                }
                _ => {
                    // Binary STL: a float of a record, or the triangle count.
                    if b.len() < 84 {
                        continue;
                    }
                    if self.rng.random_range(0..4) == 0 {
                        let count: u32 = match self.rng.random_range(0..4) {
                            0 => u32::MAX,
                            1 => 0,
                            2 => self.rng.random(),
                            _ => u32::from_le_bytes([b[80], b[81], b[82], b[83]]).wrapping_add(1),
                        };
                        b[80..84].copy_from_slice(&count.to_le_bytes());
                        what.push(format!("triangle count -> {count}"));
                    } else {
                        let records = (b.len() - 84) / 50;
                        if records == 0 {
                            continue;
                        }
                        let r = self.rng.random_range(0..records);
                        let f = self.rng.random_range(0..12);
                        let v: f32 = [f32::NAN, f32::INFINITY, f32::MAX, -1.0, 0.0, 1e30, 1e-40]
                            [self.rng.random_range(0..7)];
                        let at = 84 + 50 * r + 4 * f;
                        b[at..at + 4].copy_from_slice(&v.to_le_bytes());
                        what.push(format!("record {r} float {f} -> {v}"));
                    }
                }
            }
        }
        (b, what.join(", "))
    }
}

/// Runs `f` in its own thread with a time limit; a panic or a hang fails the test, naming the
/// case and saving its input.
fn run_case<T: Send + 'static>(
    kind: &str,
    case: usize,
    what: &str,
    input: &[u8],
    f: impl FnOnce() -> T + Send + 'static,
) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(move || {
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
            let _ = tx.send(r);
        })
        .unwrap();
    let fail = |why: &str| -> ! {
        let saved = std::env::temp_dir().join(format!("kinsynth-fuzz-{kind}-{case}"));
        let _ = std::fs::write(&saved, input);
        panic!(
            "{kind} case {case} ({what}): {why}; input saved to {}",
            saved.display()
        )
    };
    match rx.recv_timeout(CASE_LIMIT) {
        Ok(Ok(v)) => v,
        Ok(Err(_)) => fail("panicked"),
        Err(_) => fail(&format!("no answer within {CASE_LIMIT:?} (hang)")),
    }
}

/// The error must be a single line that names `file`.
fn assert_one_line(kind: &str, case: usize, what: &str, message: &str, file: &Path) {
    assert!(
        !message.is_empty() && !message.contains('\n'),
        "{kind} case {case} ({what}): not a one-line error: {message:?}"
    );
    assert!(
        message.contains(&file.display().to_string()),
        "{kind} case {case} ({what}): the error does not name {}: {message}",
        file.display()
    );
}

/// Runs the binary with a time limit: exit 0, or exit 1 with one line `error: …` on stderr.
/// Never a panic (101), a signal or a hang.
fn run_binary(kind: &str, case: usize, what: &str, args: &[&std::ffi::OsStr]) {
    let mut child = Command::new(BIN)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > RUN_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{kind} binary case {case} ({what}): no exit within {RUN_LIMIT:?}: {args:?}");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut stderr = String::new();
    use std::io::Read;
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    match status.code() {
        Some(0) => {}
        Some(1) => {
            let errors: Vec<&str> = stderr.lines().filter(|l| !l.starts_with("warning:")).collect();
            assert!(
                errors.len() == 1 && errors[0].starts_with("error: "),
                "{kind} binary case {case} ({what}): not a one-line error: {stderr}"
            );
        }
        other => panic!(
            "{kind} binary case {case} ({what}): exit {other:?} (101 is a panic): {args:?}\n{stderr}"
        ),
    }
}

/// A small planner for checking that accepted inputs can be used.
fn quick_planner(p: &PlannerConfig) -> PlannerConfig {
    PlannerConfig {
        max_iterations: p.max_iterations.min(200),
        ik_steps: p.ik_steps.min(20),
        time_limit: Some(2.0),
        schedule: None,
        self_collision: kinsynth::collision::SelfCollisionConfig {
            samples: p.self_collision.samples.min(50),
            ..p.self_collision.clone()
        },
        ..p.clone()
    }
}

/// A temporary copy of the repository's layout: `examples/scenarios/` for the mutant and a
/// `meshes` link to the bundled meshes, so the scenarios' relative mesh paths resolve.
fn layout() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let scenarios = dir.path().join("examples/scenarios");
    std::fs::create_dir_all(&scenarios).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(repo("meshes"), dir.path().join("meshes")).unwrap();
    #[cfg(not(unix))]
    {
        std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
        for m in ["glovebox.stl", "vessel.stl", "pipe_bundle.obj"] {
            std::fs::copy(
                repo(&format!("meshes/{m}")),
                dir.path().join("meshes").join(m),
            )
            .unwrap();
        }
    }
    (dir, scenarios)
}

#[test]
fn mutated_scenarios() {
    let (_dir, scenarios) = layout();
    // Scenarios with meshes load them (the decomposition takes a while): fewer cases.
    let files = [
        ("paper-2d.toml", 160),
        ("paper-3d.toml", 160),
        ("ur5-cell.toml", 160),
        ("glovebox.toml", 40),
        ("drill-fixture.toml", 80),
        ("pipework.toml", 12),
    ];
    let mut m = Mutator::new(1);
    let mut case = 0;
    for (name, cases) in files {
        let original = std::fs::read(repo(&format!("examples/scenarios/{name}"))).unwrap();
        for k in 0..cases {
            case += 1;
            let (bytes, what) = m.mutate(&original, true, false);
            let what = format!("{name}: {what}");
            let path = scenarios.join(format!("case{case}.toml"));
            std::fs::write(&path, &bytes).unwrap();
            let p = path.clone();
            let result = run_case("scenario", case, &what, &bytes, move || {
                Scenario::load(&p).map(|s| {
                    let _ = s.home_contacts();
                    let chain = s.space.largest().chain();
                    let scene = Arc::new(CollisionScene::new(&s.workspace));
                    let r = reachability(
                        &chain,
                        &scene,
                        &s.workspace.tasks,
                        &quick_planner(&s.planner),
                        s.seed,
                        0,
                    );
                    assert!((0.0..=1.0).contains(&r.reachability));
                })
            });
            if let Err(e) = result {
                assert_one_line("scenario", case, &what, &e.to_string(), &path);
            }
            if k % 16 == 0 {
                run_binary(
                    "scenario",
                    case,
                    &what,
                    &["check".as_ref(), path.as_os_str()],
                );
            }
        }
    }
}

/// A scenario that uses the mesh at `mesh` with `representation`.
fn mesh_scenario(mesh: &Path, representation: &str) -> String {
    format!(
        "[robot]\nlinks = 2\nuniform = {{ a = 0.3, axes = {{ ry = {{ min = -1.0, max = 1.0 }} }} }}\n\n\
         [[obstacle]]\nshape = \"mesh\"\nfile = \"{}\"\nrepresentation = \"{representation}\"\n\
         position = [5.0, 0.0, 0.0]\nscale = 0.1\n\n[[task]]\npoint = [0.5, 0.0, 0.1]\n",
        mesh.display()
    )
}

fn fuzz_mesh(name: &str, cases: usize, seed: u64, text: bool, stl: bool) {
    let dir = tempfile::tempdir().unwrap();
    let original = std::fs::read(repo(&format!("meshes/{name}"))).unwrap();
    let ext = Path::new(name).extension().unwrap().to_str().unwrap();
    let mut m = Mutator::new(seed);
    for case in 0..cases {
        let (bytes, what) = m.mutate(&original, text, stl);
        let path = dir.path().join(format!("case{case}.{ext}"));
        std::fs::write(&path, &bytes).unwrap();
        let p = path.clone();
        let decompose = case % 25 == 0;
        let result = run_case(name, case, &what, &bytes, move || {
            load_mesh(&p).map(|mesh| {
                let _ = mesh.to_convex_hull();
                let _ = mesh.to_parry_trimesh();
                if decompose {
                    let _ = mesh.to_convex_decomposition();
                }
            })
        });
        if let Err(e) = result {
            assert_one_line(name, case, &what, &e.to_string(), &path);
        }
        if case % 20 == 0 {
            let scenario = dir.path().join(format!("case{case}.toml"));
            std::fs::write(&scenario, mesh_scenario(&path, "hull")).unwrap();
            run_binary(name, case, &what, &["check".as_ref(), scenario.as_os_str()]);
        }
    }
}

#[test]
fn mutated_binary_stl() {
    fuzz_mesh("glovebox.stl", 300, 2, false, true);
}

#[test]
fn mutated_ascii_stl() {
    fuzz_mesh("vessel.stl", 150, 3, true, false);
}

#[test]
fn mutated_obj() {
    fuzz_mesh("pipe_bundle.obj", 200, 4, true, false);
}

/// The largest design of paper-2d, as design JSON and wrapped as a `best.json`.
fn design_json() -> (String, String) {
    let s = Scenario::load(&repo("examples/scenarios/paper-2d.toml")).unwrap();
    let d = s.space.largest();
    let json = d.to_json();
    let best = format!("{{\"design\": {json}, \"cost\": 1.0, \"reachability\": 1.0}}");
    (json, best)
}

#[test]
fn mutated_designs() {
    let dir = tempfile::tempdir().unwrap();
    let s = Arc::new(Scenario::load(&repo("examples/scenarios/paper-2d.toml")).unwrap());
    let scene = Arc::new(CollisionScene::new(&s.workspace));
    let (json, best) = design_json();
    let mut m = Mutator::new(5);
    let mut case = 0;
    for original in [json, best] {
        for k in 0..250 {
            case += 1;
            let (bytes, what) = m.mutate(original.as_bytes(), true, false);
            let path = dir.path().join(format!("case{case}.json"));
            std::fs::write(&path, &bytes).unwrap();
            let (p, s, scene) = (path.clone(), s.clone(), scene.clone());
            let urdf = dir.path().join(format!("case{case}.urdf"));
            let result = run_case("design", case, &what, &bytes, move || {
                Design::load(&p).map(|d| {
                    let chain = d.chain();
                    let r = reachability(
                        &chain,
                        &scene,
                        &s.workspace.tasks,
                        &quick_planner(&s.planner),
                        1,
                        0,
                    );
                    assert!(r.targets.iter().all(|t| !t.error.is_nan() || !t.reached));
                    kinsynth::export::write_urdf(&d, &urdf)
                })
            });
            match result {
                Err(e) => assert_one_line("design", case, &what, &e.to_string(), &path),
                Ok(Err(e)) => panic!("design case {case} ({what}): export failed: {e}"),
                Ok(Ok(())) => {}
            }
            if k % 25 == 0 {
                let out = dir.path().join(format!("case{case}-bin.urdf"));
                run_binary(
                    "design",
                    case,
                    &what,
                    &[
                        "urdf".as_ref(),
                        path.as_os_str(),
                        "-o".as_ref(),
                        out.as_os_str(),
                    ],
                );
            }
        }
    }
}

/// Mutants of the bundled robot `robots/NAME`, written beside a `meshes` link (so that its
/// relative and `package://` mesh paths resolve), imported with their bodies as `reach --urdf`
/// does, and planned with among the UR5 cell's tasks: with its obstacles when `obstacles`,
/// else in the empty cell (where a robot whose home pose touches the cell still plans).
fn fuzz_urdf(name: &str, cases: usize, seed: u64, obstacles: bool) {
    let (dir, _) = layout();
    let robots = dir.path().join("examples/robots");
    std::fs::create_dir_all(&robots).unwrap();
    let cell = repo("examples/scenarios/ur5-cell.toml");
    let mut s = Scenario::load(&cell).unwrap();
    if !obstacles {
        s.workspace.obstacles.clear();
    }
    let s = Arc::new(s);
    let scene = Arc::new(CollisionScene::new(&s.workspace));
    let original = std::fs::read(repo(&format!("examples/robots/{name}"))).unwrap();
    // The unmutated robot imports and plans: the mutants start from something usable.
    let options = kinsynth::import::ImportOptions::default();
    let plain = robots.join(name);
    std::fs::write(&plain, &original).unwrap();
    let r = kinsynth::import::load_robot(&plain, None, None, None, 4, &options).unwrap();
    let report = reachability_of(
        &r.urdf.chain,
        Arc::new(r.body),
        &scene,
        &s.workspace.tasks,
        &quick_planner(&s.planner),
        1,
        0,
    );
    assert!(
        report.reachability > 0.0,
        "{name} reaches nothing unmutated"
    );
    let mut m = Mutator::new(seed);
    for case in 0..cases {
        let (bytes, what) = m.mutate(&original, true, false);
        let what = format!("{name}: {what}");
        let path = robots.join(format!("case{case}.urdf"));
        std::fs::write(&path, &bytes).unwrap();
        let (p, s, scene) = (path.clone(), s.clone(), scene.clone());
        let result = run_case("urdf", case, &what, &bytes, move || {
            let options = kinsynth::import::ImportOptions::default();
            kinsynth::import::load_robot(&p, None, None, None, 4, &options).map(|r| {
                let report = reachability_of(
                    &r.urdf.chain,
                    Arc::new(r.body),
                    &scene,
                    &s.workspace.tasks,
                    &quick_planner(&s.planner),
                    1,
                    0,
                );
                assert!((0.0..=1.0).contains(&report.reachability));
            })
        });
        if let Err(e) = result {
            assert_one_line("urdf", case, &what, &e.to_string(), &path);
        }
        if case % 25 == 0 {
            run_binary(
                "urdf",
                case,
                &what,
                &[
                    "reach".as_ref(),
                    cell.as_os_str(),
                    "--urdf".as_ref(),
                    path.as_os_str(),
                ],
            );
        }
    }
}

#[test]
fn mutated_urdf() {
    fuzz_urdf("ur5.urdf", 400, 6, true);
}

/// The URDF robot whose bodies are meshes (STL and COLLADA, by relative and `package://`
/// paths), in the empty cell: its home pose touches the UR5 cell's beam.
#[cfg(unix)]
#[test]
fn mutated_mesh_urdf() {
    fuzz_urdf("mesh_arm.urdf", 120, 8, false);
}

/// A finished short run of paper-2d: its directory holds `checkpoint.json` and `best.json`.
fn short_run() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("paper-2d.toml");
    std::fs::copy(repo("examples/scenarios/paper-2d.toml"), &scenario).unwrap();
    let out = dir.path().join("run");
    let o = Command::new(BIN)
        .arg("optimize")
        .arg(&scenario)
        .args(["--evaluations", "40", "--seed", "2", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    dir
}

#[test]
fn mutated_checkpoints() {
    let run = short_run();
    let original = std::fs::read(run.path().join("run/checkpoint.json")).unwrap();
    let mut m = Mutator::new(7);
    for case in 0..300 {
        let (bytes, what) = m.mutate(&original, true, false);
        let dir = run.path().join(format!("case{case}"));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("checkpoint.json");
        std::fs::write(&path, &bytes).unwrap();
        let d = dir.clone();
        let result = run_case("checkpoint", case, &what, &bytes, move || {
            Runner::read_checkpoint(&d).map(|_| ())
        });
        if let Err(e) = result {
            assert_one_line("checkpoint", case, &what, &e.to_string(), &path);
        }
        if case % 30 == 0 {
            run_binary(
                "checkpoint",
                case,
                &what,
                &[
                    "optimize".as_ref(),
                    "--quiet".as_ref(),
                    "--resume".as_ref(),
                    dir.as_os_str(),
                ],
            );
        }
    }
}

/// A checkpoint's table given as an array is refused, naming the field, rather than read as
/// the struct's fields in order (an empty array as every default).
#[test]
fn regression_checkpoint_table_given_as_array_is_refused() {
    let run = short_run();
    let dir = run.path().join("run");
    let path = dir.join("checkpoint.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    v["planner"] = serde_json::json!([]);
    std::fs::write(&path, v.to_string()).unwrap();
    let e = Runner::read_checkpoint(&dir).unwrap_err().to_string();
    assert_one_line("checkpoint", 0, "planner = []", &e, &path);
    assert!(
        e.contains("checkpoint.json: planner: invalid type: sequence, expected struct"),
        "{e}"
    );
    let o = Command::new(BIN)
        .args(["optimize", "--quiet", "--resume"])
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.lines().count() == 1 && stderr.contains("planner: invalid type: sequence"),
        "{stderr}"
    );
}

// Regression tests: crash cases found by the fuzzer (and by hand), kept by name.

/// Writes `text` as `name` into a new temporary directory.
fn file(name: &str, text: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    (dir, p)
}

/// urdf-rs reports a vector with a line break inside as a message over two lines.
#[test]
fn regression_urdf_vector_split_by_a_line_break_gives_one_line() {
    let (_dir, p) = file(
        "robot.urdf",
        b"<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>\
          <joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\
          <origin xyz=\"0 -0.08 -0.0000\n00054\"/><axis xyz=\"0 0 1\"/>\
          <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint></robot>",
    );
    let e = kinsynth::import::load_chain(&p, None, None, None, 4)
        .unwrap_err()
        .to_string();
    assert_one_line("urdf", 0, "regression", &e, &p);
    assert!(e.contains("4 numbers, expected 3"), "{e}");
}

/// A URDF robot whose link `link3_dh` has the collision cylinder `line` (the bundled UR5, with
/// that element's line replaced), written beside nothing else.
fn ur5_with(line: usize, from: &str, to: &str) -> (tempfile::TempDir, PathBuf) {
    let text = std::fs::read_to_string(repo("examples/robots/ur5.urdf")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    assert!(lines[line - 1].contains(from), "{}", lines[line - 1]);
    lines[line - 1] = lines[line - 1].replace(from, to);
    file("robot.urdf", lines.join("\n").as_bytes())
}

#[test]
fn regression_urdf_collision_values_are_checked() {
    let options = kinsynth::import::ImportOptions::default();
    let load =
        |p: &Path| kinsynth::import::load_robot(p, None, None, None, 4, &options).map(|r| r.kind);
    // A negative or non-finite cylinder length reached parry's cylinder, which panics on a
    // negative one; a NaN origin gave NaN bodies.
    // A negative sphere radius beside larger ones (the chain's capsule radius is the largest)
    // made a body smaller than nothing.
    let (cylinder, sphere) = ("link3_body0", "link3_body0_start");
    for (line, from, to, element, says) in [
        (
            114,
            "length=\"0.425\"",
            "length=\"-1\"",
            cylinder,
            "<cylinder length=\"-1\">",
        ),
        (
            114,
            "length=\"0.425\"",
            "length=\"nan\"",
            cylinder,
            "<cylinder length=\"nan\">: every value must be a finite number",
        ),
        (
            112,
            "xyz=\"0.2125 0 0\"",
            "xyz=\"nan 0 0\"",
            cylinder,
            "<origin xyz=\"nan 0 0\">: every value must be a finite number",
        ),
        (
            120,
            "radius=\"0.05\"",
            "radius=\"-5\"",
            sphere,
            "<sphere radius=\"-5\">",
        ),
        (
            112,
            "rpy=\"0 -1.5707963267948966 0\"",
            "rpy=\"0 2000 0\"",
            cylinder,
            "<origin rpy=\"0 2000 0\">",
        ),
    ] {
        let (_dir, p) = ur5_with(line, from, to);
        let e = load(&p).unwrap_err().to_string();
        assert_one_line("urdf", line, to, &e, &p);
        assert!(
            e.contains("link 'link3_dh'")
                && e.contains(&format!("<collision name=\"{element}\">"))
                && e.contains(says),
            "{e}"
        );
        run_binary(
            "urdf",
            line,
            to,
            &[
                "reach".as_ref(),
                repo("examples/scenarios/ur5-cell.toml").as_os_str(),
                "--urdf".as_ref(),
                p.as_os_str(),
            ],
        );
    }
    // -0 is 0: a cylinder of no length, not a panic.
    let (_dir, p) = ur5_with(114, "length=\"0.425\"", "length=\"-0\"");
    assert_eq!(load(&p).unwrap(), kinsynth::import::BodyKind::Solids);
}

/// An SRDF for the bundled UR5: its adjacent links' pairs, as a setup assistant writes them.
const UR5_SRDF: &str = r#"<?xml version="1.0"?>
<robot name="ur5">
  <disable_collisions link1="base_link" link2="link1" reason="Adjacent"/>
  <disable_collisions link1="link1" link2="link2_dh" reason="Adjacent"/>
  <disable_collisions link1="link2" link2="link3_dh" reason="Adjacent"/>
  <disable_collisions link1="link3" link2="link4_dh" reason="Default"/>
  <disable_collisions link1="link4" link2="link6" reason="Never"/>
  <disable_collisions link1="link5" link2="tool0"/>
</robot>
"#;

#[test]
fn mutated_srdf() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = repo("examples/robots/ur5.urdf");
    let cell = repo("examples/scenarios/ur5-cell.toml");
    let original = UR5_SRDF.as_bytes();
    // The unmutated file is accepted.
    let options = |srdf: &Path| kinsynth::import::ImportOptions {
        srdf: Some(srdf.to_path_buf()),
        ..Default::default()
    };
    let plain = dir.path().join("ur5.srdf");
    std::fs::write(&plain, original).unwrap();
    kinsynth::import::load_robot(&urdf, None, None, None, 4, &options(&plain)).unwrap();
    let mut m = Mutator::new(9);
    for case in 0..300 {
        let (bytes, what) = m.mutate(original, true, false);
        let path = dir.path().join(format!("case{case}.srdf"));
        std::fs::write(&path, &bytes).unwrap();
        let (u, o) = (urdf.clone(), options(&path));
        let result = run_case("srdf", case, &what, &bytes, move || {
            kinsynth::import::load_robot(&u, None, None, None, 4, &o).map(|r| r.body.len())
        });
        if let Err(e) = result {
            assert_one_line("srdf", case, &what, &e.to_string(), &path);
        }
        if case % 25 == 0 {
            run_binary(
                "srdf",
                case,
                &what,
                &[
                    "reach".as_ref(),
                    cell.as_os_str(),
                    "--urdf".as_ref(),
                    urdf.as_os_str(),
                    "--srdf".as_ref(),
                    path.as_os_str(),
                ],
            );
        }
    }
}

/// `DIR/robot.urdf`: a robot of one revolute joint whose moving link's body is the mesh `mesh`
/// (a path relative to `DIR`).
fn one_link_robot(dir: &Path, mesh: &str) -> PathBuf {
    let robot = dir.join("robot.urdf");
    std::fs::write(
        &robot,
        format!(
            "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"><collision><geometry>\
             <mesh filename=\"{mesh}\"/></geometry></collision></link>\
             <joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\
             <axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>\
             </joint></robot>"
        ),
    )
    .unwrap();
    robot
}

/// `depth` nested elements inside `open` … `close`.
fn nested(open: &str, depth: usize, close: &str) -> String {
    format!(
        "{open}{}{}{close}",
        "<a>".repeat(depth),
        "</a>".repeat(depth)
    )
}

#[test]
fn regression_deeply_nested_srdf_and_collada_give_one_line() {
    // 20,000 nested elements overflowed the stack of the XML reader (SRDF) and of the mesh
    // loader (COLLADA): a crash instead of an error.
    let dir = tempfile::tempdir().unwrap();
    let urdf = repo("examples/robots/ur5.urdf");
    let srdf = dir.path().join("deep.srdf");
    std::fs::write(&srdf, nested("<robot>", 20_000, "</robot>")).unwrap();
    let options = kinsynth::import::ImportOptions {
        srdf: Some(srdf.clone()),
        ..Default::default()
    };
    let e = kinsynth::import::load_robot(&urdf, None, None, None, 4, &options)
        .unwrap_err()
        .to_string();
    assert_one_line("srdf", 0, "deep", &e, &srdf);
    assert!(e.contains("nested more than 64 deep"), "{e}");

    // A one-link robot whose body is a COLLADA mesh beside it.
    let dae = |depth: usize| {
        nested(
            "<?xml version=\"1.0\"?><COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">",
            depth,
            "</COLLADA>",
        )
    };
    let robot = one_link_robot(dir.path(), "deep.dae");
    let load = || {
        let options = kinsynth::import::ImportOptions::default();
        kinsynth::import::load_robot(&robot, None, None, None, 4, &options)
            .unwrap_err()
            .to_string()
    };
    std::fs::write(dir.path().join("deep.dae"), dae(20_000)).unwrap();
    let e = load();
    assert_one_line("collada", 0, "deep", &e, &robot);
    assert!(
        e.contains("deep.dae") && e.contains("nested more than 256 deep"),
        "{e}"
    );
    // At the limit it is read (on this test thread's stack) and refused for what it lacks.
    std::fs::write(dir.path().join("deep.dae"), dae(250)).unwrap();
    let e = load();
    assert!(e.contains("deep.dae") && e.contains("no triangles"), "{e}");
}

/// A COLLADA file of one triangle, valid as written; faults the COLLADA reader panics on are
/// put into it one at a time.
const TRIANGLE_DAE: &str = r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<library_geometries><geometry id="g"><mesh>
<source id="p"><float_array id="pa" count="9">0 0 0 1 0 0 0 1 0</float_array>
<technique_common><accessor source="#pa" count="3" stride="3"><param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
<triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="s"><node><instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
<scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"##;

#[test]
fn collada_faults_the_reader_panics_on_are_named() {
    // Each of these made the COLLADA reader panic; the error said only that it failed.
    let dir = tempfile::tempdir().unwrap();
    let robot = one_link_robot(dir.path(), "m.dae");
    let load = |text: &str| {
        std::fs::write(dir.path().join("m.dae"), text).unwrap();
        let options = kinsynth::import::ImportOptions::default();
        kinsynth::import::load_robot(&robot, None, None, None, 4, &options).map(|_| ())
    };
    load(TRIANGLE_DAE).expect("the unmutated file is read");
    for (from, to, expected) in [
        (
            r##"<input semantic="VERTEX" source="#v""##,
            r##"<input semantic="VERTEX" source="#zz""##,
            r##"<input source="#zz">: no element has that id"##,
        ),
        (
            r##"<input semantic="POSITION" source="#p""##,
            r##"<input semantic="POSITION" source="#pa""##,
            r##"<input source="#pa">: names a <float_array>, expected a <source>"##,
        ),
        (
            r##"<input semantic="VERTEX" source="#v""##,
            r##"<input semantic="VERTEX" source="#p""##,
            "expected the <vertices> of its own <mesh>",
        ),
        (
            r##"accessor source="#pa""##,
            r##"accessor source="#g""##,
            "names a <geometry>, expected an array",
        ),
        (
            r##"stride="3""##,
            r##"stride="0""##,
            r##"<accessor stride="0">: the stride must be at least 1"##,
        ),
        (
            r##"name="Y" type="float""##,
            r##"name="Y" type="int""##,
            r##"<source id="p"> (POSITION): needs an <accessor> of stride 3 or more"##,
        ),
        (
            r##"count="3" stride="3""##,
            r##"count="4" stride="3""##,
            "its accessor reads 4 × 3 values, its array holds 9",
        ),
        (
            "<p>0 1 2</p>",
            "<p>0 1 3</p>",
            "<triangles>: vertex index 3, but its <vertices> has 3 positions",
        ),
    ] {
        assert!(TRIANGLE_DAE.contains(from), "{from}");
        let e = load(&TRIANGLE_DAE.replacen(from, to, 1))
            .unwrap_err()
            .to_string();
        assert_one_line("collada", 0, to, &e, &robot);
        assert!(e.contains("m.dae") && e.contains(expected), "{to}: {e}");
    }
}

#[test]
fn mutated_reach_reports() {
    // A reachability report with paths and the planner's tree, as `view --reach` reads it.
    let dir = tempfile::tempdir().unwrap();
    let scenario = repo("examples/scenarios/paper-2d.toml");
    let json = dir.path().join("reach.json");
    let o = Command::new(BIN)
        .arg("reach")
        .arg(&scenario)
        .arg("--json")
        .arg(&json)
        .arg("--tree")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let original = std::fs::read(&json).unwrap();
    let s = Arc::new(Scenario::load(&scenario).unwrap());
    let dof = s.space.largest().chain().dof();
    let tasks = s.workspace.tasks.clone();
    kinsynth::export::view::load_reach(&json, &tasks, dof).unwrap();
    let mut m = Mutator::new(10);
    for case in 0..250 {
        let (bytes, what) = m.mutate(&original, true, false);
        let path = dir.path().join(format!("case{case}.json"));
        std::fs::write(&path, &bytes).unwrap();
        let (p, t) = (path.clone(), tasks.clone());
        let result = run_case("reach.json", case, &what, &bytes, move || {
            kinsynth::export::view::load_reach(&p, &t, dof).map(|r| r.targets.len())
        });
        if let Err(e) = result {
            assert_one_line("reach.json", case, &what, &e.to_string(), &path);
        }
        if case % 25 == 0 {
            let html = dir.path().join(format!("case{case}.html"));
            run_binary(
                "reach.json",
                case,
                &what,
                &[
                    "view".as_ref(),
                    scenario.as_os_str(),
                    "--reach".as_ref(),
                    path.as_os_str(),
                    "-o".as_ref(),
                    html.as_os_str(),
                ],
            );
        }
    }
}

#[test]
fn mutated_collada_meshes() {
    // The mesh arm with its COLLADA mesh of link 2 mutated, imported with its bodies.
    let dir = tempfile::tempdir().unwrap();
    let robots = dir.path().join("examples/robots");
    let arm = dir.path().join("meshes/arm");
    std::fs::create_dir_all(&robots).unwrap();
    std::fs::create_dir_all(&arm).unwrap();
    for e in std::fs::read_dir(repo("meshes/arm")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), arm.join(e.file_name())).unwrap();
    }
    let urdf = robots.join("mesh_arm.urdf");
    std::fs::copy(repo("examples/robots/mesh_arm.urdf"), &urdf).unwrap();
    let load = |u: &Path| {
        let options = kinsynth::import::ImportOptions::default();
        kinsynth::import::load_robot(u, None, None, None, 4, &options).map(|r| r.body.len())
    };
    load(&urdf).unwrap();
    let target = arm.join("link2.dae");
    let original = std::fs::read(&target).unwrap();
    let mut m = Mutator::new(11);
    for case in 0..200 {
        let (bytes, what) = m.mutate(&original, true, false);
        std::fs::write(&target, &bytes).unwrap();
        let u = urdf.clone();
        let result = run_case("link2.dae", case, &what, &bytes, move || load(&u));
        if let Err(e) = result {
            assert_one_line("link2.dae", case, &what, &e.to_string(), &urdf);
        }
    }
}

#[test]
fn regression_collada_sizes_and_name_arrays_are_checked_before_reading() {
    // The mesh reader reserved memory for what a file declares (`count`, input offsets) and
    // aborted on 336 GB; on a <Name_array> in a mesh source it never ended; on a missing
    // source it panicked. Each is now a one-line error naming the URDF, the link and the mesh.
    let dir = tempfile::tempdir().unwrap();
    let robot = one_link_robot(dir.path(), "m.dae");
    let original = std::fs::read_to_string(repo("meshes/arm/link2.dae")).unwrap();
    let load = |edits: &[(&str, &str)]| {
        let mut text = original.clone();
        for (from, to) in edits {
            assert!(text.contains(from), "{from}");
            text = text.replace(from, to);
        }
        std::fs::write(dir.path().join("m.dae"), &text).unwrap();
        let r = robot.clone();
        run_case("collada", 0, "edit", text.as_bytes(), move || {
            let options = kinsynth::import::ImportOptions::default();
            kinsynth::import::load_robot(&r, None, None, None, 4, &options).map(|r| r.body.len())
        })
    };
    assert_eq!(load(&[]).unwrap(), 1);
    for (edits, says) in [
        (
            &[(
                "<triangles count=\"28\">",
                "<triangles count=\"28000000000\">",
            )][..],
            "more indices than its <p> elements hold",
        ),
        (
            &[("offset=\"0\"", "offset=\"4000000000\"")],
            "<input offset=\"4000000000\"> in <triangles>",
        ),
        (
            &[("count=\"48\"", "count=\"4000000000\"")],
            "more values than the element holds",
        ),
        (
            &[
                ("<float_array", "<Name_array"),
                ("</float_array>", "</Name_array>"),
            ],
            "<Name_array> with values in a geometry",
        ),
        (
            &[("source=\"#link2-positions\"", "source=\"#nowhere\"")],
            "<input source=\"#nowhere\">: no element has that id",
        ),
        (
            &[("offset=\"0\"", "offset=\"-1\"")],
            "<input offset=\"-1\">: not a whole number",
        ),
    ] {
        let to = edits[0].1;
        let e = match load(edits) {
            Ok(n) => panic!("{to}: accepted, {n} bodies"),
            Err(e) => e.to_string(),
        };
        assert_one_line("collada", 0, to, &e, &robot);
        assert!(e.contains("m.dae") && e.contains(says), "{to}: {e}");
    }
}

#[test]
fn regression_urdf_mesh_scale_and_box_size_are_checked() {
    let original = std::fs::read_to_string(repo("examples/robots/mesh_arm.urdf")).unwrap();
    for (from, to, link, says) in [
        (
            "link2.dae\" scale=\"1 1 1\"",
            "link2.dae\" scale=\"0 1 1\"",
            "link2",
            "<collision> #1 <mesh scale=\"0 1 1\">: every factor must be finite, not zero",
        ),
        (
            "<box size=\"0.06 0.02 0.08\"/>",
            "<box size=\"0.06 -0.02 0.08\"/>",
            "link6",
            "<collision name=\"gripper\"> <box size=\"-0.02\">: must be finite, not negative",
        ),
    ] {
        assert!(original.contains(from), "{from}");
        let (_dir, p) = file("robot.urdf", original.replace(from, to).as_bytes());
        let options = kinsynth::import::ImportOptions::default();
        let e = kinsynth::import::load_robot(&p, None, None, None, 4, &options)
            .unwrap_err()
            .to_string();
        assert_one_line("urdf", 0, to, &e, &p);
        assert!(
            e.contains(&format!("link '{link}'")) && e.contains(says),
            "{e}"
        );
    }
}
