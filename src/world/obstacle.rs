//! Obstacles: parry shapes with a pose (paper Eq. 3, generalised from spheres).

use super::convert::{to_parry_point, to_parry_pose};
use super::mesh::load_mesh;
use crate::error::{fmt_list, Error, Num, Result};
use crate::limits::{within, MAX_LENGTH, MAX_SETTING};
use nalgebra::{IsometryMatrix3, Point3, Rotation3, Vector3};
use parry3d_f64::math::Pose;
use parry3d_f64::query;
use parry3d_f64::shape::{Segment, SharedShape};

/// Mesh files larger than this (32 MiB, about 650,000 binary STL triangles: a second or more
/// to read and convert) show a spinner on stderr while they load, when stderr is a terminal.
pub const MESH_PROGRESS_BYTES: u64 = 32 << 20;

/// The shapes built from mesh files while loading one workspace, shared by every obstacle that
/// uses the same file with the same representation and scale: a cell that places one part many
/// times reads, converts and stores it once (parry's [`SharedShape`] is reference-counted).
///
/// It also keeps the scenario's budgets, checked when a mesh has been read and before it is
/// converted: the triangles of the distinct meshes ([`crate::limits::MAX_SCENE_MESH_TRIANGLES`])
/// and the voxel–triangle tests of their decompositions
/// ([`crate::world::mesh::MAX_DECOMPOSITION_TESTS`]).
#[derive(Debug, Default)]
pub struct MeshCache {
    built: std::collections::HashMap<MeshKey, (SharedShape, usize)>,
    triangles: usize,
    voxel_tests: u64,
    /// The meshes counted ahead of building ([`MeshCache::count_ahead`]) and their triangles.
    counted: std::collections::HashSet<MeshKey>,
    counted_triangles: usize,
}

/// What a built mesh shape depends on: the file, the representation and the scale (its bits).
type MeshKey = (std::path::PathBuf, MeshRepresentation, [u64; 3]);

/// The [`MeshKey`] of a mesh shape.
fn mesh_key(
    file: &std::path::Path,
    representation: MeshRepresentation,
    scale: [f64; 3],
) -> MeshKey {
    (file.to_path_buf(), representation, scale.map(f64::to_bits))
}

/// Why `total` triangles of distinct meshes break the scenario's limit, if they do.
fn over_triangle_limit(total: usize) -> std::result::Result<(), String> {
    let limit = crate::limits::MAX_SCENE_MESH_TRIANGLES;
    if total > limit {
        return Err(format!(
            "the distinct meshes up to here have {total} triangles, more than the limit of \
             {limit} for a scenario"
        ));
    }
    Ok(())
}

impl MeshCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of distinct mesh shapes built so far.
    pub fn len(&self) -> usize {
        self.built.len()
    }

    /// True when no mesh shape has been built.
    pub fn is_empty(&self) -> bool {
        self.built.is_empty()
    }

    /// Counts a mesh about to be built, of `triangles` triangles and `tests` voxel–triangle
    /// tests of decomposition (0 for other representations), against the scenario's budgets;
    /// the reason when it would exceed one.
    fn charge(&mut self, triangles: usize, tests: u64) -> std::result::Result<(), String> {
        let total = self.triangles.saturating_add(triangles);
        over_triangle_limit(total)?;
        let all_tests = self.voxel_tests.saturating_add(tests);
        let limit = crate::world::mesh::MAX_DECOMPOSITION_TESTS;
        if all_tests > limit {
            return Err(format!(
                "the decompositions up to here need {all_tests} voxel-triangle tests, more than \
                 the limit of {limit} for a scenario (large triangles across a mesh make the \
                 decomposition slow): use `hull` or `trimesh`, or remesh into smaller triangles"
            ));
        }
        (self.triangles, self.voxel_tests) = (total, all_tests);
        Ok(())
    }

    /// Counts, before any mesh is built, the triangles of the mesh `file` with
    /// `representation` and `scale` ([`crate::world::mesh::count_triangles`]) unless the same
    /// mesh was counted before: the reason when the distinct meshes counted so far break the
    /// triangle limit, so that it holds before a large mesh takes its time and memory (two
    /// 4M-triangle meshes were refused only after the first was built, 13 s and 2 GB). A file
    /// that cannot be counted adds nothing; its build says what is wrong.
    pub fn count_ahead(
        &mut self,
        file: &std::path::Path,
        representation: MeshRepresentation,
        scale: [f64; 3],
    ) -> std::result::Result<(), String> {
        if !self.counted.insert(mesh_key(file, representation, scale)) {
            return Ok(());
        }
        let triangles = crate::world::mesh::count_triangles(file).unwrap_or(0);
        self.counted_triangles = self.counted_triangles.saturating_add(triangles);
        over_triangle_limit(self.counted_triangles)
    }
}

