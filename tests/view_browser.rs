//! The browser report in a real browser: headless Chromium opens each page from `file://` in
//! its self-test mode (`?selftest=1`), which writes what it drew (`window.kinsynthView`), the
//! canvas's pixel statistics, an animation of every reached path and every console error into
//! the DOM; these tests read the dumped DOM and check it against the inputs.
//!
//! The browser: `$KINSYNTH_CHROMIUM`, else `chromium`, `chromium-browser` or `google-chrome` on
//! the `PATH`. Without one these tests fail, saying so (`.ci/run` installs Debian's `chromium`).
//! Screenshots are kept under `target/tmp/view/`.

use kinsynth::Scenario;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

const BIN: &str = env!("CARGO_BIN_EXE_kinsynth");
/// Largest report of a bundled scenario.
const MAX_REPORT_BYTES: u64 = 3 << 20;

/// One browser at a time: each is heavy on a small machine.
static BROWSER: Mutex<()> = Mutex::new(());

fn manifest(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The Chromium binary, or a panic that says none was found and how to get one.
fn chromium() -> PathBuf {
    let candidates: Vec<PathBuf> = match std::env::var_os("KINSYNTH_CHROMIUM") {
        Some(p) => vec![PathBuf::from(p)],
        None => std::env::var_os("PATH")
            .map(|path| {
                std::env::split_paths(&path)
                    .flat_map(|d| {
                        ["chromium", "chromium-browser", "google-chrome"].map(|n| d.join(n))
                    })
                    .collect()
            })
            .unwrap_or_default(),
    };
    candidates.into_iter().find(|p| p.is_file()).unwrap_or_else(|| {
        panic!(
            "no browser found for the browser tests: install Debian's chromium \
             (apt-get install -y chromium; .ci/run does) or set KINSYNTH_CHROMIUM to a Chromium binary"
        )
    })
}

fn headless(profile: &Path) -> Command {
    let mut c = Command::new(chromium());
    c.args([
        "--headless=new",
        "--disable-gpu",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--no-sandbox",
        "--no-first-run",
        "--disable-extensions",
        "--disable-dev-shm-usage",
        "--hide-scrollbars",
        "--window-size=1280,800",
    ])
    .arg(format!("--user-data-dir={}", profile.display()));
    c
}

fn file_url(page: &Path, query: &str) -> String {
    format!("file://{}{query}", page.canonicalize().unwrap().display())
}

/// The self-test result of `page`: the JSON the page wrote into `#kinsynth-selftest`.
fn selftest(page: &Path) -> serde_json::Value {
    let _one = BROWSER.lock().unwrap_or_else(|e| e.into_inner());
    let profile = tempfile::tempdir().unwrap();
    let o = headless(profile.path())
        .arg("--virtual-time-budget=30000")
        .arg("--dump-dom")
        .arg(file_url(page, "?selftest=1"))
        .output()
        .expect("chromium runs");
    let dom = String::from_utf8_lossy(&o.stdout);
    let start = dom
        .find("<pre id=\"kinsynth-selftest\">")
        .unwrap_or_else(|| {
            panic!(
                "no self-test block in the DOM of {}; chromium said: {}",
                page.display(),
                String::from_utf8_lossy(&o.stderr)
            )
        })
        + "<pre id=\"kinsynth-selftest\">".len();
    let end = start + dom[start..].find("</pre>").unwrap();
    let text = dom[start..end]
        .replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    serde_json::from_str(&text).unwrap_or_else(|e| {
        panic!(
            "the page of {} wrote no self-test result ({e}): {text:?}; chromium said: {}",
            page.display(),
            String::from_utf8_lossy(&o.stderr)
        )
    })
}

/// Saves a screenshot of `page` as `target/tmp/view/{name}.png` and returns its path.
fn screenshot(page: &Path, name: &str) -> PathBuf {
    let _one = BROWSER.lock().unwrap_or_else(|e| e.into_inner());
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("view");
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join(format!("{name}.png"));
    let _ = std::fs::remove_file(&png);
    let profile = tempfile::tempdir().unwrap();
    let o = headless(profile.path())
        .arg("--virtual-time-budget=30000")
        .arg(format!("--screenshot={}", png.display()))
        .arg(file_url(page, ""))
        .output()
        .expect("chromium runs");
    let bytes = std::fs::read(&png).unwrap_or_else(|e| {
        panic!(
            "no screenshot {} ({e}); chromium said: {}",
            png.display(),
            String::from_utf8_lossy(&o.stderr)
        )
    });
    assert!(bytes.starts_with(b"\x89PNG"), "{} is a PNG", png.display());
    png
}

fn run(args: &[&std::ffi::OsStr]) -> String {
    let o = Command::new(BIN).args(args).output().unwrap();
    assert!(
        o.status.success(),
        "kinsynth {:?}: {}",
        args,
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn close(a: &serde_json::Value, b: &[f64], tol: f64) -> bool {
    let a: Vec<f64> = a
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

fn dist(a: &serde_json::Value, b: &[f64]) -> f64 {
    a.as_array()
        .unwrap()
        .iter()
        .zip(b)
        .map(|(x, y)| (x.as_f64().unwrap() - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Checks a self-test result against the scenario and the reach report the page was made of.
fn check_page(
    result: &serde_json::Value,
    scenario: &Scenario,
    reach: &serde_json::Value,
    links: usize,
) {
    let errors = result["errors"].as_array().unwrap();
    assert!(errors.is_empty(), "console errors: {errors:?}");
    let view = &result["view"];
    assert_eq!(view["ready"], true, "{view}");
    // What was drawn matches the input.
    let obstacles = view["obstacles"].as_array().unwrap();
    assert_eq!(obstacles.len(), scenario.workspace.obstacles.len());
    for (o, s) in obstacles.iter().zip(&scenario.workspace.obstacles) {
        assert_eq!(o["name"], s.name.as_str());
        assert_eq!(o["kind"], s.geometry.kind());
        assert!(o["triangles"].as_u64().unwrap() >= 12, "{o}");
        if let Some(t) = s.shape().as_trimesh() {
            assert_eq!(o["triangles"].as_u64().unwrap() as usize, t.indices().len());
        }
    }
    let tasks = view["tasks"].as_array().unwrap();
    let targets = reach["targets"].as_array().unwrap();
    assert_eq!(tasks.len(), scenario.workspace.tasks.len());
    for ((t, p), r) in tasks.iter().zip(&scenario.workspace.tasks).zip(targets) {
        assert!(close(&t["point"], &[p.x, p.y, p.z], 1e-12), "{t}");
        assert_eq!(t["reached"], r["reached"], "{t}");
    }
    assert_eq!(view["links"].as_u64().unwrap() as usize, links);
    let reached: Vec<&serde_json::Value> =
        targets.iter().filter(|t| t["reached"] == true).collect();
    let paths = view["paths"].as_array().unwrap();
    assert_eq!(paths.len(), reached.len(), "one path per reached task");
    for (p, t) in paths.iter().zip(&reached) {
        assert_eq!(p["task"], t["index"]);
        assert_eq!(
            p["points"].as_u64().unwrap() as usize,
            t["path"]["points"].as_array().unwrap().len()
        );
    }
    // The planner's tree, when the page has it: a segment from every node but the root.
    if !view["tree"].is_null() {
        let nodes = reach["nodes"].as_u64().unwrap();
        assert_eq!(
            view["tree"]["nodes"].as_u64().unwrap(),
            nodes,
            "{}",
            view["tree"]
        );
        assert_eq!(view["tree"]["edges"].as_u64().unwrap(), nodes - 1);
    }
    // The canvas is not blank: a good share of its pixels differ from the background, in
    // several colours.
    let canvas = &result["canvas"];
    assert!(canvas["width"].as_u64().unwrap() >= 400, "{canvas}");
    assert!(
        canvas["nonBackground"].as_f64().unwrap() > 0.005,
        "{canvas}"
    );
    assert!(canvas["colours"].as_u64().unwrap() >= 8, "{canvas}");
    // Playing each path moves the end effector from home to its task.
    let animations = result["animations"].as_array().unwrap();
    assert_eq!(animations.len(), reached.len());
    for (a, t) in animations.iter().zip(&reached) {
        assert_eq!(a["task"], t["index"]);
        let ee: Vec<f64> = t["end_effector"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let point: Vec<f64> = t["point"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert!(
            close(&a["end"], &ee, 1e-4),
            "task {}: the animation ends at {} but the planner's end effector is {ee:?}",
            t["index"],
            a["end"]
        );
        let tol = t["error"].as_f64().unwrap() + 1e-4;
        assert!(dist(&a["end"], &point) <= tol, "task {}: {a}", t["index"]);
        assert!(a["steps"].as_u64().unwrap() > 1, "{a}");
        assert_eq!(a["u"], 1.0);
    }
}

/// Every bundled scenario: `reach --json`, then `view --reach`, then the page in Chromium.
#[test]
fn bundled_scenarios_render_and_animate_in_chromium() {
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "drill-fixture",
        "glovebox",
        "paper-2d",
        "paper-3d",
        "pipework",
        "ur5-cell",
    ] {
        let file = manifest(&format!("examples/scenarios/{name}.toml"));
        let scenario = Scenario::load(&file).unwrap();
        let reach = dir.path().join(format!("{name}.reach.json"));
        let page = dir.path().join(format!("{name}.html"));
        run(&[
            "reach".as_ref(),
            file.as_os_str(),
            "--json".as_ref(),
            reach.as_os_str(),
            "--tree".as_ref(),
        ]);
        let out = run(&[
            "view".as_ref(),
            file.as_os_str(),
            "--reach".as_ref(),
            reach.as_os_str(),
            "-o".as_ref(),
            page.as_os_str(),
        ]);
        assert!(out.starts_with("wrote "), "{out}");
        let bytes = std::fs::metadata(&page).unwrap().len();
        assert!(bytes <= MAX_REPORT_BYTES, "{name}: {bytes} bytes");
        let reach: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&reach).unwrap()).unwrap();
        let result = selftest(&page);
        assert!(
            !result["view"]["tree"].is_null(),
            "{name}: reach --tree draws the tree"
        );
        check_page(
            &result,
            &scenario,
            &reach,
            scenario.space.largest().links.len(),
        );
        eprintln!(
            "{name}: {bytes} bytes, {} paths, canvas {:.0} % drawn",
            result["view"]["paths"].as_array().unwrap().len(),
            100.0 * result["canvas"]["nonBackground"].as_f64().unwrap()
        );
    }
}

/// `kinsynth optimize` writes `report.html`: the glove box, the tasks and the arm are drawn, no
/// console error, and an animation step moves the end effector to a task. Its screenshot is
/// kept as `target/tmp/view/glovebox-optimize.png`.
#[test]
fn optimize_writes_a_report_that_renders_in_chromium() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let file = manifest("examples/scenarios/glovebox.toml");
    run(&[
        "optimize".as_ref(),
        file.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--evaluations".as_ref(),
        "64".as_ref(),
        "--recheck-seeds".as_ref(),
        "0".as_ref(),
        "--quiet".as_ref(),
    ]);
    let page = out.join("report.html");
    let bytes = std::fs::metadata(&page).unwrap().len();
    assert!(bytes <= MAX_REPORT_BYTES, "{bytes} bytes");
    let scenario = Scenario::load(&file).unwrap();
    let reach: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("reach.json")).unwrap()).unwrap();
    let best: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("best.json")).unwrap()).unwrap();
    let result = selftest(&page);
    let links = best["design"]["links"].as_array().unwrap().len();
    check_page(&result, &scenario, &reach, links);
    let view = &result["view"];
    assert!(
        !view["tree"].is_null(),
        "the report draws the planner's tree"
    );
    assert_eq!(view["obstacles"][0]["name"], "glovebox");
    assert_eq!(view["obstacles"][0]["representation"], "trimesh");
    assert!(
        view["bodies"]["segments"].as_u64().unwrap() > 0,
        "the arm is drawn"
    );
    assert!(
        !view["paths"].as_array().unwrap().is_empty(),
        "some task is reached: {reach}"
    );
    // The run's settings as best.json has them.
    assert_eq!(view["run"]["seed"], best["seed"]);
    assert_eq!(view["run"]["optimizer"], best["optimizer"]);
    assert_eq!(view["run"]["checker"], best["checker"]);
    assert_eq!(view["run"]["l_max"], best["l_max"]);
    assert_eq!(view["design"]["links"].as_u64().unwrap() as usize, links);
    // At rest the page shows the first reached task's pose: its end effector is at that task.
    let first = &view["paths"][0]["task"];
    let target = &reach["targets"][first.as_u64().unwrap() as usize];
    let ee: Vec<f64> = target["end_effector"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(close(&view["endEffector"], &ee, 1e-4), "{view}");
    screenshot(&page, "glovebox-optimize");
    // The run's report plots its history; a page of its best.json (`view --design`), which
    // holds none, shows the plot beside it, and without one says where the history is.
    let rows = std::fs::read_to_string(out.join("history.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert_eq!(view["run"]["plotted"], true);
    assert_eq!(
        view["run"]["convergence"],
        format!("{rows} rows of history.csv.")
    );
    let best_page = dir.path().join("best.html");
    let best_file = out.join("best.json");
    let view_best = || {
        run(&[
            "view".as_ref(),
            file.as_os_str(),
            "--design".as_ref(),
            best_file.as_os_str(),
            "-o".as_ref(),
            best_page.as_os_str(),
        ]);
        selftest(&best_page)["view"]["run"].clone()
    };
    let shown = view_best();
    assert_eq!(shown["plotted"], true, "{shown}");
    assert!(
        shown["convergence"]
            .as_str()
            .unwrap()
            .contains("the convergence.svg beside the best.json"),
        "{shown}"
    );
    std::fs::remove_file(out.join("convergence.svg")).unwrap();
    let shown = view_best();
    assert_eq!(shown["plotted"], false, "{shown}");
    assert!(
        shown["convergence"]
            .as_str()
            .unwrap()
            .contains("A best.json holds no history"),
        "{shown}"
    );
}

/// A scene with a 100,000-triangle mesh: every triangle reaches the page and it renders.
#[test]
fn a_large_mesh_is_drawn_whole() {
    let dir = tempfile::tempdir().unwrap();
    // A torus of 250 × 200 quads: 100,000 triangles, closed, facing out.
    let (nt, np) = (250usize, 200usize);
    let (big, small) = (0.3f32, 0.1f32);
    let vertex = |i: usize, j: usize| {
        let th = (i % nt) as f32 / nt as f32 * std::f32::consts::TAU;
        let ph = (j % np) as f32 / np as f32 * std::f32::consts::TAU;
        let w = big + small * ph.cos();
        stl_io::Vertex::new([w * th.cos(), w * th.sin(), small * ph.sin()])
    };
    let mut triangles = Vec::new();
    for i in 0..nt {
        for j in 0..np {
            let (a, b, c, d) = (
                vertex(i, j),
                vertex(i + 1, j),
                vertex(i + 1, j + 1),
                vertex(i, j + 1),
            );
            let n = stl_io::Normal::new([0.0, 0.0, 0.0]);
            triangles.push(stl_io::Triangle {
                normal: n,
                vertices: [a, b, c],
            });
            triangles.push(stl_io::Triangle {
                normal: n,
                vertices: [a, c, d],
            });
        }
    }
    assert_eq!(triangles.len(), 100_000);
    let stl = dir.path().join("torus.stl");
    stl_io::write_stl(&mut std::fs::File::create(&stl).unwrap(), triangles.iter()).unwrap();
    let text = std::fs::read_to_string(manifest("examples/scenarios/glovebox.toml"))
        .unwrap()
        .replace(
            "file = \"../../meshes/glovebox.stl\"\nrepresentation = \"trimesh\"\nposition = [0.0, 0.6, 0.0]",
            &format!("file = {:?}\nrepresentation = \"trimesh\"\nposition = [0.8, 0.8, 0.5]", stl.display().to_string()),
        );
    assert!(text.contains("torus.stl"));
    let file = dir.path().join("large.toml");
    std::fs::write(&file, text).unwrap();
    let page = dir.path().join("large.html");
    let out = run(&[
        "view".as_ref(),
        file.as_os_str(),
        "-o".as_ref(),
        page.as_os_str(),
    ]);
    assert!(out.contains("100000 mesh triangles"), "{out}");
    let result = selftest(&page);
    let errors = result["errors"].as_array().unwrap();
    assert!(errors.is_empty(), "console errors: {errors:?}");
    let o = &result["view"]["obstacles"][0];
    assert_eq!(o["triangles"], 100_000, "{o}");
    assert!(result["canvas"]["nonBackground"].as_f64().unwrap() > 0.02);
    eprintln!(
        "100,000 triangles: {} bytes, ready {:.0} ms after navigation (page clock)",
        std::fs::metadata(&page).unwrap().len(),
        result["view"]["loadMs"].as_f64().unwrap()
    );
}

/// A mesh placed many times (here the pipe bundle, 200 times on a grid) is written into the
/// page once and drawn at every place: each copy shows the bundle's triangles, the page stays
/// within a few kilobytes of the scene with one bundle, and the scene still renders.
#[test]
fn a_mesh_placed_many_times_is_written_once() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(manifest("examples/scenarios/pipework.toml")).unwrap();
    let bundle = manifest("meshes/pipe_bundle.obj");
    let one = text.replace(
        "../../meshes/",
        &format!("{}/", manifest("meshes").display()),
    );
    let mut extra = String::new();
    for k in 0..200 {
        extra += &format!(
            "\n[[obstacle]]\nname = \"copy {k}\"\nshape = \"mesh\"\nfile = {:?}\n\
             representation = \"decomposition\"\nposition = [{}, {}, 0.4]\n",
            bundle.display().to_string(),
            -3.0 + 0.3 * (k % 20) as f64,
            2.0 + 0.3 * (k / 20) as f64
        );
    }
    let many = one.replacen("[[task]]", &format!("{extra}\n[[task]]"), 1);
    let (one_bytes, many_bytes, result) = base_and_many(dir.path(), &one, &many);
    let obstacles = result["view"]["obstacles"].as_array().unwrap();
    assert_eq!(obstacles.len(), 203);
    let first = obstacles
        .iter()
        .find(|o| o["name"] == "pipe bundle")
        .unwrap();
    assert!(first["triangles"].as_u64().unwrap() > 100, "{first}");
    for o in obstacles
        .iter()
        .filter(|o| o["name"] != "vessel" && o["name"] != "floor")
    {
        assert_eq!(o["triangles"], first["triangles"], "{o}");
        assert_eq!(o["representation"], "decomposition", "{o}");
    }
    assert!(result["canvas"]["nonBackground"].as_f64().unwrap() > 0.02);
    // 200 more obstacles cost their names and poses (about 200 bytes each), not their
    // triangles (the bundle's alone are tens of kilobytes).
    assert!(
        many_bytes < one_bytes + 200 * 300,
        "{one_bytes} -> {many_bytes} bytes"
    );
}

/// Primitives travel by their dimensions and are drawn instanced: 2,000 spheres of random radii
/// and 50 each of capsules, cylinders and boxes cost about 200 bytes of page each, and the page
/// draws every one of them with the triangles of its kind.
#[test]
fn many_primitives_travel_by_their_dimensions() {
    use rand::{RngExt, SeedableRng};
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(manifest("examples/scenarios/paper-3d.toml")).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let mut extra = String::new();
    let mut kinds = Vec::new();
    for k in 0..2150 {
        let (x, y, z) = (
            rng.random_range(3.0..6.0),
            rng.random_range(-3.0..3.0),
            rng.random_range(-3.0..3.0),
        );
        let r: f64 = rng.random_range(0.02..0.06);
        let (kind, dims) = match k {
            0..2000 => ("sphere", format!("radius = {r}")),
            2000..2050 => ("capsule", format!("radius = {r}\nlength = {}", 3.0 * r)),
            2050..2100 => ("cylinder", format!("radius = {r}\nlength = {}", 2.0 * r)),
            _ => ("cuboid", format!("size = [{r}, {}, {}]", 2.0 * r, 3.0 * r)),
        };
        kinds.push(kind);
        extra += &format!(
            "[[obstacle]]\nshape = \"{kind}\"\nposition = [{x}, {y}, {z}]\nrpy = [0.3, 0.2, 0.1]\n{dims}\n\n"
        );
    }
    let base_count = Scenario::load(&manifest("examples/scenarios/paper-3d.toml"))
        .unwrap()
        .workspace
        .obstacles
        .len();
    let many = text.replacen("[[task]]", &format!("{extra}[[task]]"), 1);
    let (base_bytes, many_bytes, result) = base_and_many(dir.path(), &text, &many);
    assert_eq!(result["view"]["ready"], true);
    let obstacles = result["view"]["obstacles"].as_array().unwrap();
    assert_eq!(obstacles.len(), base_count + kinds.len());
    for (o, kind) in obstacles[base_count..].iter().zip(&kinds) {
        assert_eq!(o["kind"], *kind, "{o}");
        assert!(o["triangles"].as_u64().unwrap() >= 12, "{o}");
    }
    assert!(result["canvas"]["nonBackground"].as_f64().unwrap() > 0.02);
    assert!(
        many_bytes < base_bytes + 2150 * 250,
        "{base_bytes} -> {many_bytes} bytes"
    );
}

/// Writes the pages of `base` and `many` (scenario texts) with `kinsynth view` into `dir`, and
/// returns their sizes in bytes and the self-test result of the second (checked for console
/// errors).
fn base_and_many(dir: &Path, base: &str, many: &str) -> (u64, u64, serde_json::Value) {
    let mut bytes = Vec::new();
    for (name, text) in [("base", base), ("many", many)] {
        let file = dir.join(format!("{name}.toml"));
        std::fs::write(&file, text).unwrap();
        let page = dir.join(format!("{name}.html"));
        run(&[
            "view".as_ref(),
            file.as_os_str(),
            "-o".as_ref(),
            page.as_os_str(),
        ]);
        bytes.push(std::fs::metadata(&page).unwrap().len());
    }
    let result = selftest(&dir.join("many.html"));
    let errors = result["errors"].as_array().unwrap();
    assert!(errors.is_empty(), "console errors: {errors:?}");
    (bytes[0], bytes[1], result)
}
