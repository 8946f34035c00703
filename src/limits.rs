//! Limits on every input, in one place, and the guarded file reader that applies them.
//!
//! The figures keep the bundled and realistic scenes far inside them while making sure that no
//! input file can exhaust memory, block the program or overflow a number to infinity. Each one
//! is documented in the README's "Limits" section, and exceeding one is a one-line error that
//! names the file, the field and the value.

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// Largest scenario (TOML), design (JSON) or URDF file, in bytes (16 MiB).
pub const MAX_TEXT_FILE_BYTES: u64 = 16 << 20;
/// Largest reach report `view --reach` reads (`reach --json`, a run's `reach.json`), in bytes
/// (64 MiB: its paths carry at most [`MAX_REPORT_PATH_VALUES`] values, at most about 28 MB).
pub const MAX_REPORT_FILE_BYTES: u64 = 64 << 20;
/// Largest checkpoint file (`checkpoint.json`), in bytes (64 MiB).
pub const MAX_CHECKPOINT_BYTES: u64 = 64 << 20;
/// Largest mesh file (STL or OBJ), in bytes (256 MiB: a binary STL of 5M triangles is 250 MB).
pub const MAX_MESH_FILE_BYTES: u64 = 256 << 20;
/// Largest COLLADA (`.dae`) mesh file, in bytes (64 MiB): its XML is read into a document
/// tree of about 20 bytes per byte of file (a 256 MiB file took 5.25 GB, a 64 MiB one
/// 1.3 GB).
pub const MAX_COLLADA_FILE_BYTES: u64 = 64 << 20;
/// Deepest XML element nesting accepted in a URDF or SRDF file (either needs about 5).
pub const MAX_XML_DEPTH: usize = 64;
/// Most `<collision>` elements of an imported URDF robot between its base and tip: each is a
/// body, and the self pairs to decide and check grow with their square.
pub const MAX_COLLISION_ELEMENTS: usize = 1_000;
/// Deepest XML element nesting accepted in a COLLADA (`.dae`) mesh file (its node hierarchy
/// may nest, real files stay far below this).
pub const MAX_MESH_XML_DEPTH: usize = 256;
/// Most links of a chain: `robot.links` of a scenario, `links` of a design, moving joints of a
/// URDF chain.
pub const MAX_LINKS: usize = 64;
/// Most point colliders per link (`colliders_per_link`).
pub const MAX_COLLIDERS_PER_LINK: usize = 1000;
/// Most task points of a scenario.
pub const MAX_TASKS: usize = 10_000;
/// Most obstacles of a scenario.
pub const MAX_OBSTACLES: usize = 100_000;
/// Most triangles of one mesh file.
pub const MAX_MESH_TRIANGLES: usize = 5_000_000;
/// Most mesh triangles of the distinct meshes of a scenario together (a file placed again with
/// the same representation and scale shares the first one's shape and adds nothing). A
/// 5M-triangle `trimesh` takes about 3 GB while it is built.
pub const MAX_SCENE_MESH_TRIANGLES: usize = 5_000_000;
/// Largest magnitude of a length or coordinate, in metres: DH `a` and `d`, prismatic limits,
/// positions, task points, radii, sizes, clearance, tolerances and scaled mesh vertices.
pub const MAX_LENGTH: f64 = 1e3;
/// Largest magnitude of an angle, in radians: DH `θ` and `α`, revolute limits, `rpy`.
pub const MAX_ANGLE: f64 = 1e3;
/// Most RRT iterations per evaluation (`planner.max_iterations`, `planner.schedule`).
pub const MAX_ITERATIONS: usize = 100_000;
/// Most RRT iterations times the design's free axes: the nearest-node search scans the tree,
/// so a run that reaches nothing costs about the square of its iterations times its axes
/// (100,000 iterations of a 24-axis design: 26 s).
pub const MAX_ITERATION_AXES: usize = 2_400_000;

/// Most RRT iterations times damped-least-squares steps per extension (`planner.ik_steps`)
/// times the design's free axes: every goal-biased iteration solves inverse kinematics, each
/// step an evaluation of the kinematics and the Jacobian, so a run whose task is out of reach
/// costs about its iterations times its steps times its axes. The default 20 steps keep within
/// [`MAX_ITERATION_AXES`] alone; 10,000 steps of a 24-axis design allow 200 iterations.
pub const MAX_IK_AXIS_STEPS: usize = 20 * MAX_ITERATION_AXES;