/// Clears a progress display when dropped, on success and on error alike.
struct ClearOnDrop<'a>(&'a indicatif::ProgressBar);

impl Drop for ClearOnDrop<'_> {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

/// How a mesh obstacle stands in for collision checking.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum MeshRepresentation {
    /// The convex hull (parry `ConvexPolyhedron`): fast and conservative, fills every cavity.
    #[default]
    Hull,
    /// An approximate convex decomposition (V-HACD, resolution 32, into a parry `Compound`):
    /// keeps the larger concavities of a solid, non-convex body.
    Decomposition,
    /// The triangle mesh itself (parry `TriMesh`, oriented): for thin shells such as a glovebox.
    /// Contacts are with its surface; points enclosed by a closed mesh count as inside it for
    /// task-point validation.
    Trimesh,
}

impl MeshRepresentation {
    /// The name used in files.
    pub fn name(self) -> &'static str {
        match self {
            MeshRepresentation::Hull => "hull",
            MeshRepresentation::Decomposition => "decomposition",
            MeshRepresentation::Trimesh => "trimesh",
        }
    }
}

/// What an obstacle is, as written in a scenario. Lengths in metres.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum ObstacleShape {
    /// A ball (the paper's obstacle, Eq. 3).
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// A capsule along its local z axis: a segment of `length` swept by a ball of `radius`.
    Capsule {
        /// Length of the inner segment (0 gives a sphere).
        length: f64,
        /// Radius.
        radius: f64,
    },
    /// A box with full side lengths `size` along its local x, y, z.
    Cuboid {
        /// Full side lengths.
        size: [f64; 3],
    },
    /// A solid cylinder along its local z axis (as in URDF).
    Cylinder {
        /// Full length along z.
        length: f64,
        /// Radius.
        radius: f64,
    },
    /// A triangle mesh loaded from an STL or OBJ file, scaled per axis in its own frame, then
    /// placed.
    Mesh {
        /// The mesh file.
        file: std::path::PathBuf,
        /// How it stands in for collision checking.
        representation: MeshRepresentation,
        /// Scale factors along the mesh's x, y, z.
        scale: [f64; 3],
    },
}

