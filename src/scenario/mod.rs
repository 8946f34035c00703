//! Scenario files (TOML): the robot template, the workspace and the settings of a design study,
//! read into a validated [`Scenario`]; and presets that generate the paper's random workspaces.

pub mod config;
pub mod file;
pub mod preset;

pub use crate::collision::{BodyModel, CheckerKind};
pub use crate::planning::{PlannerConfig, Schedule};
pub use config::{Algorithm, ObjectiveWeights, OptimizerConfig};
pub use file::{
    AxesSpec, AxisSpec, LinkSpec, ObstacleSpec, OrientationSpec, ParamSpec, ScenarioSpec,
    ShapeKind, TaskSpec,
};

use crate::design::{AxisRanges, Design, DesignSpace, LinkDesign, Param, Variable};
use crate::error::{fmt_list, Error, Num, Result};
use crate::kinematics::{Axis, Placement, Range};
use crate::limits::{
    within, MAX_ANGLE, MAX_COLLIDERS_PER_LINK, MAX_LENGTH, MAX_LINKS, MAX_OBSTACLES,
    MAX_POPULATION, MAX_SETTING, MAX_TASKS,
};
use crate::optimize::{ga::GaParams, pso::PsoParams};
use crate::world::{Contact, MeshCache, Obstacle, ObstacleShape, TaskOrientation, Workspace};
use nalgebra::Point3;
use std::path::{Path, PathBuf};

/// A validated scenario: design space, workspace and settings.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Name (from the file, or the file stem).
    pub name: String,
    /// The file it was read from, if any.
    pub path: Option<PathBuf>,
    /// Seed of every random stream.
    pub seed: u64,
    /// Which design variables are free, and their bounds.
    pub space: DesignSpace,
    /// Obstacles, tasks, clearance.
    pub workspace: Workspace,
    /// Planner settings.
    pub planner: PlannerConfig,
    /// Objective weights.
    pub objective: ObjectiveWeights,
    /// Optimiser settings.
    pub optimizer: OptimizerConfig,
}

/// Prefixes the field path of an error ([`Error::under`], e.g. `radius` → `obstacle[3].radius`).
fn at(prefix: &str) -> impl Fn(Error) -> Error + '_ {
    move |e| e.under(prefix)
}

pub(crate) fn check(
    ok: bool,
    field: impl Into<String>,
    value: impl std::fmt::Display,
    why: &str,
) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::invalid(field, value, why))
    }
}

/// `v` must be positive and finite.
fn check_positive(v: f64, field: impl Into<String>) -> Result<()> {
    check(
        v.is_finite() && v > 0.0,
        field,
        Num(v),
        "must be positive and finite",
    )
}

/// `v` must be finite and not negative.
fn check_non_negative(v: f64, field: impl Into<String>) -> Result<()> {
    check(
        v.is_finite() && v >= 0.0,
        field,
        Num(v),
        "must be finite and not negative",
    )
}

/// `v` must be positive, finite and at most `bound` (in `unit`).
pub(crate) fn check_positive_within(
    v: f64,
    bound: f64,
    unit: &str,
    field: impl Into<String>,
) -> Result<()> {
    check(
        v > 0.0 && within(v, bound),
        field,
        Num(v),
        &format!("must be positive and at most {bound}{unit}"),
    )
}

/// `v` must be finite, not negative and at most `bound` (in `unit`).
pub(crate) fn check_non_negative_within(
    v: f64,
    bound: f64,
    unit: &str,
    field: impl Into<String>,
) -> Result<()> {
    check(
        v >= 0.0 && within(v, bound),
        field,
        Num(v),
        &format!("must be finite, not negative and at most {bound}{unit}"),
    )
}

/// Every coordinate of `v` must be finite and within `±bound` (in `unit`).
fn check_vector(v: &[f64], bound: f64, unit: &str, field: impl Into<String>) -> Result<()> {
    let text = fmt_list(v);
    check(
        v.iter().all(|&c| within(c, bound)),
        field,
        text,
        &format!("every value must be finite and within ±{bound}{unit}"),
    )
}

/// A count must lie in `min..=max` (`max` is a limit of [`crate::limits`]).
pub(crate) fn check_count(
    n: usize,
    min: usize,
    max: usize,
    field: impl Into<String>,
) -> Result<()> {
    if n < min {
        Err(Error::invalid(field, n, format!("must be at least {min}")))
    } else if n > max {
        Err(Error::invalid(
            field,
            n,
            format!("must be at most {max} (the limit)"),
        ))
    } else {
        Ok(())
    }
}