/// The most RRT iterations a design of `axes` free axes may run with `ik_steps`
/// damped-least-squares steps per extension: [`MAX_ITERATIONS`], and fewer for a design of more
/// than 24 axes ([`MAX_ITERATION_AXES`]) or more than 20 steps ([`MAX_IK_AXIS_STEPS`]).
pub fn iteration_cap(axes: usize, ik_steps: usize) -> usize {
    let axes = axes.max(1);
    let by_search = MAX_ITERATION_AXES / axes;
    let by_ik = MAX_IK_AXIS_STEPS / axes / ik_steps.max(1);
    by_search.min(by_ik).clamp(1, MAX_ITERATIONS)
}
/// Most nodes one planner run may hold in its trees together: an iteration adds up to
/// [`crate::planning::rrt::CONNECT_STEPS`] nodes per tree when its steps are short (a large
/// `planner.lambda`) and never blocked, and the nearest-node search scans the tree, so the
/// iteration limits alone do not bound a run's work. A run that reaches it stops, as at its
/// iteration budget.
pub const MAX_TREE_NODES: usize = 100_000;

/// The most tree nodes a planner run of a design of `axes` free axes may hold:
/// [`MAX_TREE_NODES`], and fewer beyond 24 axes, as [`MAX_ITERATION_AXES`] caps iterations.
pub fn node_cap(axes: usize) -> usize {
    (MAX_ITERATION_AXES / axes.max(1)).clamp(1, MAX_TREE_NODES)
}

/// Most shape casts the `ccd` checker makes in one planner run (one body against one obstacle,
/// or one self pair, over one sub-step; against a triangle mesh, one more per triangle whose
/// bounding box comes near the moving body, the triangles the cast may test): its cost per edge
/// grows with the motion, the bodies and the triangles near them, up to 64 sub-steps of every
/// body, which the iteration limits do not see. A cast costs 7–13 µs on this machine (a 64-link
/// arm with `l_max = 100`, paper-3d, the glove box), so the limit stands for 20–40 s. A run
/// that reaches it stops, as at its iteration budget.
pub const MAX_CCD_CASTS: u64 = 3_000_000;

/// Most body tests one planner run may make: each node or edge check tests every robot body
/// against the environment and every checked self pair, so a run costs its checks times the
/// bodies and pairs, which grow with the square of a URDF robot's `<collision>` elements
/// (960 boxes: 460,000 pairs) and which the iteration limits do not see. Counted as checks
/// times (bodies + checked pairs). The largest paper-3d design (16 bodies, 91 pairs) would
/// need 37 million checks to reach it, far beyond what the iteration limits allow; 960 boxes
/// reach it after about 8,700 checks. A run that reaches it stops, as at its iteration
/// budget.
pub const MAX_BODY_TESTS: u64 = 4_000_000_000;

/// Most evaluations of the kinematics an edge checker makes in one planner run (`certified`'s
/// bisection points): a body that moves along an obstacle at a tiny constant distance needs
/// about its path length over that distance of them per edge, which the iteration limits do
/// not see. Planner runs need about 7 per edge (paper-3d at π/4), so a run of 100,000
/// iterations about a million. A run that reaches it stops, as at its iteration budget.
pub const MAX_CHECK_FK: u64 = 20_000_000;

/// Most designs' free variables a run's checkpoint holds: a GA's population or a swarm times
/// the design space's free variables, over all islands of an island job. A swarm's state
/// takes about 61 bytes per variable in `checkpoint.json` (positions, velocities and personal
/// bests), so 500,000 stay within [`MAX_CHECKPOINT_BYTES`] with room for the history: a
/// population of 10,000 over 1,024 free variables wrote 212 MB, which no resume could read.
pub const MAX_POPULATION_VARIABLES: usize = 500_000;

/// Refuses a run whose checkpoint would hold more than [`MAX_POPULATION_VARIABLES`]: `islands`
/// populations of `population` designs of `variables` free variables each (ASA keeps a few
/// designs whatever its batch: `population` is then 0).
pub fn check_population_variables(
    population: usize,
    islands: usize,
    variables: usize,
) -> crate::error::Result<()> {
    let total = population.saturating_mul(islands).saturating_mul(variables);
    if total > MAX_POPULATION_VARIABLES {
        let per = if islands > 1 {
            format!(" in each of {islands} islands")
        } else {
            String::new()
        };
        return Err(crate::error::Error::invalid(
            "optimizer.population",
            population,
            format!(
                "{population} designs{per} of {variables} free variables make {total}, more than the limit of {MAX_POPULATION_VARIABLES} a checkpoint holds"
            ),
        ));
    }
    Ok(())
}