impl ObstacleShape {
    /// Lowercase kind name (`sphere`, `capsule`, …).
    pub fn kind(&self) -> &'static str {
        match self {
            ObstacleShape::Sphere { .. } => "sphere",
            ObstacleShape::Capsule { .. } => "capsule",
            ObstacleShape::Cuboid { .. } => "cuboid",
            ObstacleShape::Cylinder { .. } => "cylinder",
            ObstacleShape::Mesh { .. } => "mesh",
        }
    }

    /// Checks every dimension: finite, positive (a capsule's length may be 0) and at most
    /// [`MAX_LENGTH`]; mesh scale factors positive and at most [`MAX_SETTING`]. The error
    /// names the field (`radius`, `size`, `length`, `scale`) relative to the obstacle.
    pub fn validate(&self) -> Result<()> {
        let positive = |field: &str, v: f64| {
            if v > 0.0 && within(v, MAX_LENGTH) {
                Ok(())
            } else if v.is_finite() && v > 0.0 {
                Err(Error::invalid(
                    field,
                    Num(v),
                    format!("must be at most {MAX_LENGTH} m"),
                ))
            } else {
                Err(Error::invalid(field, Num(v), "must be positive and finite"))
            }
        };
        match *self {
            ObstacleShape::Sphere { radius } => positive("radius", radius),
            ObstacleShape::Capsule { length, radius } => {
                positive("radius", radius)?;
                if length >= 0.0 && within(length, MAX_LENGTH) {
                    Ok(())
                } else {
                    Err(Error::invalid(
                        "length",
                        Num(length),
                        format!("must be finite, not negative and at most {MAX_LENGTH} m"),
                    ))
                }
            }
            ObstacleShape::Cuboid { size } => {
                if size.iter().all(|v| *v > 0.0 && within(*v, MAX_LENGTH)) {
                    Ok(())
                } else {
                    Err(Error::invalid(
                        "size",
                        format!("{size:?}"),
                        format!("every side must be positive and finite, at most {MAX_LENGTH} m"),
                    ))
                }
            }
            ObstacleShape::Cylinder { length, radius } => {
                positive("radius", radius)?;
                positive("length", length)
            }
            ObstacleShape::Mesh { scale, .. } => {
                if scale.iter().all(|v| *v > 0.0 && within(*v, MAX_SETTING)) {
                    Ok(())
                } else {
                    Err(Error::invalid(
                        "scale",
                        format!("{scale:?}"),
                        format!("every factor must be positive and finite, at most {MAX_SETTING}"),
                    ))
                }
            }
        }
    }

    /// The parry shape, the transform from the obstacle's frame to the shape's own frame
    /// (parry's cylinders stand along y, ours along z) and the number of mesh triangles read.
    /// Loads mesh files, or takes their shape from `cache` when built before; scaled mesh
    /// vertices must lie within [`MAX_LENGTH`] of the mesh origin.
    fn parry(&self, cache: &mut MeshCache) -> Result<(SharedShape, IsometryMatrix3<f64>, usize)> {
        let id = IsometryMatrix3::identity();
        let mut triangles = 0;
        let (shape, local) = match *self {
            ObstacleShape::Mesh {
                ref file,
                representation,
                scale,
            } => {
                let key = mesh_key(file, representation, scale);
                if let Some((shape, triangles)) = cache.built.get(&key) {
                    return Ok((shape.clone(), id, *triangles));
                }
                // Large meshes take a second or more to read and convert: show a spinner on
                // stderr (drawn only when it is a terminal).
                let bar = std::fs::metadata(file)
                    .is_ok_and(|m| m.len() > MESH_PROGRESS_BYTES)
                    .then(|| {
                        let bar = indicatif::ProgressBar::with_draw_target(
                            None,
                            indicatif::ProgressDrawTarget::stderr(),
                        );
                        bar.set_message(format!("reading mesh {}", file.display()));
                        bar.enable_steady_tick(std::time::Duration::from_millis(100));
                        bar
                    });
                let _clear = bar.as_ref().map(ClearOnDrop);
                let mut mesh = load_mesh(file).map_err(|source| Error::Mesh {
                    field: "file".into(),
                    source,
                })?;
                if let Some(bar) = &bar {
                    bar.set_message(format!(
                        "building the {} of {} ({} triangles)",
                        representation.name(),
                        file.display(),
                        mesh.triangles.len()
                    ));
                }
                let bad = |reason: String| Error::invalid("file", file.display(), reason);
                for (i, v) in mesh.vertices.iter_mut().enumerate() {
                    for (c, s) in v.iter_mut().zip(scale) {
                        *c *= s;
                    }
                    if !v.iter().all(|&c| within(c, MAX_LENGTH)) {
                        return Err(bad(format!(
                            "vertex {i} scaled by {} is {}, more than {MAX_LENGTH} m from the mesh origin",
                            fmt_list(&scale),
                            fmt_list(v)
                        )));
                    }
                }
                triangles = mesh.triangles.len();
                let tests = match representation {
                    MeshRepresentation::Decomposition => mesh.voxel_tests(),
                    _ => 0,
                };
                cache.charge(triangles, tests).map_err(bad)?;
                let shape = match representation {
                    MeshRepresentation::Hull => mesh
                        .to_convex_hull()
                        .ok_or_else(|| bad("no convex hull (degenerate mesh)".into()))?,
                    MeshRepresentation::Decomposition => mesh
                        .to_convex_decomposition()
                        .map_err(|e| bad(e.to_string()))?,
                    MeshRepresentation::Trimesh => {
                        SharedShape::new(mesh.to_parry_trimesh().map_err(|e| bad(e.to_string()))?)
                    }
                };
                cache.built.insert(key, (shape.clone(), triangles));
                (shape, id)
            }
            ObstacleShape::Sphere { radius } => (SharedShape::ball(radius), id),
            ObstacleShape::Capsule { length, radius } => {
                (SharedShape::capsule_z(0.5 * length, radius), id)
            }
            ObstacleShape::Cuboid { size } => (
                SharedShape::cuboid(0.5 * size[0], 0.5 * size[1], 0.5 * size[2]),
                id,
            ),
            ObstacleShape::Cylinder { length, radius } => (
                SharedShape::cylinder(0.5 * length, radius),
                IsometryMatrix3::from_parts(
                    Default::default(),
                    Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2),
                ),
            ),
        };
        Ok((shape, local, triangles))
    }
}

