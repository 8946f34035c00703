//! Random scenarios like the paper's experiments (§IV-A planar, §IV-B volumetric).

use super::config::{ObjectiveWeights, OptimizerConfig};
use super::file::{
    AxesSpec, AxisSpec, LinkSpec, ObstacleSpec, ParamSpec, RobotSpec, ScenarioSpec, ShapeKind,
    TaskSpec,
};
use crate::kinematics::Placement;
use crate::planning::PlannerConfig;
use nalgebra::{Point3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

/// A named scenario generator (serialised by its command-line name, `paper-2d`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Preset {
    /// Paper §IV-A: 8 links rotating about y, lengths free, 5 spheres and 10 tasks in the XZ
    /// plane.
    #[serde(rename = "paper-2d")]
    Paper2d,
    /// Paper §IV-B: 8 links with rotations about x and y and a prismatic x axis, lengths and
    /// all those ranges free, 32 spheres and 10 tasks in 3D.
    #[serde(rename = "paper-3d")]
    Paper3d,
}

impl std::str::FromStr for Preset {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "paper-2d" => Ok(Preset::Paper2d),
            "paper-3d" => Ok(Preset::Paper3d),
            _ => Err(format!(
                "unknown preset `{s}` (expected paper-2d or paper-3d)"
            )),
        }
    }
}

impl Preset {
    /// The preset's name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Paper2d => "paper-2d",
            Preset::Paper3d => "paper-3d",
        }
    }
}

/// Number of links of both presets (paper §IV: `n = 8`).
pub const LINKS: usize = 8;
/// Upper bound of every link length in the presets (metres); the largest design reaches
/// `LINKS × MAX_LINK` = 2 m.
pub const MAX_LINK: f64 = 0.25;
const LINK_RADIUS: f64 = 0.02;
const CLEARANCE: f64 = 0.01;
/// Extra gap kept between generated obstacles and the largest design's home pose, and between
/// task points and obstacles.
const MARGIN: f64 = 0.05;

fn round4(x: f64) -> f64 {
    let r = (x * 1e4).round() / 1e4;
    if r == 0.0 {
        0.0 // no negative zero in files
    } else {
        r
    }
}