/// Most work the "Always" rule's random sampling of self-collision may do for one robot body:
/// per sample, every body pair of the frame pairs still in question is tested by bounding
/// balls (1 unit each), and those whose balls meet are measured (64 units each: a GJK
/// distance of two boxes costs about as much as 64 ball tests). Two links of 499 interleaved
/// plates in contact almost everywhere take about 10 million units per sample: 1,000 samples
/// took 68 s, and 100,000 would have taken two hours. A sampling that reaches the limit stops,
/// and the pairs it has not decided stay checked (a few samples cannot tell a pair always in
/// contact from one in contact 90 % of the time); the SRDF and the `--urdf` commands say so,
/// and an SRDF or `allowed_collisions` can disable such pairs. The bundled arms use 100–250
/// units per sample (1.3 million at 100,000 samples for the UR5).
pub const MAX_SELF_COLLISION_WORK: u64 = 200_000_000;

/// Most path values (points times joints) a reach report carries over all its reached tasks
/// (and that `view --reach` reads). Each reached task's path runs from home through the tree,
/// so paths grow with the tree's depth: 1,000 identical tasks with `l_max = 0.001` and 100,000
/// iterations made paths of thousands of points each, a 1.3 GB report and 3.1 GB of memory.
/// Paths are kept in task order while they fit; a reached task whose path would not fit stays
/// reached and says why it has none (`path_omitted`). Each path's joint names count too, one
/// value per 8 bytes (a path carries them: 10,000 tasks of a joint named with 200,000
/// characters took 3.9 GB). A value takes up to about 56 bytes of the report (one joint per
/// point), so the paths stay within 28 MB, and a report with its `--tree` within
/// [`MAX_REPORT_FILE_BYTES`]; bundled runs carry a few thousand.
pub const MAX_REPORT_PATH_VALUES: usize = 500_000;

/// Most random configurations sampled for the allowed-collision matrix
/// (`robot.self_collision_samples`; MoveIt's setup assistant offers up to 100,000).
pub const MAX_SELF_COLLISION_SAMPLES: usize = 100_000;
/// Most damped-least-squares steps per extension (`planner.ik_steps`).
pub const MAX_IK_STEPS: usize = 10_000;
/// Most backward trees per task (`planner.postures`).
pub const MAX_POSTURES: usize = 100;
/// Largest growth factor of the iteration budget (`planner.budget_growth`).
pub const MAX_BUDGET_GROWTH: usize = 100;
/// Largest population, swarm or ASA batch (`optimizer.population`, `optimizer.asa.batch`).
pub const MAX_POPULATION: usize = 10_000;
/// Largest magnitude of any other real setting (objective weights, optimiser parameters,
/// `planner.lambda`, mesh scale factors).
pub const MAX_SETTING: f64 = 1e6;

/// Largest number of seconds a run's records may carry (`time.json`, a checkpoint's history as
/// `kinsynth merge` reads them) and the largest time limit of an experiment: 10^9 s, about 32
/// years.
pub const MAX_SECONDS: f64 = 1e9;

/// `v` is finite and `|v| ≤ bound`.
pub fn within(v: f64, bound: f64) -> bool {
    v.is_finite() && v.abs() <= bound
}

/// What kind of file system object `meta` describes, for messages.
fn kind(meta: &std::fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
    }
    "not a regular file"
}

fn check_regular(meta: &std::fs::Metadata, limit: u64) -> io::Result<()> {
    if !meta.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("not a regular file ({})", kind(meta)),
        ));
    }
    if meta.len() > limit {
        return Err(too_large(meta.len(), limit));
    }
    Ok(())
}

fn too_large(len: u64, limit: u64) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!("the file has {len} bytes, more than the limit of {limit} bytes"),
    )
}

/// Reads a whole file of at most `limit` bytes. Symbolic links are followed; the target must
/// be a regular file: devices (`/dev/zero`), FIFOs, sockets and directories are refused before
/// the file is opened, so nothing blocks. The file is opened non-blocking and checked again
/// after opening, and never more than `limit` bytes are read, even if it grows meanwhile.
pub fn read_file(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    check_regular(&std::fs::metadata(path)?, limit)?;
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file: File = options.open(path)?;
    let meta = file.metadata()?;
    check_regular(&meta, limit)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64, limit));
    }
    Ok(bytes)
}