/// An obstacle of the workspace: a named shape placed in the world.
#[derive(Clone, Debug)]
pub struct Obstacle {
    /// Name used in messages and reports.
    pub name: String,
    /// What the obstacle is.
    pub geometry: ObstacleShape,
    /// Its placement in the world.
    pub placement: IsometryMatrix3<f64>,
    shape: SharedShape,
    pose: Pose,
    sphere: Option<(Point3<f64>, f64)>,
    mesh_triangles: usize,
}

impl Obstacle {
    /// An obstacle from its shape and placement; dimensions are validated.
    pub fn new(
        name: impl Into<String>,
        geometry: ObstacleShape,
        placement: IsometryMatrix3<f64>,
    ) -> Result<Self> {
        Self::with_cache(name, geometry, placement, &mut MeshCache::new())
    }

    /// As [`Obstacle::new`], taking a mesh shape from `cache` when the same file was built
    /// with the same representation and scale before (and adding it otherwise).
    pub fn with_cache(
        name: impl Into<String>,
        geometry: ObstacleShape,
        placement: IsometryMatrix3<f64>,
        cache: &mut MeshCache,
    ) -> Result<Self> {
        geometry.validate()?;
        let (shape, local, mesh_triangles) = geometry.parry(cache)?;
        let sphere = match geometry {
            ObstacleShape::Sphere { radius } => {
                Some((Point3::from(placement.translation.vector), radius))
            }
            _ => None,
        };
        Ok(Obstacle {
            name: name.into(),
            geometry,
            pose: to_parry_pose(&(placement * local)),
            placement,
            shape,
            sphere,
            mesh_triangles,
        })
    }

    /// Number of triangles read from the obstacle's mesh file (0 for other shapes).
    pub fn mesh_triangles(&self) -> usize {
        self.mesh_triangles
    }

    /// A sphere obstacle at `center` (paper Eq. 3).
    pub fn sphere(name: impl Into<String>, center: Point3<f64>, radius: f64) -> Result<Self> {
        Obstacle::new(
            name,
            ObstacleShape::Sphere { radius },
            IsometryMatrix3::translation(center.x, center.y, center.z),
        )
    }

    /// The parry shape.
    pub fn shape(&self) -> &SharedShape {
        &self.shape
    }

    /// The parry pose of the shape.
    pub fn pose(&self) -> &Pose {
        &self.pose
    }