/// Distance from `p` to the segment `a`–`b` (clamped projection).
fn point_segment_distance(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

/// A random point at a distance in `[r_min, r_max]` from the origin: in the XZ plane (`planar`)
/// or anywhere in 3D; uniform in the area of the annulus / volume of the shell.
fn sample_point(rng: &mut ChaCha8Rng, planar: bool, r_min: f64, r_max: f64) -> Point3<f64> {
    loop {
        let v: Vector3<f64> = Vector3::new(
            rng.random_range(-1.0..1.0),
            if planar {
                0.0
            } else {
                rng.random_range(-1.0..1.0)
            },
            rng.random_range(-1.0..1.0),
        );
        let n = v.norm();
        if n <= 1.0 && n > 1e-9 {
            // v is uniform in the unit disc/ball, so n^k is uniform in [0, 1]: map it to a
            // radius uniform in the area/volume of the annulus/shell.
            let k = if planar { 2 } else { 3 };
            let u = n.powi(k);
            let r = (r_min.powi(k) + (r_max.powi(k) - r_min.powi(k)) * u).powf(1.0 / k as f64);
            return Point3::from(v / n * r);
        }
    }
}

/// Generates the preset's scenario for `seed`. The same seed always gives the same scenario.
///
/// Guarantees: every obstacle keeps at least `link_radius + clearance + 0.05 m` from the largest
/// design's home pose (the arm stretched along +x from the origin), every task point keeps the
/// same gap from every obstacle surface and lies between 0.3 m and 85 % of the largest reach
/// from the base.
pub fn generate(preset: Preset, seed: u64) -> ScenarioSpec {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let planar = preset == Preset::Paper2d;
    let reach = LINKS as f64 * MAX_LINK;
    let (n_obstacles, r_obstacle) = if planar {
        (5, (0.1, 0.25))
    } else {
        (32, (0.05, 0.15))
    };
    let home_a = Point3::origin();
    let home_b = Point3::new(reach, 0.0, 0.0);
    let gap = LINK_RADIUS + CLEARANCE + MARGIN;

    let mut spheres: Vec<(Point3<f64>, f64)> = Vec::new();
    while spheres.len() < n_obstacles {
        let radius = round4(rng.random_range(r_obstacle.0..r_obstacle.1));
        let c = sample_point(&mut rng, planar, 0.3, reach);
        let c = Point3::new(round4(c.x), round4(c.y), round4(c.z));
        if point_segment_distance(&c, &home_a, &home_b) > radius + gap
            && c.coords.norm() > radius + gap
        {
            spheres.push((c, radius));
        }
    }
    let mut tasks: Vec<Point3<f64>> = Vec::new();
    while tasks.len() < 10 {
        let p = sample_point(&mut rng, planar, 0.3, 0.85 * reach);
        let p = Point3::new(round4(p.x), round4(p.y), round4(p.z));
        if spheres.iter().all(|(c, r)| (p - c).norm() > r + gap) {
            tasks.push(p);
        }
    }

    let axis = |lo: f64, hi: f64| AxisSpec {
        min: ParamSpec::Free(lo, 0.0),
        max: ParamSpec::Free(0.0, hi),
    };
    let axes = if planar {
        AxesSpec {
            ry: Some(AxisSpec {
                min: ParamSpec::Fixed(round4(-PI)),
                max: ParamSpec::Fixed(round4(PI)),
            }),
            ..AxesSpec::default()
        }
    } else {
        AxesSpec {
            rx: Some(axis(round4(-PI), round4(PI))),
            ry: Some(axis(round4(-PI), round4(PI))),
            tx: Some(axis(-0.1, 0.2)),
            ..AxesSpec::default()
        }
    };
    ScenarioSpec {
        name: Some(format!("{} seed {seed}", preset.name())),
        seed,
        clearance: CLEARANCE,
        robot: RobotSpec {
            links: LINKS,
            link_radius: LINK_RADIUS,
            colliders_per_link: 4,
            snap: 1e-3,
            base: Placement::default(),
            tool: None,
            uniform: LinkSpec {
                a: Some(ParamSpec::Free(0.0, MAX_LINK)),
                axes: Some(axes),
                ..LinkSpec::default()
            },
            link: Vec::new(),
            self_collision: true,
            allowed_collisions: Vec::new(),
            self_collision_samples: 1000,
        },
        planner: PlannerConfig::default(),
        objective: ObjectiveWeights::default(),
        optimizer: OptimizerConfig::default(),
        obstacle: spheres
            .iter()
            .enumerate()
            .map(|(k, (c, r))| ObstacleSpec {
                name: Some(format!("sphere {k}")),
                shape: ShapeKind::Sphere,
                position: [c.x, c.y, c.z],
                rpy: None,
                quaternion: None,
                radius: Some(*r),
                length: None,
                size: None,
                file: None,
                representation: None,
                scale: None,
            })
            .collect(),
        task: tasks
            .iter()
            .map(|p| TaskSpec {
                name: None,
                point: [p.x, p.y, p.z],
                orientation: None,
                orientation_tolerance: None,
                approach: None,
                approach_tolerance: None,
            })
            .collect(),
    }
}

/// Half-angle of the approach cones [`orient`] adds (radians): 15°, rounded as the files are.
pub const APPROACH_TOLERANCE: f64 = 0.2618;
/// Largest angle between an approach direction [`orient`] draws and the outward direction from
/// the base to the task point (radians): 60°.
pub const APPROACH_SPREAD: f64 = PI / 3.0;

/// Gives every task of a generated scenario an approach cone ([`APPROACH_TOLERANCE`], 15°)
/// about a random direction within [`APPROACH_SPREAD`] of the outward direction from the base
/// to the point (uniform on that spherical cap; for the planar preset, uniform in that angle
/// within the XZ plane, where the planar arm's tool axis stays). The directions come from their
/// own random stream of `seed` (stream 1), so the obstacles and points stay those of
/// [`generate`] and the same seed always gives the same cones.
pub fn orient(preset: Preset, spec: &mut ScenarioSpec, seed: u64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(1);
    let planar = preset == Preset::Paper2d;
    for t in &mut spec.task {
        let p = Vector3::from(t.point);
        let out = p.normalize();
        let d = if planar {
            let a = rng.random_range(-APPROACH_SPREAD..APPROACH_SPREAD);
            // Rotation about y by a in the XZ plane.
            Vector3::new(
                out.x * a.cos() + out.z * a.sin(),
                0.0,
                -out.x * a.sin() + out.z * a.cos(),
            )
        } else {
            // Uniform on the cap: cos θ uniform in [cos spread, 1], azimuth uniform.
            let c = rng.random_range(APPROACH_SPREAD.cos()..1.0);
            let phi = rng.random_range(0.0..2.0 * PI);
            let side = if out.x.abs() < 0.9 {
                Vector3::x()
            } else {
                Vector3::y()
            };
            let u = out.cross(&side).normalize();
            let v = out.cross(&u);
            let sn = (1.0 - c * c).max(0.0).sqrt();
            out * c + (u * phi.cos() + v * phi.sin()) * sn
        };
        t.approach = Some([round4(d.x), round4(d.y), round4(d.z)]);
        t.approach_tolerance = Some(APPROACH_TOLERANCE);
    }
    if let Some(name) = &mut spec.name {
        name.push_str(", approach cones");
    }
}

/// The scenario as TOML text, with a comment header naming the preset and seed.
pub fn to_toml(preset: Preset, spec: &ScenarioSpec) -> String {
    let body = toml::to_string(spec).expect("a scenario always serialises");
    format!(
        "# kinsynth scenario generated by `kinsynth scenario --preset {} --seed {}`\n\
         # (paper §IV-{}). Edit freely; `kinsynth check` validates it.\n\n{body}",
        preset.name(),
        spec.seed,
        if preset == Preset::Paper2d { "A" } else { "B" },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;

    /// The bundled paper scenarios are what the command in their header writes today, byte
    /// for byte (and so every setting a generated scenario carries, and none that has no
    /// effect: an algorithm's population size is `optimizer.population`'s only).
    #[test]
    fn bundled_paper_scenarios_are_what_their_command_writes() {
        for (preset, file) in [
            (Preset::Paper2d, "paper-2d.toml"),
            (Preset::Paper3d, "paper-3d.toml"),
        ] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("examples/scenarios")
                .join(file);
            let bundled = std::fs::read_to_string(&path).unwrap();
            let text = to_toml(preset, &generate(preset, 1));
            assert!(
                bundled == text,
                "{file} differs from `kinsynth scenario --preset {} --seed 1`",
                preset.name()
            );
            assert!(!text.contains("\nswarm =") && text.matches("\npopulation =").count() == 1);
        }
    }

    #[test]
    fn approach_cones_are_deterministic_and_keep_the_points() {
        for preset in [Preset::Paper2d, Preset::Paper3d] {
            let plain = generate(preset, 5);
            let mut a = generate(preset, 5);
            orient(preset, &mut a, 5);
            let mut b = generate(preset, 5);
            orient(preset, &mut b, 5);
            assert_eq!(a, b);
            assert_eq!(a.obstacle, plain.obstacle);
            for (t, p) in a.task.iter().zip(&plain.task) {
                assert_eq!(t.point, p.point);
                let d = Vector3::from(t.approach.unwrap());
                assert!((d.norm() - 1.0).abs() < 1e-3);
                let out = Vector3::from(t.point).normalize();
                assert!(d.normalize().dot(&out) >= APPROACH_SPREAD.cos() - 1e-3);
                if preset == Preset::Paper2d {
                    assert_eq!(d.y, 0.0);
                }
            }
            let s = Scenario::from_spec(&a).unwrap();
            assert!(s.workspace.has_orientations());
        }
    }

    #[test]
    fn presets_are_valid_deterministic_and_clear_at_home() {
        for preset in [Preset::Paper2d, Preset::Paper3d] {
            let a = to_toml(preset, &generate(preset, 7));
            let b = to_toml(preset, &generate(preset, 7));
            assert_eq!(a, b);
            assert_ne!(a, to_toml(preset, &generate(preset, 8)));
            let s = Scenario::from_spec(&Scenario::parse(&a).unwrap()).unwrap();
            assert!(s.home_contacts().is_empty(), "{preset:?}");
            assert_eq!(s.workspace.tasks.len(), 10);
            let reach = LINKS as f64 * MAX_LINK;
            for t in &s.workspace.tasks {
                assert!(t.coords.norm() <= 0.85 * reach + 1e-9);
                if preset == Preset::Paper2d {
                    assert_eq!(t.y, 0.0);
                }
            }
        }
        let s3 = Scenario::from_spec(&generate(Preset::Paper3d, 1)).unwrap();
        assert_eq!(s3.workspace.obstacles.len(), 32);
        assert_eq!(s3.space.dim(), 8 * 7, "paper §IV-B: 7 variables per link");
        assert_eq!(s3.space.largest().chain().dof(), 24);
        let s2 = Scenario::from_spec(&generate(Preset::Paper2d, 1)).unwrap();
        assert_eq!(s2.workspace.obstacles.len(), 5);
        assert_eq!(s2.space.dim(), 8);
    }
}