/// The bound and unit of a design parameter: metres for `a`, `d` and translation limits,
/// radians for `θ`, `α` and rotation limits.
fn param_bound(param: Param) -> (f64, &'static str) {
    let length = match param {
        Param::D | Param::A => true,
        Param::Theta | Param::Alpha => false,
        Param::Min(axis) | Param::Max(axis) => !axis.is_rotation(),
    };
    if length {
        (MAX_LENGTH, " m")
    } else {
        (MAX_ANGLE, " rad")
    }
}

fn check_param(p: &ParamSpec, param: Param, field: &str) -> Result<()> {
    let (bound, unit) = param_bound(param);
    match *p {
        ParamSpec::Fixed(v) => check(
            within(v, bound),
            field,
            Num(v),
            &format!("must be finite and within ±{bound}{unit}"),
        ),
        ParamSpec::Free(lo, hi) => {
            let value = fmt_list(&[lo, hi]);
            check(
                within(lo, bound) && within(hi, bound),
                field,
                &value,
                &format!("bounds must be finite and within ±{bound}{unit}"),
            )?;
            check(lo <= hi, field, &value, "lower bound exceeds upper bound")
        }
    }
}

/// The template value of a parameter: a fixed value as given; for a free one, a new design
/// variable (appended to `vars`) and its midpoint as a placeholder.
fn resolve(p: ParamSpec, link: usize, param: Param, vars: &mut Vec<Variable>) -> f64 {
    match p {
        ParamSpec::Fixed(v) => v,
        ParamSpec::Free(lower, upper) => {
            vars.push(Variable {
                link,
                param,
                lower,
                upper,
            });
            0.5 * (lower + upper)
        }
    }
}