    /// Centre and radius when the obstacle is a sphere, for closed-form fast paths.
    pub fn as_sphere(&self) -> Option<(Point3<f64>, f64)> {
        self.sphere
    }

    /// True when `p` lies inside the obstacle or on its boundary.
    pub fn contains_point(&self, p: &Point3<f64>) -> bool {
        self.shape.contains_point(&self.pose, to_parry_point(p))
    }

    /// Distance from `p` to the obstacle: positive outside, negative inside (the depth).
    pub fn signed_distance_to_point(&self, p: &Point3<f64>) -> f64 {
        let proj = self
            .shape
            .project_point(&self.pose, to_parry_point(p), false);
        let d = (proj.point - to_parry_point(p)).length();
        if proj.is_inside {
            -d
        } else {
            d
        }
    }

    /// Distance from the capsule of `radius` around segment `a`–`b` to the obstacle; 0 when they
    /// touch or overlap.
    pub fn distance_to_capsule(&self, a: &Point3<f64>, b: &Point3<f64>, radius: f64) -> f64 {
        let seg = Segment::new(to_parry_point(a), to_parry_point(b));
        let d = query::distance(&Pose::IDENTITY, &seg, &self.pose, self.shape.as_ref())
            .map(|d| d.distance)
            .unwrap_or(0.0);
        (d - radius).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn mesh_budgets_are_kept_across_a_scenario() {
        let mut cache = MeshCache::new();
        let (triangles, tests) = (crate::limits::MAX_SCENE_MESH_TRIANGLES, 40_000_000);
        // Two decompositions of 30M tests each: the second exceeds the scenario's 40M.
        cache.charge(1_000, 30_000_000).unwrap();
        let e = cache.charge(1_000, 30_000_000).unwrap_err();
        assert!(e.contains("need 60000000 voxel-triangle tests"), "{e}");
        assert!(
            e.contains(&format!("limit of {tests} for a scenario")),
            "{e}"
        );
        // A refused mesh is not counted; meshes of other kinds cost no tests.
        cache.charge(1_000, 10_000_000).unwrap();
        cache.charge(triangles - 2_000, 0).unwrap();
        let e = cache.charge(1, 0).unwrap_err();
        assert!(
            e.contains(&format!("have {} triangles", triangles + 1)),
            "{e}"
        );
    }

    #[test]
    fn sphere_queries_match_closed_form() {
        let o = Obstacle::sphere("s", Point3::new(1.0, 0.0, 0.0), 0.5).unwrap();
        assert!(o.contains_point(&Point3::new(1.2, 0.1, 0.0)));
        assert!(!o.contains_point(&Point3::new(1.6, 0.0, 0.0)));
        assert_relative_eq!(
            o.signed_distance_to_point(&Point3::new(3.0, 0.0, 0.0)),
            1.5,
            epsilon = 1e-12
        );
        let d = o.distance_to_capsule(
            &Point3::new(0.0, 1.0, 0.0),
            &Point3::new(2.0, 1.0, 0.0),
            0.1,
        );
        assert_relative_eq!(d, 0.4, epsilon = 1e-9);
    }

    #[test]
    fn cylinder_stands_along_local_z() {
        let o = Obstacle::new(
            "c",
            ObstacleShape::Cylinder {
                length: 2.0,
                radius: 0.1,
            },
            IsometryMatrix3::identity(),
        )
        .unwrap();
        assert!(o.contains_point(&Point3::new(0.0, 0.0, 0.9)));
        assert!(!o.contains_point(&Point3::new(0.0, 0.9, 0.0)));
    }

    #[test]
    fn bad_dimensions_name_the_field() {
        let e = ObstacleShape::Sphere { radius: -1.0 }
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("radius = -1"), "{e}");
        let e = ObstacleShape::Cuboid {
            size: [1.0, f64::NAN, 1.0],
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("size") && e.contains("NaN"), "{e}");
    }
}