/// [`read_file`] as UTF-8 text.
pub fn read_text(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_file(path, limit)?).map_err(|e| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "not valid UTF-8 text (at byte {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// `Err` with the message every XML input gives when its elements nest deeper than `limit`
/// ([`xml_depth`]), checked before any parser (which may recurse) sees the text.
pub fn check_xml_depth(text: &str, limit: usize) -> Result<(), String> {
    if xml_depth(text, limit) > limit {
        Err(format!(
            "XML elements nested more than {limit} deep (the limit)"
        ))
    } else {
        Ok(())
    }
}

/// The deepest element nesting of an XML document, found by a scan that needs no recursion
/// (comments, processing instructions, CDATA sections, declarations and quoted attribute
/// values are skipped). Stops early and returns a value above `limit` as soon as the nesting
/// exceeds it. Malformed input is left for the XML parser to report.
pub fn xml_depth(text: &str, limit: usize) -> usize {
    let b = text.as_bytes();
    let mut i = 0;
    let mut depth = 0usize;
    let mut deepest = 0usize;
    let skip_to = |from: usize, end: &[u8]| -> usize {
        b[from..]
            .windows(end.len())
            .position(|w| w == end)
            .map_or(b.len(), |p| from + p + end.len())
    };
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &b[i..];
        if rest.starts_with(b"<!--") {
            i = skip_to(i + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = skip_to(i + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = skip_to(i + 2, b"?>");
        } else if rest.starts_with(b"<!") {
            i = skip_to(i + 2, b">");
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = skip_to(i + 2, b">");
        } else {
            // A start tag: find its end outside quoted attribute values.
            let mut j = i + 1;
            let mut quote = None;
            let mut self_closing = false;
            while j < b.len() {
                let c = b[j];
                match quote {
                    Some(q) if c == q => quote = None,
                    Some(_) => {}
                    None if c == b'"' || c == b'\'' => quote = Some(c),
                    None if c == b'>' => {
                        self_closing = j > i + 1 && b[j - 1] == b'/';
                        break;
                    }
                    None => {}
                }
                j += 1;
            }
            if !self_closing {
                depth += 1;
                deepest = deepest.max(depth);
                if deepest > limit {
                    return deepest;
                }
            } else {
                deepest = deepest.max(depth + 1);
            }
            i = j + 1;
        }
    }
    deepest
}

/// Serde helpers for fixed-size arrays that refuse any other number of elements: serde's own
/// arrays ignore surplus elements in some formats (TOML among them), so a 4-element `position`
/// would pass. Use as `#[serde(deserialize_with = "crate::limits::exact::array")]`, or
/// `exact::option` on an optional field with `#[serde(default)]`.
pub mod exact {
    use serde::de::{self, Deserialize, Deserializer, IgnoredAny, SeqAccess, Visitor};
    use std::marker::PhantomData;

    struct ArrayVisitor<T, const N: usize>(PhantomData<T>);

    impl<'de, T: Deserialize<'de> + Copy + Default, const N: usize> Visitor<'de>
        for ArrayVisitor<T, N>
    {
        type Value = [T; N];

        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "an array of exactly {N} numbers")
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
            let mut out = [T::default(); N];
            for (i, slot) in out.iter_mut().enumerate() {
                *slot = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(i, &self))?;
            }
            let mut n = N;
            while seq.next_element::<IgnoredAny>()?.is_some() {
                n += 1;
            }
            if n > N {
                return Err(de::Error::invalid_length(n, &self));
            }
            Ok(out)
        }
    }

    /// Deserialises `[T; N]`, refusing arrays of any other length.
    pub fn array<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de> + Copy + Default,
    {
        d.deserialize_seq(ArrayVisitor::<T, N>(PhantomData))
    }

    /// [`array()`] for an optional field (present means `Some`).
    pub fn option<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de> + Copy + Default,
    {
        array(d).map(Some)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xml_depth_counts_nesting_and_skips_comments_and_quotes() {
        assert_eq!(xml_depth("<a/>", 10), 1);
        assert_eq!(
            xml_depth("<?xml version=\"1.0\"?><a><b><c/></b></a>", 10),
            3
        );
        assert_eq!(
            xml_depth("<a><!-- <b><b><b> --><b x=\"<c>\" y='/>'></b></a>", 10),
            2
        );
        assert_eq!(xml_depth("<a><![CDATA[<b><b>]]></a>", 10), 1);
        let deep = "<a>".repeat(15_000);
        assert_eq!(
            xml_depth(&deep, 64),
            65,
            "stops as soon as the limit is passed"
        );
    }

    #[test]
    fn read_file_refuses_devices_directories_and_large_files() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_file(dir.path(), 100).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
        let p = dir.path().join("f.txt");
        std::fs::write(&p, b"0123456789").unwrap();
        assert_eq!(read_file(&p, 10).unwrap(), b"0123456789");
        let e = read_file(&p, 9).unwrap_err().to_string();
        assert!(e.contains("10 bytes") && e.contains("limit of 9"), "{e}");
        #[cfg(unix)]
        {
            let e = read_file(Path::new("/dev/zero"), 100)
                .unwrap_err()
                .to_string();
            assert!(e.contains("character device"), "{e}");
            let link = dir.path().join("zero.stl");
            std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
            let e = read_file(&link, 100).unwrap_err().to_string();
            assert!(e.contains("character device"), "{e}");
        }
    }
}