impl Scenario {
    /// Reads and validates a scenario file. Every error names the file, and the field path and
    /// value where there is one.
    pub fn load(path: &Path) -> Result<Scenario> {
        let text = crate::limits::read_text(path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(
            |source| Error::Read {
                path: path.to_path_buf(),
                source,
            },
        )?;
        let spec = Self::parse(&text).map_err(|e| e.in_file(path))?;
        let dir = path.parent().unwrap_or(Path::new(""));
        let mut s = Scenario::from_spec_in(&spec, dir).map_err(|e| e.in_file(path))?;
        if spec.name.is_none() {
            if let Some(stem) = path.file_stem() {
                s.name = stem.to_string_lossy().into_owned();
            }
        }
        s.path = Some(path.to_path_buf());
        Ok(s)
    }

    /// Parses scenario TOML into its raw form. Syntax errors, unknown keys and wrong types are
    /// reported with their field path (`obstacle[3].radius`) and line.
    pub fn parse(text: &str) -> Result<ScenarioSpec> {
        let parse_error = |message: String| Error::Parse {
            file: PathBuf::new(),
            message,
        };
        // One line per error: "line L, column C: [field path: ]message".
        let describe = |path: Option<String>, e: &toml::de::Error| {
            let mut m = String::new();
            if let Some(span) = e.span() {
                let before = &text[..span.start.min(text.len())];
                let line = before.matches('\n').count() + 1;
                let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
                m.push_str(&format!("line {line}, column {column}: "));
            }
            if let Some(p) = path.filter(|p| p != ".") {
                m.push_str(&format!("{p}: "));
            }
            let message = e.message().replace('\n', " ");
            if message.trim() == "recursion limit" && e.span().is_none() {
                // The parser names neither the place nor the cause.
                m.push_str(
                    "recursion limit: a table header, dotted key or value is nested deeper than \
                     the TOML reader allows",
                );
            } else {
                m.push_str(&message);
                // The reader names no key it finds twice: the key is the text it points at.
                let key = e.span().and_then(|s| text.get(s)).map(str::trim);
                if let Some(key) =
                    key.filter(|k| message.trim() == "duplicate key" && !k.is_empty())
                {
                    let key: String = key.lines().next().unwrap_or("").chars().take(80).collect();
                    m.push_str(&format!(" `{key}`"));
                }
            }
            parse_error(m.trim_end().to_string())
        };
        let de = toml::de::Deserializer::parse(text).map_err(|e| describe(None, &e))?;
        crate::strict::deserialize(de)
            .map_err(|e| describe(Some(crate::strict::path(&e)), e.inner()))
    }

    /// Validates a raw scenario and builds the design space and workspace; mesh files are
    /// looked up relative to the current directory.
    pub fn from_spec(spec: &ScenarioSpec) -> Result<Scenario> {
        Self::from_spec_in(spec, Path::new(""))
    }

    /// As [`Scenario::from_spec`], with mesh files relative to `dir` (the scenario's folder).
    pub fn from_spec_in(spec: &ScenarioSpec, dir: &Path) -> Result<Scenario> {
        let space = Self::design_space(spec)?;
        let workspace = Self::workspace(spec, dir)?;
        spec.planner.validate()?;
        // The nearest-node search and the inverse kinematics make iterations cost more on
        // designs of many axes, and with many IK steps.
        let axes = space.largest().chain().dof();
        let ik_steps = spec.planner.ik_steps;
        let cap = crate::limits::iteration_cap(axes, ik_steps);
        let schedule = spec.planner.schedule.iter().flat_map(|s| s.iterations);
        for (field, n) in std::iter::once(("planner.max_iterations", spec.planner.max_iterations))
            .chain(schedule.map(|n| ("planner.schedule.iterations", n)))
        {
            check(
                n <= cap,
                field,
                n,
                &format!(
                    "the largest design has {axes} free axes and planner.ik_steps is \
                     {ik_steps}, which allow at most {cap} iterations (iterations × axes at \
                     most {}, iterations × axes × IK steps at most {})",
                    crate::limits::MAX_ITERATION_AXES,
                    crate::limits::MAX_IK_AXIS_STEPS
                ),
            )?;
        }
        for (i, w) in spec.objective.as_array().into_iter().enumerate() {
            check_non_negative_within(w, MAX_SETTING, "", format!("objective.lambda{i}"))?;
        }
        Self::validate_optimizer(&spec.optimizer)?;
        let o = &spec.optimizer;
        for (field, n) in [
            ("optimizer.recheck_seeds", o.recheck_seeds),
            ("optimizer.confirm_seeds", o.confirm_seeds),
        ] {
            let max = crate::optimize::runner::MAX_SEEDS;
            check(n <= max, field, n, &format!("must be at most {max}"))?;
        }
        let r = &spec.robot;
        for (k, &[a, b]) in r.allowed_collisions.iter().enumerate() {
            for v in [a, b] {
                if v > r.links {
                    return Err(Error::invalid(
                        format!("robot.allowed_collisions[{k}]"),
                        format!("[{a}, {b}]"),
                        format!("links run from 0 (the base) to {}", r.links),
                    ));
                }
            }
        }
        let max_samples = crate::limits::MAX_SELF_COLLISION_SAMPLES;
        check(
            r.self_collision_samples <= max_samples,
            "robot.self_collision_samples",
            r.self_collision_samples,
            &format!("must be at most {max_samples}"),
        )?;
        // Each pair once, in either order: the matrix is rebuilt for every design evaluated.
        let mut allowed: Vec<[usize; 2]> = r
            .allowed_collisions
            .iter()
            .map(|&[a, b]| [a.min(b), a.max(b)])
            .collect();
        allowed.sort_unstable();
        allowed.dedup();
        let mut planner = spec.planner.clone();
        planner.self_collision = crate::collision::SelfCollisionConfig {
            enabled: r.self_collision,
            allowed,
            samples: r.self_collision_samples,
            seed: spec.seed,
        };
        Ok(Scenario {
            name: spec.name.clone().unwrap_or_else(|| "scenario".into()),
            path: None,
            seed: spec.seed,
            space,
            workspace,
            planner,
            objective: spec.objective.clone(),
            optimizer: spec.optimizer.clone(),
        })
    }

    /// Checks the `[optimizer]` section: budgets, sizes and every parameter of the three
    /// algorithms, so that no setting can stall, overflow or crash a run.
    fn validate_optimizer(o: &OptimizerConfig) -> Result<()> {
        check_count(o.population, 2, MAX_POPULATION, "optimizer.population")?;
        if let Some(t) = o.time_limit {
            check_positive(t, "optimizer.time_limit")?;
        }
        if let Some(n) = o.evaluations {
            check(n > 0, "optimizer.evaluations", n, "must be at least 1")?;
        }
        check_non_negative(o.checkpoint_interval, "optimizer.checkpoint_interval")?;
        // The GA's population and the swarm are `optimizer.population`; a size set in their
        // own sections would be overridden without a word, so one that differs is refused.
        let follows = crate::optimize::ga::FOLLOWS_POPULATION;
        for (n, field) in [
            (o.ga.population, "optimizer.ga.population"),
            (o.pso.swarm, "optimizer.pso.swarm"),
        ] {
            check(
                n == follows || n == o.population,
                field,
                n,
                &format!(
                    "the size of every algorithm's population is optimizer.population ({}): set it there",
                    o.population
                ),
            )?;
        }
        // The algorithms' and the migration's settings, by the rules a checkpoint's are held
        // to on resume.
        o.migration.check("optimizer.migration.", o.population)?;
        GaParams {
            population: o.population,
            ..o.ga.clone()
        }
        .check("optimizer.ga.")?;
        PsoParams {
            swarm: o.population,
            ..o.pso.clone()
        }
        .check("optimizer.pso.")?;
        o.asa.check("optimizer.asa.")
    }

    fn design_space(spec: &ScenarioSpec) -> Result<DesignSpace> {
        let r = &spec.robot;
        check_count(r.links, 1, MAX_LINKS, "robot.links")?;
        check_count(
            r.colliders_per_link,
            0,
            MAX_COLLIDERS_PER_LINK,
            "robot.colliders_per_link",
        )?;
        check_non_negative_within(r.link_radius, MAX_LENGTH, " m", "robot.link_radius")?;
        check_non_negative_within(r.snap, MAX_LENGTH, "", "robot.snap")?;
        check_vector(&r.base.position, MAX_LENGTH, " m", "robot.base.position")?;
        check_vector(&r.base.rpy, MAX_ANGLE, " rad", "robot.base.rpy")?;
        if let Some(t) = &r.tool {
            check_vector(&t.position, MAX_LENGTH, " m", "robot.tool.position")?;
            check_vector(&t.rpy, MAX_ANGLE, " rad", "robot.tool.rpy")?;
        }
        check(
            r.uniform.index.is_none(),
            "robot.uniform.index",
            r.uniform.index.unwrap_or(0),
            "the uniform template applies to every link; use [[robot.link]] for one link",
        )?;
        let mut overrides: Vec<Option<(usize, &LinkSpec)>> = vec![None; r.links];
        for (k, l) in r.link.iter().enumerate() {
            let field = format!("robot.link[{k}].index");
            let Some(i) = l.index else {
                return Err(Error::invalid(
                    field,
                    "missing",
                    "each override needs `index`",
                ));
            };
            check(
                (1..=r.links).contains(&i),
                &field,
                i,
                &format!("must lie in 1..={}", r.links),
            )?;
            if let Some((prev, _)) = overrides[i - 1] {
                return Err(Error::invalid(
                    field,
                    i,
                    format!("link {i} is already overridden by robot.link[{prev}]"),
                ));
            }
            overrides[i - 1] = Some((k, l));
        }
        let mut links = Vec::with_capacity(r.links);
        let mut vars = Vec::new();
        for (i, ov) in overrides.iter().enumerate() {
            let mut link = LinkDesign::default();
            let mut axes = AxisRanges::default();
            let params = [Param::Theta, Param::D, Param::A, Param::Alpha];
            let pick = |f: fn(&LinkSpec) -> Option<ParamSpec>, name: &str| match ov
                .and_then(|(k, l)| f(l).map(|p| (p, format!("robot.link[{k}].{name}"))))
            {
                Some(x) => x,
                None => (
                    f(&r.uniform).unwrap_or_default(),
                    format!("robot.uniform.{name}"),
                ),
            };
            let specs = [
                pick(|l| l.theta, "theta"),
                pick(|l| l.d, "d"),
                pick(|l| l.a, "a"),
                pick(|l| l.alpha, "alpha"),
            ];
            let mut values = [0.0; 4];
            for ((param, (p, field)), value) in params.into_iter().zip(&specs).zip(&mut values) {
                check_param(p, param, field)?;
                *value = resolve(*p, i + 1, param, &mut vars);
            }
            [link.theta, link.d, link.a, link.alpha] = values;
            let uniform_axes = r.uniform.axes.unwrap_or_default().entries();
            let override_axes = ov.and_then(|(_, l)| l.axes).map(|a| a.entries());
            for axis in Axis::ALL {
                let j = axis.index();
                let (spec, field) = match override_axes.and_then(|a| a[j]) {
                    Some(s) => (s, format!("robot.link[{}].axes.{axis}", ov.unwrap().0)),
                    None => match uniform_axes[j] {
                        Some(s) => (s, format!("robot.uniform.axes.{axis}")),
                        None => continue,
                    },
                };
                check_param(&spec.min, Param::Min(axis), &format!("{field}.min"))?;
                check_param(&spec.max, Param::Max(axis), &format!("{field}.max"))?;
                let mut range = Range::ZERO;
                for (p, param, slot) in [
                    (spec.min, Param::Min(axis), &mut range.min),
                    (spec.max, Param::Max(axis), &mut range.max),
                ] {
                    *slot = resolve(p, i + 1, param, &mut vars);
                }
                if let (ParamSpec::Fixed(lo), ParamSpec::Fixed(hi)) = (spec.min, spec.max) {
                    check(
                        lo <= hi,
                        &field,
                        format!("{{ min = {}, max = {} }}", Num(lo), Num(hi)),
                        "min must not exceed max",
                    )?;
                }
                *axes.get_mut(axis) = range;
            }
            link.axes = axes;
            links.push(link);
        }
        let template = Design {
            base: r.base,
            link_radius: r.link_radius,
            colliders_per_link: r.colliders_per_link,
            links,
            tool: r.tool,
        };
        let space = DesignSpace::new(template, vars, r.snap).map_err(at("robot"))?;
        // The template's free values are placeholders: normalise them through decode.
        let mid: Vec<f64> = space
            .variables()
            .iter()
            .map(|v| 0.5 * (v.lower + v.upper))
            .collect();
        let template = space.decode(&mid);
        DesignSpace::new(template, space.variables().to_vec(), r.snap)
    }

    fn workspace(spec: &ScenarioSpec, dir: &Path) -> Result<Workspace> {
        check_non_negative_within(spec.clearance, MAX_LENGTH, " m", "clearance")?;
        check_count(spec.obstacle.len(), 0, MAX_OBSTACLES, "obstacle")?;
        check_count(spec.task.len(), 0, MAX_TASKS, "task")?;
        let mut obstacles = Vec::with_capacity(spec.obstacle.len());
        // A mesh placed many times is read and converted once; the cache also keeps the
        // scenario's mesh budgets (triangles, decomposition work). The triangles of all
        // meshes are counted before the first is built.
        let mut meshes = MeshCache::new();
        for (k, o) in spec.obstacle.iter().enumerate() {
            let (ShapeKind::Mesh, Some(file)) = (o.shape, &o.file) else {
                continue;
            };
            let path = dir.join(file);
            let scale = o.scale.map_or([1.0; 3], |s| s.factors());
            meshes
                .count_ahead(&path, o.representation.unwrap_or_default(), scale)
                .map_err(|reason| {
                    Error::invalid(format!("obstacle[{k}].file"), path.display(), reason)
                })?;
        }
        for (k, o) in spec.obstacle.iter().enumerate() {
            let obstacle = Self::obstacle(k, o, dir, &mut meshes)?;
            obstacles.push(obstacle);
        }
        let mut tasks = Vec::with_capacity(spec.task.len());
        let mut orientations = Vec::with_capacity(spec.task.len());
        for (j, t) in spec.task.iter().enumerate() {
            check_vector(&t.point, MAX_LENGTH, " m", format!("task[{j}].point"))?;
            tasks.push(Point3::from(t.point));
            orientations.push(Self::task_orientation(j, t)?);
        }
        Ok(Workspace::new(obstacles, tasks, spec.clearance)?.with_orientations(orientations))
    }

    /// The orientation constraint of `[[task]]` number `j`: none, a full orientation or an
    /// approach cone, validated (one of the two at most, each with its tolerance in `[0, π]`,
    /// a unit quaternion within 1e-6, a non-zero approach vector; both normalised).
    fn task_orientation(j: usize, t: &TaskSpec) -> Result<TaskOrientation> {
        let field = |f: &str| format!("task[{j}].{f}");
        let tolerance = |v: Option<f64>, name: &str, of: &str| -> Result<f64> {
            let v = v.ok_or_else(|| {
                Error::invalid(
                    field(name),
                    "missing",
                    format!("`{of}` needs `{name}` (radians, in [0, π])"),
                )
            })?;
            check(
                (0.0..=std::f64::consts::PI).contains(&v),
                field(name),
                Num(v),
                "must lie in [0, π] (radians)",
            )?;
            Ok(v)
        };
        let unused = |present: bool, name: &str, of: &str| {
            check(
                !present,
                field(name),
                "given",
                &format!("`{name}` applies only with `{of}`"),
            )
        };
        match (&t.orientation, &t.approach) {
            (Some(_), Some(a)) => Err(Error::invalid(
                field("approach"),
                fmt_list(a),
                "give either `orientation` or `approach`, not both",
            )),
            (None, None) => {
                unused(
                    t.orientation_tolerance.is_some(),
                    "orientation_tolerance",
                    "orientation",
                )?;
                unused(
                    t.approach_tolerance.is_some(),
                    "approach_tolerance",
                    "approach",
                )?;
                Ok(TaskOrientation::Free)
            }
            (None, Some(a)) => {
                unused(
                    t.orientation_tolerance.is_some(),
                    "orientation_tolerance",
                    "orientation",
                )?;
                check_vector(a, MAX_LENGTH, "", field("approach"))?;
                let v = nalgebra::Vector3::from(*a);
                check(
                    v.norm() > 1e-9,
                    field("approach"),
                    fmt_list(a),
                    "must be a non-zero direction",
                )?;
                Ok(TaskOrientation::Approach {
                    axis: nalgebra::Unit::new_normalize(v),
                    tolerance: tolerance(t.approach_tolerance, "approach_tolerance", "approach")?,
                })
            }
            (Some(o), None) => {
                unused(
                    t.approach_tolerance.is_some(),
                    "approach_tolerance",
                    "approach",
                )?;
                let rotation = match (o.rpy, o.quaternion) {
                    (Some(_), Some(q)) => {
                        return Err(Error::invalid(
                            field("orientation.quaternion"),
                            fmt_list(&q),
                            "give either `rpy` or `quaternion`, not both",
                        ))
                    }
                    (None, None) => {
                        return Err(Error::invalid(
                            field("orientation"),
                            "{}",
                            "needs `rpy = [roll, pitch, yaw]` or `quaternion = [x, y, z, w]`",
                        ))
                    }
                    (Some(rpy), None) => {
                        check_vector(&rpy, MAX_ANGLE, " rad", field("orientation.rpy"))?;
                        nalgebra::Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2])
                    }
                    (None, Some(q)) => {
                        let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
                        check(
                            q.iter().all(|v| v.is_finite()) && (n - 1.0).abs() <= 1e-6,
                            field("orientation.quaternion"),
                            fmt_list(&q),
                            "must be a unit quaternion [x, y, z, w] (norm within 1e-6 of 1)",
                        )?;
                        nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                            q[3], q[0], q[1], q[2],
                        ))
                        .to_rotation_matrix()
                    }
                };
                Ok(TaskOrientation::Pose {
                    rotation,
                    tolerance: tolerance(
                        t.orientation_tolerance,
                        "orientation_tolerance",
                        "orientation",
                    )?,
                })
            }
        }
    }

    fn obstacle(
        k: usize,
        o: &ObstacleSpec,
        dir: &Path,
        meshes: &mut MeshCache,
    ) -> Result<Obstacle> {
        let prefix = format!("obstacle[{k}]");
        let field = |f: &str| format!("{prefix}.{f}");
        check_vector(&o.position, MAX_LENGTH, " m", field("position"))?;
        let rpy = o.rpy.unwrap_or_default();
        check_vector(&rpy, MAX_ANGLE, " rad", field("rpy"))?;
        let kind = match o.shape {
            ShapeKind::Sphere => "sphere",
            ShapeKind::Capsule => "capsule",
            ShapeKind::Cuboid => "cuboid",
            ShapeKind::Cylinder => "cylinder",
            ShapeKind::Mesh => "mesh",
        };
        let need = |v: Option<f64>, f: &str| {
            v.ok_or_else(|| Error::invalid(field(f), "missing", format!("a {kind} needs `{f}`")))
        };
        let unused = |present: bool, f: &str| {
            check(
                !present,
                field(f),
                "given",
                &format!("a {kind} has no `{f}`"),
            )
        };
        if o.shape != ShapeKind::Mesh {
            unused(o.file.is_some(), "file")?;
            unused(o.representation.is_some(), "representation")?;
            unused(o.scale.is_some(), "scale")?;
        }
        let geometry = match o.shape {
            ShapeKind::Mesh => {
                unused(o.radius.is_some(), "radius")?;
                unused(o.length.is_some(), "length")?;
                unused(o.size.is_some(), "size")?;
                let file = o.file.as_ref().ok_or_else(|| {
                    Error::invalid(field("file"), "missing", "a mesh needs `file`")
                })?;
                ObstacleShape::Mesh {
                    file: dir.join(file),
                    representation: o.representation.unwrap_or_default(),
                    scale: o.scale.map_or([1.0; 3], |s| s.factors()),
                }
            }
            ShapeKind::Sphere => {
                unused(o.length.is_some(), "length")?;
                unused(o.size.is_some(), "size")?;
                ObstacleShape::Sphere {
                    radius: need(o.radius, "radius")?,
                }
            }
            ShapeKind::Capsule | ShapeKind::Cylinder => {
                unused(o.size.is_some(), "size")?;
                let radius = need(o.radius, "radius")?;
                let length = need(o.length, "length")?;
                if o.shape == ShapeKind::Capsule {
                    ObstacleShape::Capsule { length, radius }
                } else {
                    ObstacleShape::Cylinder { length, radius }
                }
            }
            ShapeKind::Cuboid => {
                unused(o.radius.is_some(), "radius")?;
                unused(o.length.is_some(), "length")?;
                ObstacleShape::Cuboid {
                    size: o.size.ok_or_else(|| {
                        Error::invalid(field("size"), "missing", "a cuboid needs `size`")
                    })?,
                }
            }
        };
        let mut placement = Placement {
            position: o.position,
            rpy,
        }
        .isometry();
        if let Some(q) = o.quaternion {
            check(
                o.rpy.is_none(),
                field("quaternion"),
                format!("{q:?}"),
                "give either `rpy` or `quaternion`, not both",
            )?;
            let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
            check(
                q.iter().all(|v| v.is_finite()) && n.is_finite() && n > 1e-9,
                field("quaternion"),
                format!("{q:?}"),
                "must be finite and non-zero ([x, y, z, w])",
            )?;
            let uq = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q[3], q[0], q[1], q[2],
            ));
            placement.rotation = uq.to_rotation_matrix();
        }
        let name = o.name.clone().unwrap_or_else(|| format!("{kind} {k}"));
        Obstacle::with_cache(name, geometry, placement, meshes).map_err(at(&prefix))
    }

    /// The mesh files the scenario's obstacles are read from, each once, as the scenario names
    /// them (relative to its folder).
    pub fn mesh_files(&self) -> Vec<&Path> {
        let mut seen = std::collections::HashSet::new();
        let mut files: Vec<&Path> = Vec::new();
        for o in &self.workspace.obstacles {
            if let crate::world::obstacle::ObstacleShape::Mesh { file, .. } = &o.geometry {
                if seen.insert(file.as_path()) {
                    files.push(file);
                }
            }
        }
        files
    }

    /// Links of the scenario's largest design ([`DesignSpace::largest`]) that touch an obstacle
    /// (within the clearance) in the home pose. A design whose home pose collides cannot move.
    pub fn home_contacts(&self) -> Vec<Contact> {
        let chain = self.space.largest().chain();
        self.workspace.contacts(&chain, chain.home())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    const MINIMAL: &str = r#"
[robot]
links = 2
uniform = { a = [0.0, 0.5], axes = { ry = { min = -3.0, max = 3.0 } } }

[[task]]
point = [0.5, 0.0, 0.2]
"#;

    #[test]
    fn minimal_scenario_uses_documented_defaults() {
        let s = Scenario::from_spec(&Scenario::parse(MINIMAL).unwrap()).unwrap();
        assert_eq!(s.space.dim(), 2);
        assert_eq!(s.planner, PlannerConfig::default());
        assert_eq!(s.space.template().link_radius, 0.02);
        assert_eq!(s.space.largest().links[1].a, 0.5);
        assert_eq!(s.space.largest().chain().dof(), 2);
    }

    #[test]
    fn override_replaces_uniform_fields() {
        let text = format!("{MINIMAL}\n[[robot.link]]\nindex = 1\nd = 0.3\na = 0.0\naxes = {{ rz = {{ min = [-1.0, 0.0], max = 1.0 }} }}\n");
        let s = Scenario::from_spec(&Scenario::parse(&text).unwrap()).unwrap();
        let names: Vec<String> = s.space.variables().iter().map(|v| v.name()).collect();
        assert_eq!(names, vec!["link1.rz.min", "link2.a"]);
        let d = s.space.largest();
        assert_eq!(d.links[0].d, 0.3);
        assert_eq!(d.links[0].axes.get(Axis::Ry), Range::new(-3.0, 3.0));
        assert_eq!(d.links[0].axes.get(Axis::Rz), Range::new(-1.0, 1.0));
    }

    #[test]
    fn parse_errors_name_the_field_path_and_line() {
        let text = format!(
            "{MINIMAL}\n[[obstacle]]\nshape = \"sphere\"\nposition = [1, 0, 0]\nradus = 0.1\n"
        );
        let e = Scenario::parse(&text).unwrap_err().to_string();
        assert!(e.contains("obstacle[0]") && e.contains("radus"), "{e}");
        assert!(e.contains("line"), "{e}");
    }

    /// The pipework scenario with its pipe bundle placed `copies` times, 0.3 m apart along x,
    /// and once more scaled by 1.1.
    fn bundle_copies(copies: usize) -> Scenario {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios");
        let text = std::fs::read_to_string(dir.join("pipework.toml")).unwrap();
        let block = "[[obstacle]]\nname = \"pipe bundle\"\nshape = \"mesh\"\n\
                     file = \"../../meshes/pipe_bundle.obj\"\n\
                     representation = \"decomposition\"\n";
        assert!(text.contains(block));
        let mut extra = String::new();
        for k in 0..copies {
            extra += &format!(
                "\n[[obstacle]]\nname = \"copy {k}\"\nshape = \"mesh\"\n\
                 file = \"../../meshes/pipe_bundle.obj\"\nrepresentation = \"decomposition\"\n\
                 position = [{}, 1.5, 0.4]\nrpy = [0.0, 0.0, {}]\n",
                0.3 * k as f64,
                0.1 * k as f64
            );
        }
        extra += "\n[[obstacle]]\nname = \"scaled\"\nshape = \"mesh\"\n\
                  file = \"../../meshes/pipe_bundle.obj\"\nrepresentation = \"decomposition\"\n\
                  position = [0.0, -1.5, 0.4]\nscale = 1.1\n";
        let text = text.replacen("[[task]]", &format!("{extra}\n[[task]]"), 1);
        Scenario::from_spec_in(&Scenario::parse(&text).unwrap(), &dir).unwrap()
    }

    /// A mesh placed many times is built once: the copies share the first one's shape (a
    /// different scale is another shape), each at its own pose, and each copy's distances are
    /// those of the same obstacle built alone.
    #[test]
    fn a_mesh_placed_many_times_is_built_once() {
        let s = bundle_copies(4);
        let obstacles = &s.workspace.obstacles;
        let bundle = obstacles
            .iter()
            .position(|o| o.name == "pipe bundle")
            .unwrap();
        let shared = |o: &Obstacle| Arc::ptr_eq(&o.shape().0, &obstacles[bundle].shape().0);
        let copies: Vec<&Obstacle> = obstacles
            .iter()
            .filter(|o| o.name.starts_with("copy "))
            .collect();
        assert_eq!(copies.len(), 4);
        assert!(copies.iter().all(|o| shared(o)));
        let scaled = obstacles.iter().find(|o| o.name == "scaled").unwrap();
        assert!(!shared(scaled));
        assert!(!shared(
            obstacles.iter().find(|o| o.name == "vessel").unwrap()
        ));
        for o in copies.iter().chain([&scaled]) {
            let alone = Obstacle::new("alone", o.geometry.clone(), o.placement).unwrap();
            assert!(!Arc::ptr_eq(&alone.shape().0, &o.shape().0));
            let centre = Point3::from(o.placement.translation.vector);
            for offset in [[0.0, 0.0, 0.0], [0.05, 0.1, -0.02], [0.4, 0.0, 0.3]] {
                let p = centre + nalgebra::Vector3::from(offset);
                let (a, b) = (
                    o.signed_distance_to_point(&p),
                    alone.signed_distance_to_point(&p),
                );
                assert_eq!(a, b, "{} at {p}", o.name);
            }
        }
        // The copies stand where they were placed: the distance at each one's centre differs
        // from the distance at that point to the first copy.
        let p = Point3::from(copies[3].placement.translation.vector);
        assert!(copies[0].signed_distance_to_point(&p) > copies[3].signed_distance_to_point(&p));
    }

    /// `allowed_collisions` reaches the planner once per pair, in either order: a list that
    /// repeats a pair a million times costs every evaluated design nothing more.
    #[test]
    fn allowed_collisions_are_kept_once_per_pair() {
        let pairs = "[2, 1], [1, 2], [1, 2], [0, 2], [2, 0], [1, 2]";
        let text = MINIMAL.replacen(
            "[robot]\n",
            &format!("[robot]\nallowed_collisions = [{pairs}]\n"),
            1,
        );
        assert_ne!(text, MINIMAL);
        let s = Scenario::from_spec(&Scenario::parse(&text).unwrap()).unwrap();
        assert_eq!(s.planner.self_collision.allowed, vec![[0, 2], [1, 2]]);
    }
}
