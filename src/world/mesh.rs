//! Loading obstacle triangle meshes from STL and OBJ files, and turning them
//! into parry collision shapes.
//!
//! [`load_mesh`] reads a file into a [`MeshData`] (an indexed triangle mesh
//! with `f64` vertices) and checks that it is usable: it has triangles, every
//! vertex is finite, every triangle index is in range and not every triangle
//! has zero area. Errors name the file and say exactly what is wrong.
//!
//! A [`MeshData`] can then be converted into a parry [`TriMesh`]
//! ([`MeshData::to_parry_trimesh`]), a convex hull
//! ([`MeshData::to_convex_hull`]) or an approximate convex decomposition
//! ([`MeshData::to_convex_decomposition`]).
//!
//! Triangles follow the usual convention of STL, OBJ and parry: the vertices
//! of a triangle are listed counter-clockwise when seen from outside, so the
//! right-hand normal points out of the solid.

use std::borrow::Cow;
use std::fmt;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::shape::{SharedShape, TriMesh, TriMeshBuilderError, TriMeshFlags};
use parry3d_f64::transformation::vhacd::{VHACDParameters, VHACD};

/// An indexed triangle mesh with `f64` vertex coordinates.
///
/// Produced by [`load_mesh`]; can also be built by hand, in which case
/// [`MeshData::validate`] checks it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeshData {
    /// Vertex positions `[x, y, z]`, in the units of the source file.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as indices into [`MeshData::vertices`], counter-clockwise
    /// when seen from outside the solid.
    pub triangles: Vec<[u32; 3]>,
}

/// A problem with the contents of a mesh, independent of where it came from.
///
/// Returned by [`MeshData::validate`]; [`load_mesh`] reports the same problems
/// as [`MeshError`] variants that also name the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshDefect {
    /// The mesh has no triangles.
    #[error("mesh has no triangles")]
    Empty,
    /// A vertex has a NaN or infinite coordinate.
    #[error("vertex {index} is not finite: {}", FmtPoint(.value))]
    NonFiniteVertex {
        /// Index of the first offending vertex.
        index: usize,
        /// Its coordinates.
        value: [f64; 3],
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "triangle {triangle} refers to vertex {vertex}, but the mesh has only {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// Index of the first offending triangle.
        triangle: usize,
        /// The out-of-range vertex index it contains.
        vertex: u32,
        /// Number of vertices in the mesh.
        vertex_count: usize,
    },
    /// Every triangle has zero area (relative to the size of the mesh).
    #[error(
        "mesh is degenerate: every triangle has zero area ({triangle_count} in all){}",
        FmtSpan(*.largest)
    )]
    Degenerate {
        /// Number of triangles in the mesh.
        triangle_count: usize,
        /// The largest coordinate of a vertex (its absolute value).
        largest: f64,
    },
}

/// Why [`load_mesh`] could not load a mesh file.
///
/// Every message starts with the path of the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The file is missing or could not be read.
    #[error("{}: cannot read file: {error}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        error: std::io::Error,
    },
    /// The file extension is not one of the supported formats.
    #[error(
        "{}: unsupported mesh format: {} (expected .stl or .obj)",
        .path.display(),
        FmtExtension(.extension.as_deref())
    )]
    UnknownExtension {
        /// The file.
        path: PathBuf,
        /// Its extension (without the dot), if it has one.
        extension: Option<String>,
    },
    /// The file could not be parsed.
    #[error("{}: cannot parse as {format}: {}", .path.display(), crate::error::shorten(&crate::error::one_line(.message)))]
    Parse {
        /// The file.
        path: PathBuf,
        /// The format the file was parsed as: `"binary STL"`, `"ASCII STL"` or `"OBJ"`.
        format: &'static str,
        /// What the parser reported.
        message: String,
    },
    /// The file contains no triangles.
    #[error("{}: mesh has no triangles", .path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A vertex has a NaN or infinite coordinate.
    #[error("{}: vertex {index} is not finite: {}", .path.display(), FmtPoint(.value))]
    NonFiniteVertex {
        /// The file.
        path: PathBuf,
        /// Index of the first offending vertex in the loaded mesh.
        index: usize,
        /// Its coordinates.
        value: [f64; 3],
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "{}: triangle {triangle} refers to vertex {vertex}, but the mesh has only {vertex_count} vertices",
        .path.display()
    )]
    IndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// Index of the first offending triangle.
        triangle: usize,
        /// The out-of-range vertex index it contains.
        vertex: u32,
        /// Number of vertices in the mesh.
        vertex_count: usize,
    },
    /// Every triangle has zero area (relative to the size of the mesh).
    #[error(
        "{}: mesh is degenerate: every triangle has zero area ({triangle_count} in all){}",
        .path.display(),
        FmtSpan(*.largest)
    )]
    Degenerate {
        /// The file.
        path: PathBuf,
        /// Number of triangles in the mesh.
        triangle_count: usize,
        /// The largest coordinate of a vertex (its absolute value).
        largest: f64,
    },
}

impl MeshError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            MeshError::Io { path, .. }
            | MeshError::UnknownExtension { path, .. }
            | MeshError::Parse { path, .. }
            | MeshError::Empty { path }
            | MeshError::NonFiniteVertex { path, .. }
            | MeshError::IndexOutOfRange { path, .. }
            | MeshError::Degenerate { path, .. } => path,
        }
    }

    /// Attaches `path` to a content problem.
    fn from_defect(path: &Path, defect: MeshDefect) -> Self {
        let path = path.to_path_buf();
        match defect {
            MeshDefect::Empty => MeshError::Empty { path },
            MeshDefect::NonFiniteVertex { index, value } => {
                MeshError::NonFiniteVertex { path, index, value }
            }
            MeshDefect::IndexOutOfRange {
                triangle,
                vertex,
                vertex_count,
            } => MeshError::IndexOutOfRange {
                path,
                triangle,
                vertex,
                vertex_count,
            },
            MeshDefect::Degenerate {
                triangle_count,
                largest,
            } => MeshError::Degenerate {
                path,
                triangle_count,
                largest,
            },
        }
    }
}

/// Why a [`MeshData`] could not be converted into a parry shape.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ShapeError {
    /// The mesh failed [`MeshData::validate`].
    #[error(transparent)]
    InvalidMesh(#[from] MeshDefect),
    /// parry refused to build the triangle mesh.
    #[error("cannot build a parry triangle mesh: {0}")]
    TriMesh(TriMeshBuilderError),
    /// The decomposition's voxelization would test more voxel–triangle pairs than
    /// [`MAX_DECOMPOSITION_TESTS`] (large triangles that cross the mesh's bounding box).
    #[error(
        "its triangles span {tests} voxel-triangle tests at resolution {DECOMPOSITION_RESOLUTION}, \
         more than the limit of {MAX_DECOMPOSITION_TESTS} (large triangles across the mesh make \
         the decomposition slow): use `hull` or `trimesh`, or remesh it into smaller triangles"
    )]
    DecompositionTooCostly {
        /// The estimated number of tests.
        tests: u64,
    },
    /// The convex decomposition produced no usable convex part. (A flat mesh
    /// still gives one flat part; this guards against inputs for which parry
    /// finds none.)
    #[error("convex decomposition produced no convex parts")]
    EmptyDecomposition,
}

/// Formats a point as `[x, y, z]` with the shortest exact decimal form of
/// each coordinate (`NaN`, `inf` for non-finite ones).
struct FmtPoint<'a>(&'a [f64; 3]);

impl fmt::Display for FmtPoint<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [x, y, z] = self.0;
        write!(f, "[{x}, {y}, {z}]")
    }
}

/// After a degenerate mesh's message: when a coordinate is far beyond any cell (more than
/// 1,000 × [`crate::limits::MAX_LENGTH`]), that coordinate, which makes every other triangle
/// small by comparison (and is likely in a wrong unit); else nothing.
struct FmtSpan(f64);

impl fmt::Display for FmtSpan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0 > 1e3 * crate::limits::MAX_LENGTH {
            write!(
                f,
                ", relative to a vertex coordinate of {:e}: is the unit wrong?",
                self.0
            )
        } else {
            Ok(())
        }
    }
}

/// Formats a file extension for [`MeshError::UnknownExtension`].
struct FmtExtension<'a>(Option<&'a str>);

impl fmt::Display for FmtExtension<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(ext) => write!(f, "file extension \".{ext}\""),
            None => f.write_str("no file extension"),
        }
    }
}

/// Flags used by [`MeshData::to_parry_trimesh`].
///
/// * `ORIENTED` computes the pseudo-normals parry needs to tell the inside of
///   a closed, outward-oriented mesh from the outside; without it
///   `contains_point` is false and `project_point(.., solid = true)` reports
///   `is_inside == false` for every point not exactly on the surface.
/// * `MERGE_DUPLICATE_VERTICES` makes triangles that share a position share a
///   vertex index. parry accumulates the edge and vertex pseudo-normals per
///   index, and the containment test (Baerentzen's angle-weighted
///   pseudo-normals) assumes they average all triangles around an edge or
///   vertex; a "triangle soup" (every triangle with its own three vertices,
///   as OBJ files with per-face normals load) would only see one triangle.
/// * `DELETE_DEGENERATE_TRIANGLES` drops triangles that have two equal
///   vertices after merging; their zero normal can make points whose closest
///   feature lies on such a triangle count as inside.
/// * `DELETE_DUPLICATE_TRIANGLES` keeps one of the triangles on the same three
///   vertices (in either orientation): a copy adds nothing to the surface but
///   every query near it pays for it again (a file of one triangle repeated
///   100,000 times made a planner run take 40 s).
///
/// `ORIENTED` is set only once the merged mesh is known to be closed and consistently
/// oriented ([`closed_and_oriented`]): the pseudo-normals of an open surface would make
/// points far behind it count as inside.
const TRIMESH_FLAGS: TriMeshFlags = TriMeshFlags::MERGE_DUPLICATE_VERTICES
    .union(TriMeshFlags::DELETE_DEGENERATE_TRIANGLES)
    .union(TriMeshFlags::DELETE_DUPLICATE_TRIANGLES);

/// True when every directed edge of `triangles` appears exactly once and its reverse exactly
/// once: the surface is closed (every edge shared by two triangles) and its triangles turn the
/// same way. Sorts the edges, so memory is linear in the triangles.
pub fn closed_and_oriented(triangles: &[[u32; 3]]) -> bool {
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    edges.sort_unstable();
    if edges.windows(2).any(|w| w[0] == w[1]) {
        return false;
    }
    !edges.is_empty()
        && edges
            .iter()
            .all(|&(a, b)| edges.binary_search(&(b, a)).is_ok())
}

/// Voxel grid resolution (along the longest side of the mesh bounding box)
/// used by [`MeshData::to_convex_decomposition`].
const DECOMPOSITION_RESOLUTION: u32 = 32;

/// Most voxel–triangle intersection tests the voxelization of a convex decomposition may make
/// (each triangle is tested against every voxel of its bounding box grown by one voxel, about 5
/// million tests a second): 10,000 random triangles across a box need 62 million (13 s), while
/// a surface of a million small triangles needs about 27 million (the 27 voxels around each).
pub const MAX_DECOMPOSITION_TESTS: u64 = 40_000_000;

/// The number of voxel–triangle tests parry's voxelization makes for `triangles` of `vertices`
/// at `resolution` voxels along the longest side of their bounding box: per triangle, the
/// voxels of its bounding box grown by one voxel on each side (as
/// `VoxelizedVolume::voxelize`).
fn voxel_tests(vertices: &[[f64; 3]], triangles: &[[u32; 3]], resolution: u32) -> u64 {
    let (mut min, mut max) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for v in vertices {
        for k in 0..3 {
            min[k] = min[k].min(v[k]);
            max[k] = max[k].max(v[k]);
        }
    }
    let longest = (0..3).map(|k| max[k] - min[k]).fold(0.0, f64::max);
    if longest.is_nan() || longest <= 0.0 {
        return 0;
    }
    let scale = f64::from(resolution.max(2) - 1) / longest;
    let cells: [i64; 3] = std::array::from_fn(|k| ((max[k] - min[k]) * scale) as i64 + 3);
    triangles
        .iter()
        .map(|t| {
            let mut count = 1u64;
            for k in 0..3 {
                let at = |i: u32| ((vertices[i as usize][k] - min[k]) * scale + 0.5) as i64;
                let (lo, hi) = (
                    t.iter().map(|&i| at(i)).min(),
                    t.iter().map(|&i| at(i)).max(),
                );
                let (lo, hi) = (lo.unwrap_or(0), hi.unwrap_or(0));
                let span = ((hi + 2).min(cells[k]) - (lo - 1).max(0)).max(0);
                count *= span as u64;
            }
            count
        })
        .sum()
}

/// A triangle whose doubled area is at most this fraction of the squared
/// bounding-box diagonal counts as having zero area.
const ZERO_AREA_RELATIVE: f64 = 1e-12;

impl MeshData {
    /// Checks that the mesh is usable: it has at least one triangle, all
    /// vertices are finite, all triangle indices are in range, and at least
    /// one triangle has non-zero area.
    ///
    /// Closedness and orientation are *not* checked: open meshes are valid
    /// obstacles, they just have no inside.
    pub fn validate(&self) -> Result<(), MeshDefect> {
        if self.triangles.is_empty() {
            return Err(MeshDefect::Empty);
        }
        if let Some((index, value)) = self
            .vertices
            .iter()
            .enumerate()
            .find(|(_, v)| !v.iter().all(|c| c.is_finite()))
        {
            return Err(MeshDefect::NonFiniteVertex {
                index,
                value: *value,
            });
        }
        let vertex_count = self.vertices.len();
        for (triangle, tri) in self.triangles.iter().enumerate() {
            if let Some(&vertex) = tri.iter().find(|&&i| i as usize >= vertex_count) {
                return Err(MeshDefect::IndexOutOfRange {
                    triangle,
                    vertex,
                    vertex_count,
                });
            }
        }
        let (min, max) = self.aabb();
        let diagonal_sq: f64 = (0..3).map(|k| (max[k] - min[k]).powi(2)).sum();
        let tolerance = ZERO_AREA_RELATIVE * diagonal_sq;
        let all_zero = self.triangles.iter().all(|tri| {
            let [a, b, c] = tri.map(|i| self.vertices[i as usize]);
            let ab = sub(b, a);
            let ac = sub(c, a);
            norm(cross(ab, ac)) <= tolerance
        });
        if all_zero {
            let largest = min.iter().chain(&max).fold(0.0f64, |m, x| m.max(x.abs()));
            return Err(MeshDefect::Degenerate {
                triangle_count: self.triangles.len(),
                largest,
            });
        }
        Ok(())
    }

    /// Axis-aligned bounding box `(min, max)` of all vertices.
    ///
    /// For a mesh without vertices, `min` is `+inf` and `max` is `-inf` in
    /// every coordinate.
    pub fn aabb(&self) -> ([f64; 3], [f64; 3]) {
        let mut min = [f64::INFINITY; 3];
        let mut max = [f64::NEG_INFINITY; 3];
        for v in &self.vertices {
            for k in 0..3 {
                min[k] = min[k].min(v[k]);
                max[k] = max[k].max(v[k]);
            }
        }
        (min, max)
    }

    /// Converts the mesh into a parry triangle mesh.
    ///
    /// Identical vertex positions are merged, and triangles made degenerate by
    /// the merge and repeated triangles (the same three vertices) are dropped. When the merged mesh is closed and consistently
    /// oriented ([`closed_and_oriented`]), pseudo-normals are computed so that,
    /// its triangles counter-clockwise seen from outside, `contains_point` and
    /// `project_point(.., solid = true)` tell points inside the solid from
    /// points outside. An open mesh is a surface: it contains no point and
    /// nothing is inside it. Distance and intersection queries work either way.
    pub fn to_parry_trimesh(&self) -> Result<TriMesh, ShapeError> {
        self.validate()?;
        let mut mesh =
            TriMesh::with_flags(self.parry_vertices(), self.triangles.clone(), TRIMESH_FLAGS)
                .map_err(ShapeError::TriMesh)?;
        if closed_and_oriented(mesh.indices()) {
            // Only the topology flags can fail, and none is asked for.
            let _ = mesh.set_flags(TRIMESH_FLAGS | TriMeshFlags::ORIENTED);
        }
        Ok(mesh)
    }

    /// The convex hull of all vertices, as a parry convex polyhedron.
    ///
    /// Returns `None` if the mesh fails [`MeshData::validate`] or parry cannot
    /// build the hull. If all vertices are coplanar the hull is a flat
    /// polygon (two-sided), which still works for distance and intersection
    /// queries but has no inside.
    ///
    /// Large meshes are reduced first without changing the hull ([`hull_candidates`]):
    /// duplicate vertices are merged and vertices strictly inside the polytope spanned by the
    /// extreme vertices in 26 directions are dropped. When more than [`EXACT_HULL_POINTS`]
    /// candidates remain (a finely tessellated smooth surface, whose exact hull has hundreds
    /// of thousands of vertices and takes minutes), the result is instead the intersection of
    /// the [`SUPPORT_PLANES`] supporting half-spaces of the vertices in evenly spread
    /// directions ([`support_polytope`]): it contains every vertex, so it is conservative for
    /// collision checking, and is within 0.4 % of the mesh size of the exact hull. A mesh of
    /// a million triangles takes well under a second either way (`benches/hull.rs`).
    pub fn to_convex_hull(&self) -> Option<SharedShape> {
        self.validate().ok()?;
        hull_of_points(&self.vertices)
    }

    /// The voxel–triangle tests the voxelization of [`MeshData::to_convex_decomposition`]
    /// makes (at most [`MAX_DECOMPOSITION_TESTS`] are allowed).
    pub fn voxel_tests(&self) -> u64 {
        voxel_tests(&self.vertices, &self.triangles, DECOMPOSITION_RESOLUTION)
    }

    /// An approximate convex decomposition of the mesh (V-HACD), as a parry
    /// compound of convex polyhedra.
    ///
    /// The mesh should be closed: the voxelization flood-fills its inside. A
    /// voxel grid of 32 cells along the longest side of the bounding box is
    /// used, which keeps a mesh of a few thousand triangles in the
    /// sub-second range; each part is the exact convex hull of the mesh
    /// triangles falling into it, so parts hug the original surface rather
    /// than the voxels.
    pub fn to_convex_decomposition(&self) -> Result<SharedShape, ShapeError> {
        self.validate()?;
        let tests = self.voxel_tests();
        if tests > MAX_DECOMPOSITION_TESTS {
            return Err(ShapeError::DecompositionTooCostly { tests });
        }
        let vertices = self.parry_vertices();
        let params = VHACDParameters {
            resolution: DECOMPOSITION_RESOLUTION,
            ..VHACDParameters::default()
        };
        let decomposition = VHACD::decompose(&params, &vertices, &self.triangles, true);
        let parts: Vec<(Pose, SharedShape)> = decomposition
            .compute_exact_convex_hulls(&vertices, &self.triangles)
            .into_iter()
            .filter_map(|(points, indices)| SharedShape::convex_mesh(points, &indices))
            .map(|part| (Pose::IDENTITY, part))
            .collect();
        if parts.is_empty() {
            return Err(ShapeError::EmptyDecomposition);
        }
        // `SharedShape::compound` panics on an empty list, hence the check above.
        Ok(SharedShape::compound(parts))
    }

    /// The vertices as parry vectors.
    fn parry_vertices(&self) -> Vec<Vector> {
        self.vertices
            .iter()
            .map(|&v| Vector::from_array(v))
            .collect()
    }
}

/// The convex hull of `vertices` (all finite), as [`MeshData::to_convex_hull`] builds it: the
/// exact hull of the [`hull_candidates`], or beyond [`EXACT_HULL_POINTS`] of them their
/// [`support_polytope`] (the exact hull again when that fails). `None` when parry finds no hull
/// (points on a line or at one point; flat points give a two-sided polygon).
pub fn hull_of_points(vertices: &[[f64; 3]]) -> Option<SharedShape> {
    let points = hull_candidates(vertices);
    if points.len() > EXACT_HULL_POINTS {
        if let Some(hull) =
            support_polytope(&points, SUPPORT_PLANES).and_then(|v| SharedShape::convex_hull(&v))
        {
            return Some(hull);
        }
    }
    SharedShape::convex_hull(&points)
}

/// Most candidate points for which [`MeshData::to_convex_hull`] computes the exact hull;
/// beyond, it builds the [`support_polytope`].
pub const EXACT_HULL_POINTS: usize = 20_000;

/// Number of supporting half-spaces of the [`support_polytope`] of a large mesh.
pub const SUPPORT_PLANES: usize = 1024;

/// `n` unit directions spread evenly over the sphere (a Fibonacci lattice).
fn sphere_directions(n: usize) -> Vec<[f64; 3]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * i as f64;
            [r * phi.cos(), r * phi.sin(), z]
        })
        .collect()
}

/// Support values `max_p d·(p − centre)` of `points` in each direction: by chunks of points in
/// parallel, with the directions' coordinates in separate arrays (they stay in cache and the
/// inner loop vectorises).
fn supports(points: &[Vector], centre: Vector, directions: &[Vector]) -> Vec<f64> {
    use rayon::prelude::*;
    let dx: Vec<f64> = directions.iter().map(|d| d.x).collect();
    let dy: Vec<f64> = directions.iter().map(|d| d.y).collect();
    let dz: Vec<f64> = directions.iter().map(|d| d.z).collect();
    let none = || vec![f64::NEG_INFINITY; directions.len()];
    points
        .par_chunks(4096)
        .map(|chunk| {
            let mut h = none();
            for p in chunk {
                let q = *p - centre;
                for (((h, x), y), z) in h.iter_mut().zip(&dx).zip(&dy).zip(&dz) {
                    let s = x * q.x + y * q.y + z * q.z;
                    if s > *h {
                        *h = s;
                    }
                }
            }
            h
        })
        .reduce(none, |mut a, b| {
            for (x, y) in a.iter_mut().zip(b) {
                if y > *x {
                    *x = y;
                }
            }
            a
        })
}

/// The distinct points of `points` that are extreme in some of `directions`.
fn extreme_points(points: &[Vector], directions: &[Vector]) -> Vec<Vector> {
    let mut best = vec![(f64::NEG_INFINITY, 0usize); directions.len()];
    for (i, p) in points.iter().enumerate() {
        for (d, b) in directions.iter().zip(best.iter_mut()) {
            let s = d.dot(*p);
            if s > b.0 {
                *b = (s, i);
            }
        }
    }
    let mut idx: Vec<usize> = best.iter().map(|b| b.1).collect();
    idx.sort_unstable();
    idx.dedup();
    idx.into_iter().map(|i| points[i]).collect()
}

/// The vertices of the polytope `∩_k {x : d_k·x ≤ max_p d_k·p}`: a convex polytope that
/// contains every point (and so their hull) and touches it in each direction `d_k`. The
/// directions are `planes` evenly spread unit vectors and the 26 of `{-1, 0, 1}³`, then the
/// facet normals of the exact hull of the points found extreme in those: the latter make the
/// flat faces of boxy meshes exact. Computed by polar duality: about the centre of the points'
/// bounding box, the half-space `d_k·x ≤ h_k` becomes the point `d_k / h_k`, and each facet
/// `n·y = c` of the hull of those points is the vertex `n / c` of the polytope. `None` when
/// the points are (nearly) flat, so that the centre is not strictly inside; the caller then
/// takes the exact hull.
pub fn support_polytope(points: &[Vector], planes: usize) -> Option<Vec<Vector>> {
    let first = points.first()?;
    let (mut min, mut max) = (*first, *first);
    for p in points {
        min = min.min(*p);
        max = max.max(*p);
    }
    let centre = (min + max) * 0.5;
    let diagonal = (max - min).length();
    if diagonal.is_nan() || diagonal <= 0.0 {
        return None;
    }
    let mut directions: Vec<Vector> = sphere_directions(planes)
        .into_iter()
        .map(Vector::from_array)
        .collect();
    for x in -1i8..=1 {
        for y in -1i8..=1 {
            for z in -1i8..=1 {
                if (x, y, z) != (0, 0, 0) {
                    let d = Vector::new(f64::from(x), f64::from(y), f64::from(z));
                    directions.push(d / d.length());
                }
            }
        }
    }
    // The hull of points extreme in the 26 lattice and 128 spread directions lies inside the
    // true hull; its facets' normals are directions in which the true hull is (nearly) flat.
    let mut coarse: Vec<Vector> = directions[planes..].to_vec();
    coarse.extend(sphere_directions(128).into_iter().map(Vector::from_array));
    let inner = extreme_points(points, &coarse);
    if let Ok((iv, faces)) = parry3d_f64::transformation::try_convex_hull(&inner) {
        // The normals of the largest facets first, at most a quarter of `planes` of them (a
        // box has 6; a round body many small ones, which the spread directions cover).
        let mut facets: Vec<(f64, Vector)> = faces
            .iter()
            .filter_map(|f| {
                let [a, b, c] = f.map(|i| iv[i as usize]);
                let n = (b - a).cross(c - a);
                let len = n.length();
                (len > 1e-12 * diagonal * diagonal).then(|| (len, n / len))
            })
            .collect();
        facets.sort_by(|x, y| y.0.total_cmp(&x.0));
        let mut normals: Vec<Vector> = Vec::new();
        for (_, n) in facets {
            if normals.len() >= planes / 4 {
                break;
            }
            if !normals.iter().any(|m| m.dot(n) > 1.0 - 1e-12) {
                normals.push(n);
            }
        }
        directions.extend(normals);
    }
    let support = supports(points, centre, &directions);
    // A margin against rounding keeps every point inside.
    let margin = 1e-9 * diagonal;
    if support.iter().any(|&h| h <= 1e-6 * diagonal) {
        return None;
    }
    let dual: Vec<Vector> = directions
        .iter()
        .zip(&support)
        .map(|(d, h)| *d / (h + margin))
        .collect();
    let (dv, faces) = parry3d_f64::transformation::try_convex_hull(&dual).ok()?;
    let mut vertices = Vec::with_capacity(faces.len());
    for f in &faces {
        let [a, b, c] = f.map(|i| dv[i as usize]);
        let n = (b - a).cross(c - a);
        let len = n.length();
        if len.is_nan() || len <= 0.0 {
            continue;
        }
        let n = n / len;
        let offset = n.dot(a).abs();
        if offset.is_nan() || offset <= 0.0 {
            return None;
        }
        vertices.push(centre + n / offset);
    }
    // Numerical trouble (a non-finite vertex) falls back to the exact hull.
    (vertices.len() >= 4 && vertices.iter().all(|v| v.is_finite())).then_some(vertices)
}

/// The points that can be vertices of the convex hull of `vertices` (all finite): distinct
/// positions only, without those strictly inside the polytope spanned by the extreme points in
/// the 26 directions of `{-1, 0, 1}³ \ {0}` (Akl–Toussaint). Dropping them leaves the hull
/// unchanged; a small tolerance keeps points on the polytope's faces.
pub fn hull_candidates(vertices: &[[f64; 3]]) -> Vec<Vector> {
    let mut points: Vec<[f64; 3]> = vertices.to_vec();
    points.sort_unstable_by(|a, b| {
        a[0].total_cmp(&b[0])
            .then(a[1].total_cmp(&b[1]))
            .then(a[2].total_cmp(&b[2]))
    });
    points.dedup();
    let all = |points: &[[f64; 3]]| points.iter().map(|&v| Vector::from_array(v)).collect();
    if points.len() <= 64 {
        return all(&points);
    }
    let mut directions = Vec::with_capacity(26);
    for x in -1i8..=1 {
        for y in -1i8..=1 {
            for z in -1i8..=1 {
                if (x, y, z) != (0, 0, 0) {
                    directions.push([f64::from(x), f64::from(y), f64::from(z)]);
                }
            }
        }
    }
    let mut extreme = vec![(f64::NEG_INFINITY, 0usize); directions.len()];
    for (k, p) in points.iter().enumerate() {
        for (d, e) in directions.iter().zip(extreme.iter_mut()) {
            let s = dot(*d, *p);
            if s > e.0 {
                *e = (s, k);
            }
        }
    }
    let mut corners: Vec<usize> = extreme.iter().map(|e| e.1).collect();
    corners.sort_unstable();
    corners.dedup();
    let corner_points: Vec<Vector> = corners
        .iter()
        .map(|&k| Vector::from_array(points[k]))
        .collect();
    let Ok((hv, faces)) = parry3d_f64::transformation::try_convex_hull(&corner_points) else {
        return all(&points);
    };
    if faces.len() < 4 {
        return all(&points);
    }
    let to3 = |v: &Vector| [v.x, v.y, v.z];
    let centroid = hv.iter().fold([0.0; 3], |c, v| {
        let v = to3(v);
        [c[0] + v[0], c[1] + v[1], c[2] + v[2]]
    });
    let centroid = centroid.map(|c| c / hv.len() as f64);
    let (min, max) = MeshData {
        vertices: points.clone(),
        triangles: Vec::new(),
    }
    .aabb();
    let diagonal = norm(sub(max, min));
    let tolerance = 1e-9 * diagonal;
    // Outward unit normals and offsets of the polytope's faces.
    let mut planes = Vec::with_capacity(faces.len());
    for f in &faces {
        let [a, b, c] = f.map(|i| to3(&hv[i as usize]));
        let n = cross(sub(b, a), sub(c, a));
        let len = norm(n);
        if len <= 1e-12 * diagonal * diagonal {
            continue;
        }
        let mut n = n.map(|v| v / len);
        let mut offset = dot(n, a);
        if dot(n, centroid) > offset {
            n = n.map(|v| -v);
            offset = -offset;
        }
        planes.push((n, offset));
    }
    if planes.len() < 4 {
        return all(&points);
    }
    points
        .iter()
        .filter(|p| planes.iter().any(|(n, o)| dot(*n, **p) - o > -tolerance))
        .map(|&v| Vector::from_array(v))
        .collect()
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Loads a triangle mesh from an STL (binary or ASCII) or OBJ file.
///
/// The format is chosen by the file extension, case-insensitively: `.stl` or
/// `.obj`. Binary and ASCII STL are told apart by content, not by the
/// `solid` keyword alone (many binary files start their header with it).
///
/// * STL: vertices with bit-identical coordinates are shared between
///   triangles. Coordinates are stored as `f32` in binary STL and parsed as
///   `f32` from ASCII STL, then widened to `f64`.
/// * OBJ: all objects and groups of the file are merged into one mesh;
///   polygons are fan-triangulated (so they should be convex); point and line
///   elements are ignored; material libraries are not read. A position used
///   with different texture coordinates or normals becomes several vertices.
///
/// The result is checked with [`MeshData::validate`].
pub fn load_mesh(path: &Path) -> Result<MeshData, MeshError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let parse: fn(&Path, &[u8]) -> Result<MeshData, MeshError> = match extension.as_deref() {
        Some("stl") => parse_stl,
        Some("obj") => parse_obj,
        _ => {
            return Err(MeshError::UnknownExtension {
                path: path.to_path_buf(),
                extension: path.extension().map(|e| e.to_string_lossy().into_owned()),
            })
        }
    };
    let bytes =
        crate::limits::read_file(path, crate::limits::MAX_MESH_FILE_BYTES).map_err(|error| {
            MeshError::Io {
                path: path.to_path_buf(),
                error,
            }
        })?;
    let mesh = parse(path, &bytes)?;
    mesh.validate()
        .map_err(|defect| MeshError::from_defect(path, defect))?;
    Ok(mesh)
}

/// The number of triangles of the mesh file `path` as its reader will find them (for an OBJ,
/// its faces fanned into triangles; for a binary STL, the header's count; for an ASCII STL, its
/// `facet`s), counted without building anything: `None` when the file cannot be read or is
/// neither STL nor OBJ (its reader reports why). A scenario's meshes are counted all together
/// before the first is built ([`crate::limits::MAX_SCENE_MESH_TRIANGLES`]).
pub fn count_triangles(path: &Path) -> Option<usize> {
    let extension = path.extension()?.to_string_lossy().to_ascii_lowercase();
    let bytes = crate::limits::read_file(path, crate::limits::MAX_MESH_FILE_BYTES).ok()?;
    match extension.as_str() {
        "obj" => Some(obj_counts(&bytes).0),
        "stl" => {
            let (declared, ascii) = stl_layout(&bytes);
            if ascii {
                // Lines may end with carriage returns alone (see `parse_stl`).
                let facets = bytes
                    .split(|&b| b == b'\n' || b == b'\r')
                    .filter(|line| words(line).next() == Some(b"facet"));
                Some(facets.count())
            } else {
                declared.map(|n| n as usize)
            }
        }
        _ => None,
    }
}

/// Text `bytes` whose carriage returns that end a line alone (classic Mac OS, also mixed with
/// other line ends) become line feeds; `None` when there are none.
fn lone_carriage_returns(bytes: &[u8]) -> Option<Vec<u8>> {
    let lone = |i: usize| bytes[i] == b'\r' && bytes.get(i + 1) != Some(&b'\n');
    (0..bytes.len()).any(lone).then(|| {
        (0..bytes.len())
            .map(|i| if lone(i) { b'\n' } else { bytes[i] })
            .collect()
    })
}

/// The words of a line of a text mesh file: its runs of bytes between ASCII whitespace.
fn words(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace())
        .filter(|w| !w.is_empty())
}

/// The numbers of triangles (faces fanned) and vertices of OBJ bytes, counted line by line.
fn obj_counts(bytes: &[u8]) -> (usize, usize) {
    let (mut triangles, mut vertices) = (0usize, 0usize);
    for line in bytes.split(|&b| b == b'\n') {
        let data = line.split(|&b| b == b'#').next().unwrap_or(line);
        let mut tokens = words(data);
        match tokens.next() {
            Some(b"f") => triangles += tokens.count().saturating_sub(2),
            Some(b"v") => vertices += 1,
            _ => {}
        }
    }
    (triangles, vertices)
}

/// Size of the header (80 bytes) plus triangle count (4 bytes) of binary STL.
const STL_BINARY_HEADER: usize = 84;
/// Size of one triangle record of binary STL.
const STL_BINARY_TRIANGLE: u64 = 50;

/// The triangle count a binary STL header declares (`None` for fewer than 84 bytes), and
/// whether the bytes are read as ASCII STL: not exactly the size that count makes, starting
/// with `solid` and without a NUL byte (see [`parse_stl`]).
fn stl_layout(bytes: &[u8]) -> (Option<u32>, bool) {
    let declared = bytes
        .get(80..STL_BINARY_HEADER)
        .map(|count| u32::from_le_bytes([count[0], count[1], count[2], count[3]]));
    let exact_binary = declared.is_some_and(|n| {
        STL_BINARY_HEADER as u64 + STL_BINARY_TRIANGLE * u64::from(n) == bytes.len() as u64
    });
    let ascii = !exact_binary && solid_keyword_offset(bytes).is_some() && !bytes.contains(&0);
    (declared, ascii)
}

/// Parses STL bytes, binary or ASCII.
///
/// `stl_io::read_stl` decides between ASCII and binary by checking whether
/// the first line starts with `"solid "`. That misreads binary files whose
/// header starts with "solid" (common) and ASCII files whose first line is a
/// bare `solid`. The format is therefore decided here: a file whose size
/// matches the triangle count of a binary header is binary; otherwise a text
/// file (no NUL byte) starting with `solid` is ASCII; anything else is
/// binary. The bytes handed to stl_io are adjusted so that it takes the same
/// decision.
fn parse_stl(path: &Path, bytes: &[u8]) -> Result<MeshData, MeshError> {
    let parse_error = |format: &'static str, message: String| MeshError::Parse {
        path: path.to_path_buf(),
        format,
        message,
    };

    let (declared_triangles, ascii) = stl_layout(bytes);
    let binary_size =
        declared_triangles.map(|n| STL_BINARY_HEADER as u64 + STL_BINARY_TRIANGLE * u64::from(n));

    // An ASCII file with carriage returns alone (classic Mac OS) ends its lines with them.
    let converted: Vec<u8>;
    let bytes = match lone_carriage_returns(bytes).filter(|_| ascii) {
        Some(lines) => {
            converted = lines;
            &converted[..]
        }
        None => bytes,
    };
    let (format, input): (&'static str, Cow<'_, [u8]>) = if ascii {
        // ASCII. Replace the first line by one stl_io accepts ("solid " + name).
        let start = solid_keyword_offset(bytes).unwrap_or(0);
        let rest = match bytes[start..].iter().position(|&b| b == b'\n') {
            Some(newline) => &bytes[start + newline + 1..],
            None => &[][..],
        };
        // A file of several solids (`endsolid`, then `solid` again) is read whole: the lines
        // between them are dropped, and one `endsolid` ends the one solid read (also when
        // the file has none, as Assimp-based readers such as coal and MoveIt read it).
        // Keywords are lower-case, as those readers need them.
        let mut normalised = b"solid mesh\n".to_vec();
        let (mut ended, mut closed) = (false, false);
        for line in rest.split_inclusive(|&b| b == b'\n') {
            // A file without `endsolid` must have a facet to be taken as ASCII STL (a binary
            // file whose header starts with `solid` may look like one line of text).
            // `endsolid` then anything, as Assimp reads it (a name after a no-break space).
            let first = match words(line).next() {
                Some(w) if w.starts_with(b"endsolid") => Some(&b"endsolid"[..]),
                other => other,
            };
            closed |= matches!(first, Some(b"endsolid") | Some(b"endfacet"));
            match first {
                Some(b"endsolid") => ended = true,
                Some(b"solid") if ended => ended = false,
                None => {} // a blank line
                // Normals are not used (and may be NaN): the reader gets zeros.
                Some(b"facet")
                    if words(line).nth(1) == Some(b"normal") && words(line).count() == 5 =>
                {
                    ended = false;
                    normalised.extend_from_slice(b"facet normal 0 0 0\n");
                }
                _ => {
                    ended = false;
                    normalised.extend_from_slice(line);
                    if !line.ends_with(b"\n") {
                        normalised.push(b'\n');
                    }
                }
            }
        }
        if closed {
            normalised.extend_from_slice(b"endsolid mesh\n");
        }
        ("ASCII STL", Cow::Owned(normalised))
    } else {
        let format = "binary STL";
        let (Some(count), Some(expected)) = (declared_triangles, binary_size) else {
            let message = if bytes.is_empty() {
                "the file is empty".to_string()
            } else {
                format!(
                    "the file has {} bytes, fewer than the {STL_BINARY_HEADER}-byte header \
                         of a binary STL, and does not start with \"solid\" like an ASCII STL",
                    bytes.len()
                )
            };
            return Err(parse_error(format, message));
        };
        if count as usize > crate::limits::MAX_MESH_TRIANGLES {
            return Err(parse_error(
                format,
                format!(
                    "the header declares {count} triangles, more than the limit of {}",
                    crate::limits::MAX_MESH_TRIANGLES
                ),
            ));
        }
        if (bytes.len() as u64) < expected {
            return Err(parse_error(
                format,
                format!(
                    "the header declares {count} triangles, which need {expected} bytes, \
                         but the file has only {} bytes",
                    bytes.len()
                ),
            ));
        }
        if bytes.len() as u64 >= expected + STL_BINARY_TRIANGLE {
            // A whole triangle record or more past the declared ones: the count is wrong
            // (reading it would silently drop triangles). Shorter trailers are padding.
            return Err(parse_error(
                format,
                format!(
                    "the header declares {count} triangles, which need {expected} bytes, \
                         but the file has {} bytes: the count is wrong",
                    bytes.len()
                ),
            ));
        }
        if bytes.starts_with(b"solid") {
            // Blank the header so stl_io does not take it for ASCII.
            let mut patched = bytes.to_vec();
            patched[..80].fill(0);
            (format, Cow::Owned(patched))
        } else {
            (format, Cow::Borrowed(bytes))
        }
    };

    let indexed = stl_io::read_stl(&mut Cursor::new(input.as_ref())).map_err(|e| {
        let said = e.to_string().replace('\n', " ");
        // An ASCII file's fault is named by its line, as the reader checks it.
        match ascii.then(|| ascii_stl_error_line(bytes)).flatten() {
            Some((line, what, text)) => {
                parse_error(format, format!("line {line}: {what}: `{text}`"))
            }
            None => parse_error(format, said),
        }
    })?;
    if indexed.faces.len() > crate::limits::MAX_MESH_TRIANGLES {
        return Err(parse_error(
            format,
            format!(
                "{} triangles, more than the limit of {}",
                indexed.faces.len(),
                crate::limits::MAX_MESH_TRIANGLES
            ),
        ));
    }
    let vertices = indexed
        .vertices
        .iter()
        .map(|v| v.0.map(f64::from))
        .collect();
    let triangles = indexed
        .faces
        .iter()
        .map(|face| {
            let [a, b, c] = face.vertices;
            match (u32::try_from(a), u32::try_from(b), u32::try_from(c)) {
                (Ok(a), Ok(b), Ok(c)) => Ok([a, b, c]),
                _ => Err(parse_error(
                    format,
                    "more than 2^32 distinct vertices".to_string(),
                )),
            }
        })
        .collect::<Result<_, _>>()?;
    Ok(MeshData {
        vertices,
        triangles,
    })
}

/// Offset of the `solid` keyword if the bytes (after an optional UTF-8 byte
/// order mark and whitespace) start with it, case-insensitively.
fn solid_keyword_offset(bytes: &[u8]) -> Option<usize> {
    let bom = if bytes.starts_with(b"\xEF\xBB\xBF") {
        3
    } else {
        0
    };
    let start = bom
        + bytes[bom..]
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(bytes.len() - bom);
    let word = bytes.get(start..start + 5)?;
    let after = bytes.get(start + 5).copied();
    (word.eq_ignore_ascii_case(b"solid") && after.is_none_or(|b| b.is_ascii_whitespace()))
        .then_some(start)
}

/// The first line of the ASCII STL `bytes` that breaks the grammar stl_io reads (blank lines
/// skipped; the first line is the `solid` header): `facet normal x y z` or `endsolid`, then
/// `outer loop`, three `vertex x y z`, `endloop`, `endfacet`, with every number a finite
/// 32-bit float. Its number (from 1), what was expected and its text as [`quote`] gives it;
/// for a file that ends early, its last line. `None` when no line breaks it.
fn ascii_stl_error_line(bytes: &[u8]) -> Option<(usize, String, String)> {
    /// What the next line must be.
    #[derive(Clone, Copy, PartialEq)]
    enum Next {
        Header,
        AfterEnd,
        Facet,
        Loop,
        Vertex(u8),
        EndLoop,
        EndFacet,
    }
    let finite = |w: &str| w.parse::<f32>().is_ok_and(f32::is_finite);
    let numbers = |words: &[&str]| -> Option<String> {
        words.iter().find(|w| !finite(w)).map(|w| {
            format!(
                "`{}` is not a finite 32-bit number",
                crate::error::shorten(w)
            )
        })
    };
    // From the `solid` keyword on (after a byte order mark or blank lines), numbered in the file.
    let start = solid_keyword_offset(bytes).unwrap_or(0);
    let before = bytes[..start].iter().filter(|&&b| b == b'\n').count();
    let mut next = Next::Header;
    let mut facets = 0usize;
    let mut last = (0, String::new());
    for (number, raw) in bytes[start..].split(|&b| b == b'\n').enumerate() {
        let number = number + before;
        let line = String::from_utf8_lossy(raw);
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.is_empty() {
            continue;
        }
        last = (number + 1, quote(&line));
        let fault = match next {
            Next::Header => {
                next = Next::Facet;
                None
            }
            // Another solid may follow; the reader takes them all as one.
            Next::AfterEnd => {
                next = Next::Facet;
                (words[0] != "solid").then(|| "expected `solid` or the end of the file".to_string())
            }
            Next::Facet if words[0] == "endsolid" => {
                next = Next::AfterEnd;
                None
            }
            Next::Facet => {
                next = Next::Loop;
                facets += 1;
                // The normal's values are not read (see `parse_stl`).
                (words.len() != 5 || words[0] != "facet" || words[1] != "normal")
                    .then(|| "expected `facet normal x y z` or `endsolid`".to_string())
            }
            Next::Loop => {
                next = Next::Vertex(0);
                (words != ["outer", "loop"]).then(|| "expected `outer loop`".to_string())
            }
            Next::Vertex(k) => {
                next = if k == 2 {
                    Next::EndLoop
                } else {
                    Next::Vertex(k + 1)
                };
                if words.len() != 4 || words[0] != "vertex" {
                    Some("expected `vertex x y z`".to_string())
                } else {
                    numbers(&words[1..])
                }
            }
            Next::EndLoop => {
                next = Next::EndFacet;
                (words != ["endloop"]).then(|| "expected `endloop`".to_string())
            }
            Next::EndFacet => {
                next = Next::Facet;
                (words != ["endfacet"]).then(|| "expected `endfacet`".to_string())
            }
        };
        if let Some(mut what) = fault {
            // A keyword in capitals: Assimp-based readers (coal, MoveIt) refuse it too.
            const KEYWORDS: [&str; 9] = [
                "solid", "facet", "normal", "outer", "loop", "vertex", "endloop", "endfacet",
                "endsolid",
            ];
            let capital = |w: &str| w != w.to_ascii_lowercase();
            let keyword = |w: &str| KEYWORDS.contains(&w.to_ascii_lowercase().as_str());
            if words.iter().take(2).any(|w| capital(w) && keyword(w)) {
                what.push_str(
                    " (in lower case, as Assimp-based readers such as coal and MoveIt read it)",
                );
            }
            return Some((number + 1, what, last.1));
        }
    }
    // A file may end after a whole facet without `endsolid`.
    if next == Next::AfterEnd || (next == Next::Facet && facets > 0) {
        return None;
    }
    if next == Next::Header || next == Next::Facet {
        let (line, text) = last;
        return Some((line, "the file ends before `endsolid`".to_string(), text));
    }
    let (line, text) = last;
    Some((line, "the file ends inside a facet".to_string(), text))
}

/// Parses OBJ bytes with tobj, merging all models into one mesh.
fn parse_obj(path: &Path, bytes: &[u8]) -> Result<MeshData, MeshError> {
    let parse_error = |message: String| MeshError::Parse {
        path: path.to_path_buf(),
        format: "OBJ",
        message,
    };
    // A byte order mark would hide the first line's keyword; a file with carriage returns
    // only (classic Mac OS) ends its lines with them.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let converted: Vec<u8>;
    let bytes = match lone_carriage_returns(bytes) {
        Some(lines) => {
            converted = lines;
            &converted[..]
        }
        None => bytes,
    };
    // Text in another encoding (Latin-1 is common) only in comments and names does not touch
    // the geometry: those lines are read with the bytes replaced. Elsewhere it is an error.
    let lossy: Vec<u8>;
    let bytes = if std::str::from_utf8(bytes).is_err() && obj_bad_text_only_in_names(bytes) {
        lossy = String::from_utf8_lossy(bytes).into_owned().into_bytes();
        &lossy[..]
    } else {
        bytes
    };
    // What Assimp-based readers (coal, MoveIt) read otherwise is refused; polylines and points
    // are dropped, and comments after geometry, before tobj reads the file.
    let prepared: Vec<u8>;
    let bytes = match obj_prepare(bytes) {
        Err((line, text, why)) => {
            return Err(parse_error(format!("line {line}: {why}: `{text}`")));
        }
        Ok(Some(rewritten)) => {
            prepared = rewritten;
            &prepared[..]
        }
        Ok(None) => bytes,
    };
    // Count triangles and vertices before tobj builds them, so a small file of long polygons
    // cannot expand into gigabytes.
    let (triangles, vertices) = obj_counts(bytes);
    let limit = crate::limits::MAX_MESH_TRIANGLES;
    if triangles > limit || vertices > limit {
        return Err(parse_error(format!(
            "{triangles} triangles and {vertices} vertices: more than the limit of {limit}"
        )));
    }
    // tobj drops a face of one or two vertices as a point or a line: a face needs three.
    if let Some((line, text)) = obj_short_face(bytes) {
        return Err(parse_error(format!(
            "line {line}: a face needs at least 3 vertices: `{text}`"
        )));
    }
    // The struct update covers fields that only exist with tobj's optional
    // `merging` and `reordering` features.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // Material libraries are irrelevant for collision geometry: never read them.
    let (models, _materials) =
        tobj::load_obj_buf(
            &mut Cursor::new(bytes),
            &options,
            |_| Ok(Default::default()),
        )
        .map_err(|e| {
            // Reading from memory only fails on bad UTF-8.
            let what = match e {
                tobj::LoadError::ReadError => "the file is not valid UTF-8 text".to_string(),
                other => other.to_string(),
            };
            parse_error(match obj_error_line(bytes, e) {
                Some((line, text)) => format!("line {line}: {what}: `{text}`"),
                None => what,
            })
        })?;

    let mut mesh = MeshData::default();
    for model in &models {
        let base = u32::try_from(mesh.vertices.len())
            .map_err(|_| parse_error("more than 2^32 vertices".to_string()))?;
        let positions = &model.mesh.positions;
        if positions.len() % 3 != 0 || model.mesh.indices.len() % 3 != 0 {
            return Err(parse_error(format!(
                "object \"{}\" has a position or index count that is not a multiple of 3",
                model.name
            )));
        }
        mesh.vertices.extend(
            positions
                .chunks_exact(3)
                .map(|p| [obj_float(p[0]), obj_float(p[1]), obj_float(p[2])]),
        );
        for tri in model.mesh.indices.chunks_exact(3) {
            let shifted = [tri[0], tri[1], tri[2]].map(|i| base.checked_add(i));
            let [Some(a), Some(b), Some(c)] = shifted else {
                return Err(parse_error("more than 2^32 vertices".to_string()));
            };
            mesh.triangles.push([a, b, c]);
        }
    }
    // A coordinate tobj read as NaN or infinite ("nan", "inf", 1e400), used by a face or not,
    // is named by its line, which an OBJ author can find (the merged mesh numbers its vertices
    // differently).
    if let Some((line, text)) = obj_non_finite_line(bytes) {
        return Err(parse_error(format!(
            "line {line}: a vertex coordinate is not finite: `{text}`"
        )));
    }
    Ok(mesh)
}

/// A line [`obj_prepare`] refuses: its number (from 1), its text as [`quote`] gives it, and why.
type ObjRefusal = (usize, String, &'static str);

/// The OBJ `bytes` as tobj is given them, or the first line that Assimp-based readers (coal,
/// MoveIt, so the independent checkers of a plan) read otherwise than tobj, with its text and
/// why. Refused: a `v`, `vt`, `vn` or `f` line that is indented or holds a space other than a
/// blank or a tab (Assimp skips it), a vertex coordinate written with a bare leading dot such
/// as `.5` (Assimp drops the vertex), any line ending in a backslash (Assimp joins the next
/// line to it). Rewritten, when present
/// (`Some`; lines keep their numbers): `l` and `p` lines are emptied (tobj would fill a
/// polyline of three or more points as a polygon; Assimp drops lines and points, as collision
/// geometry must), a `#` comment after the data of a `v`, `vt`, `vn` or `f` line is cut
/// (tobj cannot read it; Assimp skips it), a vertex colour is dropped (tobj refuses colours
/// on some vertices only; Assimp reads them; neither is geometry), and when a face uses a
/// position a later object defines (Assimp reads indices over the whole file, tobj over what
/// the face's object has read at its end), the `o` and `g` lines are emptied (the objects are
/// merged into one mesh anyway).
fn obj_prepare(bytes: &[u8]) -> Result<Option<Vec<u8>>, ObjRefusal> {
    const GEOMETRY: [&[u8]; 6] = [b"v", b"vt", b"vn", b"f", b"l", b"p"];
    let refuse = |number: usize, raw: &[u8], why: &'static str| {
        Err((number + 1, quote(&String::from_utf8_lossy(raw)), why))
    };
    let mut rewrite = false;
    // Per object (from an `o` or `g` line on), the counts of positions, texture coordinates and
    // normals at its end and the largest positive index its faces use of each.
    let mut ends: Vec<[usize; 3]> = Vec::new();
    let mut used: Vec<[usize; 3]> = vec![[0; 3]];
    let mut counts = [0usize; 3];
    for (number, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let first = words(raw).next().unwrap_or(b"");
        match first {
            b"v" => counts[0] += 1,
            b"vt" => counts[1] += 1,
            b"vn" => counts[2] += 1,
            b"o" | b"g" => {
                ends.push(counts);
                used.push([0; 3]);
            }
            b"f" => {
                let data = raw.split(|&b| b == b'#').next().unwrap_or(raw);
                let last = used.last_mut().expect("one object at least");
                for vertex in words(data).skip(1) {
                    for (k, index) in vertex.split(|&b| b == b'/').take(3).enumerate() {
                        let index = std::str::from_utf8(index).ok().and_then(|i| i.parse().ok());
                        if let Some(i) = index.filter(|&i: &usize| i > 0) {
                            last[k] = last[k].max(i);
                        }
                    }
                }
            }
            _ => {}
        }
        let geometry = GEOMETRY.contains(&first);
        let data = raw.split(|&b| b == b'#').next().unwrap_or(raw);
        // As tobj splits a line: at any Unicode space (a vertical tab, a no-break space).
        let text = String::from_utf8_lossy(data);
        let keyword = text.split_whitespace().next().unwrap_or("");
        if ["v", "vt", "vn", "f"].contains(&keyword) {
            if text.starts_with(char::is_whitespace) {
                return refuse(
                    number,
                    raw,
                    "an indented line, which Assimp-based readers (coal, MoveIt) skip: remove the leading spaces",
                );
            }
            if text.contains(|c: char| c.is_whitespace() && !matches!(c, ' ' | '\t' | '\r')) {
                return refuse(
                    number,
                    raw,
                    "a space other than a blank or a tab, which Assimp-based readers (coal, MoveIt) do not read as one: use blanks",
                );
            }
        }
        if first == b"v" && words(data).skip(1).any(|w| w.starts_with(b".")) {
            return refuse(
                number,
                raw,
                "a coordinate written with a bare leading dot, whose vertex Assimp-based readers (coal, MoveIt) drop: write 0.5 for .5",
            );
        }
        if raw.strip_suffix(b"\r").unwrap_or(raw).ends_with(b"\\") {
            return refuse(
                number,
                raw,
                "a line ending in a backslash, to which Assimp-based readers (coal, MoveIt) join the next line: remove the backslash",
            );
        }
        rewrite |= matches!(first, b"l" | b"p")
            || (geometry && raw.contains(&b'#'))
            || (first == b"v" && obj_coloured(raw));
    }
    ends.push(counts);
    // A face that uses a position (texture coordinate, normal) a later object defines: Assimp
    // reads indices over the whole file, tobj only over what its object's end has read. As the
    // objects are merged anyway, their `o` and `g` lines are then emptied.
    let forward = used
        .iter()
        .zip(&ends)
        .any(|(u, e)| (0..3).any(|k| u[k] > e[k] && u[k] <= counts[k]));
    rewrite |= forward;
    if !rewrite {
        return Ok(None);
    }
    let mut out = Vec::with_capacity(bytes.len());
    for (number, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        if number > 0 {
            out.push(b'\n');
        }
        let first = words(raw).next().unwrap_or(b"");
        if matches!(first, b"l" | b"p") || (forward && matches!(first, b"o" | b"g")) {
            continue;
        }
        let keep = match raw.iter().position(|&b| b == b'#') {
            Some(cut) if GEOMETRY.contains(&first) => &raw[..cut],
            _ => raw,
        };
        if first == b"v" && obj_coloured(keep) {
            // The position alone: tobj refuses colours on some vertices and not others.
            for w in words(keep).take(4) {
                out.extend_from_slice(w);
                out.push(b' ');
            }
        } else {
            out.extend_from_slice(keep);
        }
    }
    Ok(Some(out))
}

/// True when the OBJ `v` line `raw` (its comment cut) holds a colour: six numbers, a position
/// and red, green, blue (as Assimp reads six; tobj too, but only when every vertex has one).
fn obj_coloured(raw: &[u8]) -> bool {
    let data = raw.split(|&b| b == b'#').next().unwrap_or(raw);
    words(data).count() == 7
}

/// True when every line of the OBJ `bytes` that is not valid UTF-8 is a comment or names
/// something (`#`, `o`, `g`, `s`, `usemtl`, `mtllib`): lines whose text does not matter to the
/// geometry.
fn obj_bad_text_only_in_names(bytes: &[u8]) -> bool {
    bytes
        .split(|&b| b == b'\n')
        .filter(|line| std::str::from_utf8(line).is_err())
        .all(|line| {
            let first = words(line).next().unwrap_or(b"");
            first.starts_with(b"#") || matches!(first, b"o" | b"g" | b"s" | b"usemtl" | b"mtllib")
        })
}

/// The first `f` line of the OBJ `bytes` with fewer than three vertices, with its text as
/// [`quote`] gives it.
fn obj_short_face(bytes: &[u8]) -> Option<(usize, String)> {
    bytes
        .split(|&b| b == b'\n')
        .enumerate()
        .find_map(|(number, raw)| {
            let mut words = words(raw);
            (words.next() == Some(b"f") && words.count() < 3)
                .then(|| (number + 1, quote(&String::from_utf8_lossy(raw))))
        })
}

/// The first `v` line of the OBJ `bytes` whose position (divided by its `w`, as tobj reads
/// it) is not finite, with its text as [`quote`] gives it.
fn obj_non_finite_line(bytes: &[u8]) -> Option<(usize, String)> {
    bytes
        .split(|&b| b == b'\n')
        .enumerate()
        .find_map(|(number, raw)| {
            let line = std::str::from_utf8(raw).ok()?;
            let mut words = line.split_whitespace();
            if words.next() != Some("v") {
                return None;
            }
            // Up to five numbers (x y z, then w, or a colour), without allocating per line.
            let mut values = [0.0f64; 5];
            let mut n = 0;
            for x in words.map_while(|w| w.parse::<f64>().ok()).take(5) {
                values[n] = x;
                n += 1;
            }
            let w = if n == 4 { values[3] } else { 1.0 };
            let bad = values[..n.min(3)].iter().any(|x| !(x / w).is_finite());
            bad.then(|| (number + 1, quote(line)))
        })
}

/// Longest excerpt of an offending line quoted in an error message (in characters).
const QUOTED_LINE: usize = 60;

/// The line (from 1) of the OBJ `bytes` that makes tobj fail with `error`, and its text
/// (trimmed, cut to [`QUOTED_LINE`] characters): the first line that breaks the rule behind
/// that error, checked as tobj checks it. `None` when the error is not about one line (or no
/// line breaks the rule).
fn obj_error_line(bytes: &[u8], error: tobj::LoadError) -> Option<(usize, String)> {
    use tobj::LoadError as E;
    let floats = |words: &[&str], n: usize| {
        words.len() >= n && words[..n].iter().all(|w| w.parse::<f64>().is_ok())
    };
    // The positions, texture coordinates and normals read when each object ends (at the next
    // `o` or `g` line, or the end of the file): tobj checks a face's positive indices then.
    let mut ends: Vec<[usize; 3]> = Vec::new();
    if error == E::FaceVertexOutOfBounds
        || error == E::FaceTexCoordOutOfBounds
        || error == E::FaceNormalOutOfBounds
    {
        let mut counts = [0usize; 3];
        for line in bytes.split(|&b| b == b'\n') {
            match String::from_utf8_lossy(line).split_whitespace().next() {
                Some("v") => counts[0] += 1,
                Some("vt") => counts[1] += 1,
                Some("vn") => counts[2] += 1,
                Some("o") | Some("g") => ends.push(counts),
                _ => {}
            }
        }
        ends.push(counts);
    }
    let mut object = 0;
    let (mut v, mut vt, mut vn) = (0isize, 0isize, 0isize);
    for (number, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let Ok(line) = std::str::from_utf8(raw) else {
            return (error == E::ReadError)
                .then(|| (number + 1, quote(&String::from_utf8_lossy(raw))));
        };
        let mut words = line.split_whitespace();
        let key = words.next();
        let words: Vec<&str> = words.collect();
        let bad = match key {
            Some("v") => {
                let rest = words.get(3..).unwrap_or(&[]);
                let fails = match error {
                    E::PositionParseError => {
                        !floats(&words, 3) || (rest.len() == 1 && rest[0].parse::<f64>().is_err())
                    }
                    E::ScalingByZeroError => {
                        rest.len() == 1 && rest[0].parse::<f64>().is_ok_and(|w| w == 0.0)
                    }
                    E::ColorParseError => rest.len() == 2 || rest.len() > 3,
                    _ => false,
                };
                v += 1;
                fails
            }
            Some("vt") => {
                vt += 1;
                error == E::TexcoordParseError && !floats(&words, 2)
            }
            Some("vn") => {
                vn += 1;
                error == E::NormalParseError && !floats(&words, 3)
            }
            Some("o") | Some("g") => {
                object += 1;
                false
            }
            // tobj parses `l` lines as faces but (ignoring lines) never resolves their indices.
            Some(kind @ ("f" | "l")) => words.iter().any(|corner| {
                let parts: Vec<&str> = corner.split('/').collect();
                if error == E::FaceParseError {
                    return parts.iter().skip(3).any(|p| !p.is_empty())
                        || parts
                            .iter()
                            .any(|p| !p.is_empty() && p.parse::<isize>().is_err());
                }
                if kind == "l" {
                    return false;
                }
                let end = ends.get(object).copied().unwrap_or_default();
                // Index `k` of a corner against the count seen so far (negative, relative)
                // or at the end of its object (positive, from 1). A position index of 0 is
                // out of range; a texture or normal index of 0 counts as none.
                let out = |k: usize, seen: isize, total: usize| {
                    parts
                        .get(k)
                        .and_then(|p| p.parse::<isize>().ok())
                        .is_some_and(|i| {
                            if i < 0 {
                                seen + i < 0
                            } else {
                                (i == 0 && k == 0) || i as usize > total
                            }
                        })
                };
                match error {
                    E::FaceVertexOutOfBounds => out(0, v, end[0]),
                    E::FaceTexCoordOutOfBounds => end[1] > 0 && out(1, vt, end[1]),
                    E::FaceNormalOutOfBounds => end[2] > 0 && out(2, vn, end[2]),
                    _ => false,
                }
            }),
            Some("usemtl") => {
                error == E::MaterialParseError
                    && line
                        .split_once(' ')
                        .is_none_or(|(_, name)| name.trim().is_empty())
            }
            _ => false,
        };
        if bad {
            return Some((number + 1, quote(line)));
        }
    }
    None
}

/// `line` trimmed and cut to [`QUOTED_LINE`] characters (with `…` when cut), for an error
/// message.
fn quote(line: &str) -> String {
    let line = line.trim();
    match line.char_indices().nth(QUOTED_LINE) {
        Some((cut, _)) => format!("{}…", &line[..cut]),
        None => line.to_string(),
    }
}

/// Widens a tobj coordinate to `f64` (tobj parses `f64` with its `use_f64`
/// feature and `f32` without; this works with either).
fn obj_float(x: impl Into<f64>) -> f64 {
    x.into()
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d_f64::query::PointQuery;
    use std::collections::HashMap;
    use std::time::Instant;

    fn p(x: f64, y: f64, z: f64) -> Vector {
        Vector::new(x, y, z)
    }

    /// Extrudes a counter-clockwise polygon of the `(x, z)` plane along `+y`
    /// by `depth`; `caps` triangulates the polygon (counter-clockwise too).
    fn extrude(profile: &[[f64; 2]], caps: &[[u32; 3]], depth: f64) -> MeshData {
        let n = profile.len() as u32;
        let mut vertices: Vec<[f64; 3]> = profile.iter().map(|q| [q[0], 0.0, q[1]]).collect();
        vertices.extend(profile.iter().map(|q| [q[0], depth, q[1]]));
        // Counter-clockwise in (x, z) faces -y: right for the front cap.
        let mut triangles: Vec<[u32; 3]> = caps.to_vec();
        triangles.extend(caps.iter().map(|&[a, b, c]| [a + n, c + n, b + n]));
        for i in 0..n {
            let j = (i + 1) % n;
            triangles.push([i, i + n, j + n]);
            triangles.push([i, j + n, j]);
        }
        MeshData {
            vertices,
            triangles,
        }
    }

    /// The unit cube [0, 1]^3.
    fn cube() -> MeshData {
        extrude(
            &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            &[[0, 1, 2], [0, 2, 3]],
            1.0,
        )
    }

    /// A U: a 3 × 1 bar (z in [0, 1]) with two 1-wide pillars up to z = 3,
    /// extruded 1 along y; the notch is x in [1, 2], z in [1, 3].
    fn u_shape() -> MeshData {
        extrude(
            &[
                [0.0, 0.0],
                [3.0, 0.0],
                [3.0, 3.0],
                [2.0, 3.0],
                [2.0, 1.0],
                [1.0, 1.0],
                [1.0, 3.0],
                [0.0, 3.0],
            ],
            &[
                [0, 1, 4],
                [1, 2, 4],
                [2, 3, 4],
                [0, 4, 5],
                [0, 5, 6],
                [0, 6, 7],
            ],
            1.0,
        )
    }

    /// The same surface with every triangle given its own three vertices.
    fn soup(mesh: &MeshData) -> MeshData {
        let mut out = MeshData::default();
        for tri in &mesh.triangles {
            let base = out.vertices.len() as u32;
            out.vertices
                .extend(tri.iter().map(|&i| mesh.vertices[i as usize]));
            out.triangles.push([base, base + 1, base + 2]);
        }
        out
    }

    fn signed_volume(mesh: &MeshData) -> f64 {
        mesh.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
                a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0])
            })
            .sum::<f64>()
            / 6.0
    }

    /// Checks that every directed edge appears exactly once and its reverse
    /// exactly once: the surface is closed and consistently oriented.
    fn assert_closed_and_oriented(name: &str, mesh: &MeshData) {
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(count, 1, "{name}: edge {a}->{b} appears {count} times");
            assert_eq!(
                directed.get(&(b, a)),
                Some(&1),
                "{name}: edge {a}->{b} has no matching opposite edge"
            );
        }
    }

    fn binary_stl_bytes(mesh: &MeshData, header: &[u8]) -> Vec<u8> {
        let mut bytes = header.to_vec();
        bytes.resize(80, b' ');
        bytes.extend_from_slice(&(mesh.triangles.len() as u32).to_le_bytes());
        for tri in &mesh.triangles {
            bytes.extend_from_slice(&[0u8; 12]);
            for &i in tri {
                for c in mesh.vertices[i as usize] {
                    bytes.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
            bytes.extend_from_slice(&[0u8; 2]);
        }
        bytes
    }

    #[test]
    fn triangles_are_counted_as_the_readers_find_them() {
        let dir = tempfile::tempdir().unwrap();
        let ascii = "solid two\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
                     vertex 0 1 0\nendloop\nendfacet\n  facet normal 0 0 1\nouter loop\n\
                     vertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid two\n";
        let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nf 1 2 3 4\nf 1 2 5\n";
        let cases = [
            // A binary header that starts with "solid" is still binary.
            (
                "cube.stl",
                binary_stl_bytes(&cube(), b"solid cube exported by some CAD tool"),
            ),
            ("two.stl", ascii.as_bytes().to_vec()),
            ("fan.obj", obj.as_bytes().to_vec()),
        ];
        for (name, bytes) in cases {
            let path = write(&dir, name, &bytes);
            let read = load_mesh(&path).unwrap().triangles.len();
            assert_eq!(count_triangles(&path), Some(read), "{name}");
        }
        assert_eq!(count_triangles(&dir.path().join("missing.stl")), None);
        assert_eq!(count_triangles(&write(&dir, "m.ply", b"ply")), None);
    }

    fn write(dir: &tempfile::TempDir, name: &str, contents: &[u8]) -> PathBuf {
        let path = dir.path().join(name);
        std::fs::write(&path, contents).unwrap();
        path
    }

    fn load_err(path: &Path) -> String {
        let err = load_mesh(path).expect_err("loading should fail");
        assert_eq!(err.path(), path);
        let message = err.to_string();
        assert!(
            message.starts_with(&format!("{}: ", path.display())),
            "message does not start with the path: {message}"
        );
        message
    }

    const TETRA_ASCII: &str = "solid tetra
  facet normal 0 0 -1
    outer loop
      vertex 0 0 0
      vertex 0 1 0
      vertex 1 0 0
    endloop
  endfacet
  facet normal 0 -1 0
    outer loop
      vertex 0 0 0
      vertex 1 0 0
      vertex 0 0 1.25
    endloop
  endfacet
  facet normal -1 0 0
    outer loop
      vertex 0 0 0
      vertex 0 0 1.25
      vertex 0 1 0
    endloop
  endfacet
  facet normal 0.577 0.577 0.577
    outer loop
      vertex 1 0 0
      vertex 0 1 0
      vertex 0 0 1.25
    endloop
  endfacet
endsolid tetra
";

    #[test]
    fn loads_binary_stl() {
        let dir = tempfile::tempdir().unwrap();
        let mut cube = cube();
        cube.vertices[6] = [1.0, 1.0, 1.5];
        let path = write(&dir, "cube.stl", &stl_io_bytes(&cube));
        let mesh = load_mesh(&path).unwrap();
        assert_eq!(mesh.triangles.len(), 12);
        assert_eq!(mesh.vertices.len(), 8);
        assert!(mesh.vertices.contains(&[1.0, 1.0, 1.5]));
        assert!(mesh.vertices.contains(&[0.0, 1.0, 0.0]));
        assert_closed_and_oriented("cube.stl", &mesh);
        assert!(signed_volume(&mesh) > 1.0);
        assert_eq!(mesh.aabb(), ([0.0, 0.0, 0.0], [1.0, 1.0, 1.5]));
    }

    /// Binary STL written by stl_io's own writer.
    fn stl_io_bytes(mesh: &MeshData) -> Vec<u8> {
        let triangles: Vec<stl_io::Triangle> = mesh
            .triangles
            .iter()
            .map(|t| stl_io::Triangle {
                normal: stl_io::Normal::new([0.0; 3]),
                vertices: t
                    .map(|i| stl_io::Vertex::new(mesh.vertices[i as usize].map(|c| c as f32))),
            })
            .collect();
        let mut bytes = Vec::new();
        stl_io::write_stl(&mut bytes, triangles.iter()).unwrap();
        bytes
    }

    #[test]
    fn loads_binary_stl_whose_header_starts_with_solid() {
        // Many exporters start the binary header with "solid"; stl_io alone
        // would parse such a file as ASCII and fail.
        let dir = tempfile::tempdir().unwrap();
        let bytes = binary_stl_bytes(&cube(), b"solid cube exported by some CAD tool");
        let path = write(&dir, "cube.STL", &bytes);
        let mesh = load_mesh(&path).unwrap();
        assert_eq!((mesh.vertices.len(), mesh.triangles.len()), (8, 12));
        assert_closed_and_oriented("cube.STL", &mesh);
    }

    #[test]
    fn loads_ascii_stl() {
        let dir = tempfile::tempdir().unwrap();
        let path = write(&dir, "tetra.stl", TETRA_ASCII.as_bytes());
        let mesh = load_mesh(&path).unwrap();
        assert_eq!(mesh.triangles.len(), 4);
        assert_eq!(mesh.vertices.len(), 4);
        assert_eq!(
            mesh.vertices,
            vec![
                [0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 0.0, 1.25]
            ]
        );
        assert_eq!(mesh.triangles[0], [0, 1, 2]);
        assert_closed_and_oriented("tetra.stl", &mesh);
        assert!((signed_volume(&mesh) - 1.25 / 6.0).abs() < 1e-12);
    }

    #[test]
    fn loads_ascii_stl_with_bare_solid_line_and_crlf() {
        // stl_io alone requires the first line to start with "solid ".
        let dir = tempfile::tempdir().unwrap();
        let text = TETRA_ASCII
            .replacen("solid tetra", "\u{feff}  solid", 1)
            .replace('\n', "\r\n");
        let path = write(&dir, "tetra.stl", text.as_bytes());
        let mesh = load_mesh(&path).unwrap();
        assert_eq!((mesh.vertices.len(), mesh.triangles.len()), (4, 4));
    }

    #[test]
    fn loads_obj_merging_objects_and_triangulating() {
        let dir = tempfile::tempdir().unwrap();
        let text = "# two objects
mtllib does_not_exist.mtl
o first
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vn 0 0 1
f 1//1 2//1 3//1 4//1
o second
v 0 0 2
v 1 0 2.5
v 0 1 2
l 5 6
f -3 -2 -1
";
        let path = write(&dir, "parts.OBJ", text.as_bytes());
        let mesh = load_mesh(&path).unwrap();
        // The quad becomes two triangles; the line element is ignored.
        assert_eq!(mesh.triangles.len(), 3);
        assert_eq!(mesh.vertices.len(), 7);
        assert_eq!(mesh.triangles[0], [0, 1, 2]);
        assert_eq!(mesh.triangles[1], [0, 2, 3]);
        assert_eq!(mesh.triangles[2], [4, 5, 6]);
        assert_eq!(mesh.vertices[2], [1.0, 1.0, 0.0]);
        assert_eq!(mesh.vertices[5], [1.0, 0.0, 2.5]);
    }

    #[test]
    fn obj_coordinates_keep_f64_precision() {
        let dir = tempfile::tempdir().unwrap();
        let text = "v 0.1 0.2 0.3\nv 1.000000001 0 0\nv 0 1 0\nf 1 2 3\n";
        let path = write(&dir, "precise.obj", text.as_bytes());
        let mesh = load_mesh(&path).unwrap();
        assert_eq!(mesh.vertices[0], [0.1, 0.2, 0.3]);
        assert_eq!(mesh.vertices[1][0], 1.000000001);
    }

    #[test]
    fn error_missing_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("missing.stl");
        let message = load_err(&path);
        assert!(message.contains("cannot read file"), "{message}");
        assert!(matches!(
            load_mesh(&path),
            Err(MeshError::Io { error, .. }) if error.kind() == std::io::ErrorKind::NotFound
        ));
    }

    #[test]
    fn error_unknown_extension() {
        let dir = tempfile::tempdir().unwrap();
        let path = write(&dir, "model.ply", b"ply\n");
        let message = load_err(&path);
        assert!(
            message.ends_with(
                "unsupported mesh format: file extension \".ply\" (expected .stl or .obj)"
            ),
            "{message}"
        );
        let path = write(&dir, "model", b"");
        let message = load_err(&path);
        assert!(message.contains("no file extension"), "{message}");
    }

    #[test]
    fn error_unparseable_files() {
        let dir = tempfile::tempdir().unwrap();

        let text = TETRA_ASCII.replacen("vertex 0 1 0", "vertex 0 one 0", 1);
        let path = write(&dir, "bad_ascii.stl", text.as_bytes());
        let message = load_err(&path);
        assert!(message.contains("cannot parse as ASCII STL"), "{message}");

        let mut bytes = binary_stl_bytes(&cube(), b"");
        bytes.truncate(bytes.len() - 30);
        let path = write(&dir, "truncated.stl", &bytes);
        let message = load_err(&path);
        assert!(
            message.contains("cannot parse as binary STL: the header declares 12 triangles"),
            "{message}"
        );

        // A count smaller than the triangles held: refused, not read short; a short trailer
        // (padding) is accepted.
        let mut bytes = binary_stl_bytes(&cube(), b"");
        bytes[80..84].copy_from_slice(&11u32.to_le_bytes());
        let path = write(&dir, "undercounted.stl", &bytes);
        let message = load_err(&path);
        assert!(
            message.contains("declares 11 triangles, which need 634 bytes, but the file has 684 bytes: the count is wrong"),
            "{message}"
        );
        let mut bytes = binary_stl_bytes(&cube(), b"");
        bytes.extend_from_slice(&[0u8; 49]);
        let path = write(&dir, "padded.stl", &bytes);
        assert_eq!(load_mesh(&path).unwrap().triangles.len(), 12);

        let path = write(&dir, "short.stl", b"not a mesh");
        let message = load_err(&path);
        assert!(
            message.contains("fewer than the 84-byte header"),
            "{message}"
        );

        let path = write(&dir, "empty.stl", b"");
        let message = load_err(&path);
        assert!(message.contains("the file is empty"), "{message}");

        let path = write(
            &dir,
            "bad_face.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
        );
        let message = load_err(&path);
        assert!(
            message.contains(
                "cannot parse as OBJ: line 4: face vertex index out of bounds: `f 1 2 9`"
            ),
            "{message}"
        );

        let path = write(&dir, "binary.obj", b"v 0 0 0\n\xff\xfe\n");
        let message = load_err(&path);
        assert!(message.contains("not valid UTF-8"), "{message}");
    }

    /// OBJ lines that Assimp-based readers (coal, MoveIt) read otherwise than tobj: polylines
    /// and points are dropped, comments after data cut and vertex colours dropped (as Assimp
    /// reads them); indented geometry lines, spaces other than blanks and tabs, bare leading dots
    /// and lines ending in a backslash are refused with their line.
    #[test]
    fn obj_is_read_as_assimp_based_readers_read_it() {
        let dir = tempfile::tempdir().unwrap();
        let v4 = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\n";
        let read = |text: String| load_mesh(&write(&dir, "a.obj", text.as_bytes()));
        let mesh = read(format!("{v4}l 1 2 4\np 1 2 4\nf 1 2 3\n")).unwrap();
        assert_eq!(mesh.triangles.len(), 1, "a polyline is no face");
        assert_eq!(mesh.aabb().1, [1.0, 1.0, 0.0]);
        let mesh = read(format!("{v4}v 0 0 1 # apex\nf 1 2 5 # side\n")).unwrap();
        assert_eq!(mesh.triangles.len(), 1);
        assert_eq!(mesh.aabb().1, [1.0, 0.0, 1.0]);
        assert!(read(format!("{v4}v 0 0 -.5\nf 1 2 5\n")).is_ok());
        // A dot or a backslash in a comment, not ending the line, is no matter; nor is an
        // indented polyline (dropped anyway).
        assert!(read(format!("{v4}v 0 0 1 # .5 m\n# c \\ \n  l 1 2\nf 1 2 5\n")).is_ok());
        // Comments are not counted as corners ahead of reading.
        let path = write(
            &dir,
            "c.obj",
            format!("{v4}f 1 2 3 # one two three four\n").as_bytes(),
        );
        assert_eq!(count_triangles(&path), Some(1));
        // Colours on some vertices only (tobj refused them): the positions are read.
        let mesh = read(format!(
            "v 0 0 0 1 0 0\n{v4}v 0 0 2 0.5 0.5 0.5 # c\nf 3 4 6\n"
        ))
        .unwrap();
        assert_eq!((mesh.triangles.len(), mesh.aabb().1), (1, [1.0, 1.0, 2.0]));
        for (text, expected) in [
            (format!("{v4}  f 1 2 3\n"), "line 5: an indented line"),
            (
                format!("{v4}\tv 0 0 1\nf 1 2 5\n"),
                "line 5: an indented line",
            ),
            (
                format!("{v4}v 0 0 .5\nf 1 2 5\n"),
                "line 5: a coordinate written with a bare leading dot",
            ),
            (
                format!("# apex \\\n{v4}f 1 2 3\n"),
                "line 1: a line ending in a backslash",
            ),
            (
                format!("{v4}v 0 0 1 # apex \\\r\nf 1 2 5\n"),
                "line 5: a line ending in a backslash",
            ),
            (
                format!("{v4}\u{b}v 0 0 1\nf 1 2 5\n"),
                "line 5: an indented line",
            ),
            (
                format!("{v4}v\u{a0}0 0 1\nf 1 2 5\n"),
                "line 5: a space other than a blank or a tab",
            ),
        ] {
            let message = read(text.clone()).unwrap_err().to_string();
            assert!(message.contains(expected), "{text:?}: {message}");
            assert!(
                message.contains("Assimp-based readers (coal, MoveIt)"),
                "{message}"
            );
        }
    }

    /// A file tobj refuses is named with the line that breaks its rule, quoted; so is a
    /// coordinate tobj reads as not finite.
    #[test]
    fn obj_errors_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let good = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
        let cases: [(&str, &str); 15] = [
            ("v 1 2 x", "line 6: position parse error: `v 1 2 x`"),
            ("v 1 2", "line 6: position parse error: `v 1 2`"),
            ("v 1 2 3 0", "line 6: scaling (w) by zero: `v 1 2 3 0`"),
            ("v 1 2 3 4 5", "line 6: color parse error"),
            ("vt 0", "line 6: texcoord parse error: `vt 0`"),
            ("vn 0 1", "line 6: normal parse error: `vn 0 1`"),
            ("f 1 2 3/x", "line 6: face parse error: `f 1 2 3/x`"),
            (
                "f 1 2 0",
                "line 6: face vertex index out of bounds: `f 1 2 0`",
            ),
            (
                "f 1 2 9",
                "line 6: face vertex index out of bounds: `f 1 2 9`",
            ),
            (
                "f -1 -2 -4",
                "line 6: face vertex index out of bounds: `f -1 -2 -4`",
            ),
            (
                "f 1/1 2/2 3/1",
                "line 6: face texcoord index out of bounds: `f 1/1 2/2 3/1`",
            ),
            (
                "v 1 nan 0\nf 1 2 4",
                "line 6: a vertex coordinate is not finite: `v 1 nan 0`",
            ),
            (
                "v 1 nan 0",
                "line 6: a vertex coordinate is not finite: `v 1 nan 0`",
            ),
            ("f 1 2", "line 6: a face needs at least 3 vertices: `f 1 2`"),
            ("f", "line 6: a face needs at least 3 vertices: `f`"),
        ];
        for (bad, expected) in cases {
            let text = format!("{good}{bad}\nf 1 2 3\n");
            let path = write(&dir, "bad.obj", text.as_bytes());
            let message = load_err(&path);
            assert!(message.contains(expected), "{bad:?}: {message}");
        }
        // Where tobj's own rules differ from a plain reading: `l` indices are never resolved, a
        // texture index of 0 is none, an empty fourth part of a corner is allowed, and positive
        // indices count the positions read when their object ends (the whole file's, when a
        // face uses a later object's, as Assimp reads them).
        let v4 = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
        for (text, expected) in [
            (
                format!("{v4}l 1 9\nf 1 2 9\n"),
                "line 6: face vertex index out of bounds",
            ),
            (
                format!("{v4}vt 0 0\nf 1/0 2/1 3/1\nf 1/1 2/1 3/5\n"),
                "line 7: face texcoord index out of bounds",
            ),
            (
                format!("{v4}f 1/1/1/ 2 3\nf 1 2 x\n"),
                "line 6: face parse error",
            ),
            (
                // `f 1 2 5` uses the next object's position, which Assimp reads too.
                format!("o a\n{v4}f 1 2 5\no b\nv 1 1 1\nf 1 2 9\n"),
                "line 9: face vertex index out of bounds: `f 1 2 9`",
            ),
        ] {
            let message = load_err(&write(&dir, "rules.obj", text.as_bytes()));
            assert!(message.contains(expected), "{text:?}: {message}");
        }
        // Another encoding in a comment or a name is read; in a number it is an error.
        let latin = [
            b"# Cr\xe9\xe9 par\no pi\xe8ce\n".as_slice(),
            good.as_bytes(),
            b"f 1 2 3\n",
        ]
        .concat();
        assert!(load_mesh(&write(&dir, "latin.obj", &latin)).is_ok());
        let latin = [good.as_bytes(), b"v 1 \xe9 2\nf 1 2 3\n"].concat();
        let message = load_err(&write(&dir, "latin_bad.obj", &latin));
        assert!(
            message.contains("line 6: the file is not valid UTF-8 text"),
            "{message}"
        );
        // A byte order mark, and carriage returns alone as line ends, are read.
        let bom = format!("\u{feff}{good}f 1 2 3\n");
        assert!(load_mesh(&write(&dir, "bom.obj", bom.as_bytes())).is_ok());
        let classic = format!("{good}f 1 2 3\n").replace('\n', "\r");
        let mesh = load_mesh(&write(&dir, "cr.obj", classic.as_bytes())).unwrap();
        assert_eq!(mesh.triangles.len(), 1);
        let bad = format!("{good}v 1 x 0\n").replace('\n', "\r");
        let message = load_err(&write(&dir, "cr_bad.obj", bad.as_bytes()));
        assert!(
            message.contains("line 6: position parse error"),
            "{message}"
        );
        // A long line is cut.
        let long = format!("{good}f 1 2 {}\n", "9".repeat(200));
        let message = load_err(&write(&dir, "long.obj", long.as_bytes()));
        assert!(message.contains("line 6: face"), "{message}");
        assert!(message.ends_with("…`"), "{message}");
        assert!(message.len() < 250, "{message}");
    }

    /// A face may use positions a later object defines, as Assimp-based readers (coal, MoveIt)
    /// read it: the objects are merged (coal 3.0.3 reads both files below as 2 triangles of 4
    /// vertices, and refuses an index beyond the file's positions, as here).
    #[test]
    fn obj_faces_may_use_positions_of_later_objects() {
        let dir = tempfile::tempdir().unwrap();
        let ahead = "o a\nf 1 2 3\nf 1 3 4\no b\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\n";
        let mesh = load_mesh(&write(&dir, "ahead.obj", ahead.as_bytes())).unwrap();
        assert_eq!(mesh.triangles.len(), 2);
        let corner = |t: usize, k: usize| mesh.vertices[mesh.triangles[t][k] as usize];
        assert_eq!(corner(1, 2), [1.0, 1.0, 1.0]);
        // Relative indices count what is read so far; a later group's position by number.
        let mixed = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nf 1 2 5\ng b\nv 1 1 1\nv 2 2 2\n";
        let mesh = load_mesh(&write(&dir, "mixed.obj", mixed.as_bytes())).unwrap();
        assert_eq!(mesh.triangles.len(), 2);
        let corner = |t: usize, k: usize| mesh.vertices[mesh.triangles[t][k] as usize];
        assert_eq!(
            [corner(0, 0), corner(0, 1), corner(0, 2)],
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        );
        assert_eq!(corner(1, 2), [2.0, 2.0, 2.0]);
        let beyond = "o a\nf 1 2 9\no b\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let message = load_err(&write(&dir, "beyond.obj", beyond.as_bytes()));
        assert!(
            message.contains("line 2: face vertex index out of bounds: `f 1 2 9`"),
            "{message}"
        );
    }

    /// An ASCII STL the reader refuses is named with the line that breaks its grammar, quoted.
    #[test]
    fn ascii_stl_errors_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
        let cases = [
            (
                "facet normal 0 0 1\nouter loop\nvertex 0 0 NaN\n",
                "line 11: `NaN` is not a finite 32-bit number: `vertex 0 0 NaN`",
            ),
            (
                "facet normal 0 0 1\nouter loop\n\n  vertex 0 0 1e39\n",
                "line 12: `1e39` is not a finite 32-bit number: `vertex 0 0 1e39`",
            ),
            (
                "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\n",
                "line 12: expected `vertex x y z`: `endloop`",
            ),
            (
                "facet normal 0 0\n",
                "line 9: expected `facet normal x y z` or `endsolid`: `facet normal 0 0`",
            ),
            (
                "facet normal 0 0 1\nouter  lop\n",
                "line 10: expected `outer loop`: `outer  lop`",
            ),
            (
                "facet normal 0 0 1\nouter loop\n",
                "line 10: the file ends inside a facet: `outer loop`",
            ),
            (
                "FACET NORMAL 0 0 1\nOUTER LOOP\n",
                "line 9: expected `facet normal x y z` or `endsolid` (in lower case, as Assimp-based readers such as coal and MoveIt read it): `FACET NORMAL 0 0 1`",
            ),
        ];
        for (bad, expected) in cases {
            let text = format!("solid x\n{facet}{bad}");
            let message = load_err(&write(&dir, "bad.stl", text.as_bytes()));
            assert!(
                message.contains(&format!("cannot parse as ASCII STL: {expected}")),
                "{bad:?}: {message}"
            );
        }
        let good = format!("solid x\n{facet}endsolid x\n");
        assert!(load_mesh(&write(&dir, "good.stl", good.as_bytes())).is_ok());
        // As Assimp-based readers (coal, MoveIt) read it: a file that ends after a whole facet
        // without `endsolid`.
        let open = format!("solid x\n{facet}{facet}").replacen("vertex 0 0 0", "vertex 0 0 1", 1);
        let open = write(&dir, "open.stl", open.as_bytes());
        assert_eq!(load_mesh(&open).unwrap().triangles.len(), 2);
        // Two solids, the first ended by `endsolid` and a no-break space: both read (coal
        // reads 2 triangles; the second solid was dropped).
        let second = facet.replacen("vertex 0 0 0", "vertex 0 0 1", 1);
        let two = format!("solid a\n{facet}endsolid\u{a0}a\nsolid b\n{second}endsolid b\n");
        let two = write(&dir, "two.stl", two.as_bytes());
        assert_eq!(load_mesh(&two).unwrap().triangles.len(), 2);
        assert_eq!(count_triangles(&two), Some(2));
        // But a header alone (such as a binary file whose header starts with `solid` and has
        // no NUL byte) is no mesh.
        let header = write(&dir, "header.stl", b"solid x 1 2 3 garbage");
        let message = load_err(&header);
        assert!(
            message.contains("line 1: the file ends before `endsolid`"),
            "{message}"
        );
        // Normals are not read (NaN is fine), and carriage returns alone end lines.
        let nan = good.replacen("facet normal 0 0 1", "facet normal nan inf -nan", 1);
        assert!(load_mesh(&write(&dir, "nan.stl", nan.as_bytes())).is_ok());
        let classic = good.replace('\n', "\r");
        let path = write(&dir, "cr.stl", classic.as_bytes());
        assert_eq!(load_mesh(&path).unwrap().triangles.len(), 1);
        assert_eq!(count_triangles(&path), Some(1), "counted ahead as read");
        let mixed = format!("{}\n", classic.trim_end());
        assert_eq!(
            load_mesh(&write(&dir, "mixed.stl", mixed.as_bytes()))
                .unwrap()
                .triangles
                .len(),
            1
        );
        let odd = good.replacen("facet normal 0 0 1", "facet nromal 0 0 1", 1);
        let message = load_err(&write(&dir, "odd.stl", odd.as_bytes()));
        assert!(
            message.contains("line 2: expected `facet normal x y z`"),
            "{message}"
        );
        // After a byte order mark on its own line, lines are still counted from the file's
        // first.
        let bom =
            format!("\u{feff}\nsolid x\n{facet}facet normal 0 0 1\nouter loop\nvertex 0 0 nan\n");
        let message = load_err(&write(&dir, "bom.stl", bom.as_bytes()));
        assert!(
            message.contains("line 12: `nan` is not a finite"),
            "{message}"
        );
        // Several solids are read as one (the reader alone stopped at the first `endsolid`);
        // anything else after an `endsolid` is an error.
        let far = facet.replace("vertex 0 0 0", "vertex 0 0 7");
        let two = format!("solid a\n{facet}endsolid a\n\nsolid b\n{far}endsolid b\n");
        let mesh = load_mesh(&write(&dir, "two.stl", two.as_bytes())).unwrap();
        assert_eq!(mesh.triangles.len(), 2);
        assert_eq!(mesh.aabb().1[2], 7.0);
        let junk = format!("solid a\n{facet}endsolid a\njunk\n");
        let message = load_err(&write(&dir, "junk.stl", junk.as_bytes()));
        assert!(
            message.contains("line 10: expected `solid` or the end of the file: `junk`"),
            "{message}"
        );
    }

    #[test]
    fn error_empty_mesh() {
        let dir = tempfile::tempdir().unwrap();
        let path = write(&dir, "nothing.stl", b"solid nothing\nendsolid nothing\n");
        assert_eq!(
            load_err(&path),
            format!("{}: mesh has no triangles", path.display())
        );
        let path = write(&dir, "points.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n");
        assert!(load_err(&path).ends_with("mesh has no triangles"));
        let path = write(
            &dir,
            "zero.stl",
            &binary_stl_bytes(&MeshData::default(), b""),
        );
        assert!(matches!(load_mesh(&path), Err(MeshError::Empty { .. })));
    }

    #[test]
    fn error_non_finite_vertex() {
        let dir = tempfile::tempdir().unwrap();
        let mut mesh = cube();
        mesh.vertices[3] = [f64::NAN, 0.0, 1.0];
        let path = write(&dir, "nan.stl", &binary_stl_bytes(&mesh, b""));
        let message = load_err(&path);
        assert!(
            message.contains("vertex 3 is not finite: [NaN, 0, 1]"),
            "{message}"
        );

        let path = write(&dir, "inf.obj", b"v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n");
        assert_eq!(
            load_err(&path),
            format!(
                "{}: cannot parse as OBJ: line 2: a vertex coordinate is not finite: `v 1 inf 0`",
                path.display()
            )
        );
    }

    #[test]
    fn error_index_out_of_range() {
        // Both loaders reject such files themselves (tobj as a parse error,
        // stl_io cannot produce them), so check the validation directly.
        let mut mesh = cube();
        mesh.triangles[5] = [0, 1, 8];
        let defect = mesh.validate().unwrap_err();
        assert_eq!(
            defect.to_string(),
            "triangle 5 refers to vertex 8, but the mesh has only 8 vertices"
        );
        let path = Path::new("meshes/broken.obj");
        let message = MeshError::from_defect(path, defect).to_string();
        assert_eq!(
            message,
            "meshes/broken.obj: triangle 5 refers to vertex 8, but the mesh has only 8 vertices"
        );
        assert!(matches!(
            mesh.to_parry_trimesh(),
            Err(ShapeError::InvalidMesh(MeshDefect::IndexOutOfRange { .. }))
        ));
    }

    #[test]
    fn error_degenerate_mesh() {
        let dir = tempfile::tempdir().unwrap();
        let text = "v 0 0 0\nv 1 1 1\nv 2 2 2\nv 3 3 3\nf 1 2 3\nf 1 3 4\nf 2 2 4\n";
        let path = write(&dir, "flat.obj", text.as_bytes());
        assert_eq!(
            load_err(&path),
            format!(
                "{}: mesh is degenerate: every triangle has zero area (3 in all)",
                path.display()
            )
        );
        // A coordinate far beyond any cell makes every other triangle small: it is named.
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv -1e160 0 0\nf 1 2 3\nf 1 2 4\n";
        let path = write(&dir, "far.obj", text.as_bytes());
        assert!(
            load_err(&path).ends_with(
                "every triangle has zero area (2 in all), relative to a vertex coordinate of 1e160: is the unit wrong?"
            ),
            "{}",
            load_err(&path)
        );
    }

    #[test]
    fn non_finite_reported_before_degeneracy() {
        let mut mesh = cube();
        mesh.vertices[7][2] = f64::INFINITY;
        assert_eq!(
            mesh.validate(),
            Err(MeshDefect::NonFiniteVertex {
                index: 7,
                value: [0.0, 1.0, f64::INFINITY]
            })
        );
    }

    #[test]
    fn test_shapes_are_closed_and_outward() {
        for (name, mesh, volume) in [("cube", cube(), 1.0), ("U", u_shape(), 7.0)] {
            assert_closed_and_oriented(name, &mesh);
            assert!((signed_volume(&mesh) - volume).abs() < 1e-12, "{name}");
            mesh.validate().unwrap();
        }
    }

    #[test]
    fn trimesh_tells_inside_from_outside_on_cube() {
        for mesh in [cube(), soup(&cube())] {
            let trimesh = mesh.to_parry_trimesh().unwrap();
            let id = Pose::IDENTITY;
            let inside = [p(0.5, 0.5, 0.5), p(0.99, 0.99, 0.99), p(0.01, 0.5, 0.99)];
            let outside = [
                p(1.5, 0.5, 0.5),
                p(1.1, 1.1, 1.1),
                p(-0.1, -0.1, 0.5),
                p(0.5, 0.5, -0.01),
            ];
            for q in inside {
                assert!(trimesh.contains_point(&id, q), "{q:?} should be inside");
                assert!(trimesh.project_point(&id, q, true).is_inside, "{q:?}");
                assert!(trimesh.project_point(&id, q, false).is_inside, "{q:?}");
            }
            for q in outside {
                assert!(!trimesh.contains_point(&id, q), "{q:?} should be outside");
                assert!(!trimesh.project_point(&id, q, true).is_inside, "{q:?}");
            }
        }
    }

    /// A thin wedge: right triangle with legs 1 (x) and 0.2 (z), extruded 1
    /// along y; its edge along y at x = 1 is sharp (about 11°).
    fn wedge() -> MeshData {
        extrude(&[[0.0, 0.0], [1.0, 0.0], [0.0, 0.2]], &[[0, 1, 2]], 1.0)
    }

    #[test]
    fn trimesh_of_triangle_soup_classifies_points_near_a_sharp_edge() {
        let wedge = wedge();
        assert_closed_and_oriented("wedge", &wedge);
        let trimesh = soup(&wedge).to_parry_trimesh().unwrap();
        let id = Pose::IDENTITY;
        for y in [-0.03, 0.1, 0.5, 0.9, 1.03] {
            for degrees in (-88..=10).step_by(7) {
                let (s, c) = f64::from(degrees).to_radians().sin_cos();
                // Just outside the sharp edge (or its end corners).
                let q = p(1.0 + 0.05 * c, y, 0.05 * s);
                assert!(!trimesh.contains_point(&id, q), "{q:?} should be outside");
            }
        }
        for q in [p(0.95, 0.5, 0.005), p(0.9, 0.01, 0.01), p(0.02, 0.98, 0.19)] {
            assert!(trimesh.contains_point(&id, q), "{q:?} should be inside");
        }
    }

    #[test]
    fn decomposition_refuses_triangles_that_span_the_mesh() {
        use rand::{RngExt, SeedableRng};
        // 10,000 random triangles across a unit box: each spans a large share of the 32³ grid.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut soup = MeshData {
            vertices: Vec::new(),
            triangles: Vec::new(),
        };
        for t in 0..10_000u32 {
            for _ in 0..3 {
                soup.vertices
                    .push(std::array::from_fn(|_| rng.random::<f64>()));
            }
            soup.triangles.push([3 * t, 3 * t + 1, 3 * t + 2]);
        }
        match soup.to_convex_decomposition() {
            Err(ShapeError::DecompositionTooCostly { tests }) => {
                assert!(tests > MAX_DECOMPOSITION_TESTS, "{tests}")
            }
            other => panic!("expected a refusal, got {other:?}"),
        }
        // A small triangle costs the 27 voxels around it; the cube's twelve, at most the grid.
        let cube = cube();
        let tiny = [[0.5, 0.5, 0.5], [0.5001, 0.5, 0.5], [0.5, 0.5001, 0.5]];
        let mut vertices = cube.vertices.clone();
        vertices.extend(tiny);
        let n = cube.vertices.len() as u32;
        assert_eq!(voxel_tests(&vertices, &[[n, n + 1, n + 2]], 32), 27);
        assert!(voxel_tests(&cube.vertices, &cube.triangles, 32) <= 12 * 34 * 34 * 34);
        assert!(cube.to_convex_decomposition().is_ok());
    }

    #[test]
    fn open_trimesh_contains_nothing() {
        // One triangle, and the cube without its last face: points behind them, near and far,
        // are not inside (the pseudo-normals of an open surface would say they are).
        let mut open_cube = cube();
        open_cube.triangles.truncate(open_cube.triangles.len() - 2);
        let triangle = MeshData {
            vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2]],
        };
        assert!(closed_and_oriented(&cube().triangles));
        for mesh in [open_cube, triangle] {
            assert!(!closed_and_oriented(&mesh.triangles));
            let trimesh = mesh.to_parry_trimesh().unwrap();
            for q in [
                p(0.5, 0.5, 0.5),
                p(0.2, 0.2, -0.01),
                p(0.2, 0.2, -50.0),
                p(0.2, 0.2, 50.0),
            ] {
                assert!(!trimesh.contains_point(&Pose::IDENTITY, q), "{q:?}");
                assert!(
                    !trimesh.project_point(&Pose::IDENTITY, q, true).is_inside,
                    "{q:?}"
                );
            }
        }
        // A face turned the wrong way is not consistently oriented.
        let mut flipped = cube();
        flipped.triangles[0].swap(1, 2);
        assert!(!closed_and_oriented(&flipped.triangles));
    }

    /// A triangle repeated (also with its vertices in another order, or as a copy of its
    /// vertices) is kept once; a closed mesh with every face given twice is still the closed
    /// solid, its inside as before.
    #[test]
    fn repeated_triangles_are_kept_once() {
        let mut vertices = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        vertices.extend_from_within(..);
        let mut triangles = vec![[0, 1, 2]; 1000];
        triangles.extend([[1, 2, 0], [0, 2, 1], [3, 4, 5], [5, 4, 3]]);
        let soup = MeshData {
            vertices,
            triangles,
        };
        assert_eq!(soup.to_parry_trimesh().unwrap().indices().len(), 1);
        let mut twice = cube();
        let faces = twice.triangles.len();
        twice.triangles.extend_from_within(..);
        let trimesh = twice.to_parry_trimesh().unwrap();
        assert_eq!(trimesh.indices().len(), faces);
        assert!(trimesh.contains_point(&Pose::IDENTITY, p(0.5, 0.5, 0.5)));
        assert!(!trimesh.contains_point(&Pose::IDENTITY, p(1.5, 0.5, 0.5)));
    }

    #[test]
    fn trimesh_without_orientation_flag_has_no_inside() {
        // Documents why `ORIENTED` is needed.
        let mesh = cube();
        let plain = TriMesh::new(mesh.parry_vertices(), mesh.triangles.clone()).unwrap();
        assert!(!plain.contains_point(&Pose::IDENTITY, p(0.5, 0.5, 0.5)));
    }

    #[test]
    fn shapes_of_u_shape() {
        let mesh = u_shape();
        let id = Pose::IDENTITY;
        let notch = p(1.5, 0.5, 2.0);
        let bar = p(1.5, 0.5, 0.5);
        let pillar = p(0.5, 0.5, 2.5);
        let far = p(1.5, 3.0, 2.0);

        let trimesh = mesh.to_parry_trimesh().unwrap();
        assert!(trimesh.contains_point(&id, bar));
        assert!(trimesh.contains_point(&id, pillar));
        assert!(!trimesh.contains_point(&id, notch));
        assert!(!trimesh.contains_point(&id, far));

        let hull = mesh.to_convex_hull().unwrap();
        assert!(hull.contains_point(&id, bar));
        assert!(hull.contains_point(&id, notch));
        assert!(!hull.contains_point(&id, far));

        let start = Instant::now();
        let decomposition = mesh.to_convex_decomposition().unwrap();
        let elapsed = start.elapsed();
        let parts = decomposition.as_compound().unwrap().shapes().len();
        assert!(
            parts >= 2,
            "a U needs at least two convex parts, got {parts}"
        );
        assert!(decomposition.contains_point(&id, bar));
        assert!(decomposition.contains_point(&id, pillar));
        assert!(!decomposition.contains_point(&id, notch));
        assert!(!decomposition.contains_point(&id, far));
        eprintln!("U-shape decomposition: {parts} parts in {elapsed:?}");
    }

    #[test]
    fn shapes_of_cube() {
        let mesh = cube();
        let id = Pose::IDENTITY;
        let hull = mesh.to_convex_hull().unwrap();
        let decomposition = mesh.to_convex_decomposition().unwrap();
        for shape in [&hull, &decomposition] {
            assert!(shape.contains_point(&id, p(0.5, 0.5, 0.5)));
            assert!(shape.contains_point(&id, p(0.95, 0.05, 0.95)));
            assert!(!shape.contains_point(&id, p(1.05, 0.5, 0.5)));
            assert!(!shape.contains_point(&id, p(0.5, 0.5, -0.05)));
        }
        let (min, max) = ([0.0; 3], [1.0; 3]);
        let aabb = decomposition.compute_local_aabb();
        for k in 0..3 {
            assert!((aabb.mins[k] - min[k]).abs() < 1e-9);
            assert!((aabb.maxs[k] - max[k]).abs() < 1e-9);
        }
    }

    /// The reduced candidate set spans the same hull as all vertices: same hull vertices, far
    /// fewer points for clouds with an interior.
    #[test]
    fn hull_candidates_keep_the_hull_and_drop_interior_points() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let sorted = |mut v: Vec<[f64; 3]>| {
            v.sort_by(|a, b| a.partial_cmp(b).unwrap());
            v
        };
        let hull_points = |points: &[Vector]| -> Vec<[f64; 3]> {
            let (v, _) = parry3d_f64::transformation::try_convex_hull(points).unwrap();
            sorted(v.iter().map(|p| [p.x, p.y, p.z]).collect())
        };
        // A cube full of points, and a ball of points with a few on its sphere.
        let mut cube: Vec<[f64; 3]> = (0..20_000)
            .map(|_| [rng.random(), rng.random(), rng.random()])
            .collect();
        cube.extend(cube.clone()); // duplicates
        let mut ball: Vec<[f64; 3]> = Vec::new();
        while ball.len() < 20_000 {
            let q: [f64; 3] = [rng.random(), rng.random(), rng.random()];
            let q = q.map(|c| 2.0 * c - 1.0);
            let n = norm(q);
            if n <= 1.0 {
                ball.push(if ball.len() % 50 == 0 {
                    q.map(|c| c / n)
                } else {
                    q
                });
            }
        }
        for (name, cloud) in [("cube", cube), ("ball", ball)] {
            let all: Vec<Vector> = cloud.iter().map(|&v| Vector::from_array(v)).collect();
            let reduced = hull_candidates(&cloud);
            assert!(
                reduced.len() * 4 < cloud.len(),
                "{name}: {} of {} points kept",
                reduced.len(),
                cloud.len()
            );
            assert_eq!(hull_points(&reduced), hull_points(&all), "{name}");
        }
    }

    /// The support polytope of points on a sphere contains them all and stays within 0.4 %
    /// of the radius of the sphere (the exact hull).
    #[test]
    fn support_polytope_contains_the_points_and_stays_close() {
        let points: Vec<Vector> = sphere_directions(30_000)
            .into_iter()
            .map(|d| Vector::from_array(d) * 0.5 + Vector::new(1.0, -2.0, 0.25))
            .collect();
        let vertices = support_polytope(&points, SUPPORT_PLANES).unwrap();
        assert!(vertices.len() <= 4 * SUPPORT_PLANES);
        let centre = Vector::new(1.0, -2.0, 0.25);
        let worst = vertices
            .iter()
            .map(|v| (*v - centre).length() - 0.5)
            .fold(0.0, f64::max);
        assert!(worst > 0.0 && worst < 0.004 * 0.5, "{worst}");
        let hull = SharedShape::convex_hull(&vertices).unwrap();
        for p in &points {
            assert!(hull.contains_point(&Pose::IDENTITY, *p), "{p:?} outside");
        }
        // A finely sampled rotated box: its faces come out exact.
        let rotation = parry3d_f64::math::Rotation::from_axis_angle(
            Vector::new(1.0, 2.0, 3.0).normalize(),
            0.4,
        );
        let mut boxed = Vec::new();
        for i in 0..=40 {
            for j in 0..=40 {
                let (u, v) = (i as f64 / 40.0 - 0.5, j as f64 / 40.0 - 0.5);
                for q in [
                    [u, v, 0.5],
                    [u, v, -0.5],
                    [u, 0.5, v],
                    [u, -0.5, v],
                    [0.5, u, v],
                    [-0.5, u, v],
                ] {
                    boxed.push(rotation * Vector::from_array(q));
                }
            }
        }
        let vertices = support_polytope(&boxed, SUPPORT_PLANES).unwrap();
        let worst = vertices
            .iter()
            .map(|v| (rotation.inverse() * *v).abs().max_element() - 0.5)
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "{worst}");
        // A flat cloud has no interior: no polytope (the exact hull is used).
        let flat: Vec<Vector> = points.iter().map(|p| Vector::new(p.x, p.y, 0.0)).collect();
        assert!(support_polytope(&flat, SUPPORT_PLANES).is_none());
    }

    #[test]
    fn shapes_of_invalid_or_flat_meshes() {
        let empty = MeshData::default();
        assert_eq!(
            empty.to_parry_trimesh().unwrap_err(),
            ShapeError::InvalidMesh(MeshDefect::Empty)
        );
        assert_eq!(
            empty.to_convex_decomposition().unwrap_err(),
            ShapeError::InvalidMesh(MeshDefect::Empty)
        );
        assert!(empty.to_convex_hull().is_none());
        assert_eq!(empty.aabb().0, [f64::INFINITY; 3]);

        let square = MeshData {
            vertices: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        let flat_hull = square.to_convex_hull().unwrap();
        let above = flat_hull.project_point(&Pose::IDENTITY, p(0.5, 0.5, 0.25), true);
        assert!((above.point - p(0.5, 0.5, 0.0)).length() < 1e-12);
        assert!(square.to_parry_trimesh().is_ok());
        // Flat: no volume to decompose; must not panic.
        let flat = square.to_convex_decomposition();
        assert!(matches!(flat, Ok(_) | Err(ShapeError::EmptyDecomposition)));

        let mut nan = cube();
        nan.vertices[0][0] = f64::NAN;
        assert!(nan.to_convex_hull().is_none());
    }

    fn committed(name: &str) -> MeshData {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("meshes")
            .join(name);
        load_mesh(&path).unwrap_or_else(|e| panic!("{e}"))
    }

    fn assert_extent(name: &str, mesh: &MeshData, expected: [f64; 3]) {
        let (min, max) = mesh.aabb();
        for k in 0..3 {
            let extent = max[k] - min[k];
            assert!(
                (extent - expected[k]).abs() < 1e-6,
                "{name}: extent {k} is {extent}, expected {}",
                expected[k]
            );
        }
    }

    #[test]
    fn committed_meshes_are_closed_outward_and_small() {
        for (name, extent) in [
            ("glovebox.stl", [1.0, 0.6, 0.7]),
            ("pipe_bundle.obj", [1.0, 0.9, 0.29]),
            ("vessel.stl", [0.75, 0.6, 0.8]),
        ] {
            let mesh = committed(name);
            assert!(mesh.triangles.len() <= 3000, "{name}: too many triangles");
            assert_closed_and_oriented(name, &mesh);
            assert!(signed_volume(&mesh) > 0.0, "{name}: not outward");
            assert_extent(name, &mesh, extent);
        }
    }

    #[test]
    fn committed_glovebox_is_a_hollow_shell_with_ports() {
        let mesh = committed("glovebox.stl");
        assert!((signed_volume(&mesh) - 0.0639).abs() < 1e-3);
        let trimesh = mesh.to_parry_trimesh().unwrap();
        let id = Pose::IDENTITY;
        // Inside the front wall, inside the back wall, in the cavity, in a
        // glove port, outside.
        assert!(trimesh.contains_point(&id, p(0.0, -0.29, 0.1)));
        assert!(trimesh.contains_point(&id, p(0.3, 0.29, 0.6)));
        assert!(!trimesh.contains_point(&id, p(0.0, 0.0, 0.35)));
        assert!(!trimesh.contains_point(&id, p(-0.25, -0.29, 0.35)));
        assert!(!trimesh.contains_point(&id, p(0.25, -0.29, 0.42)));
        assert!(trimesh.contains_point(&id, p(0.25, -0.29, 0.46)));
        assert!(!trimesh.contains_point(&id, p(0.0, -0.4, 0.35)));
    }

    #[test]
    fn committed_pipes_and_vessel_contain_their_interiors() {
        let id = Pose::IDENTITY;
        let pipes = committed("pipe_bundle.obj").to_parry_trimesh().unwrap();
        assert!(pipes.contains_point(&id, p(0.0, 0.0, 0.5)));
        assert!(pipes.contains_point(&id, p(0.49, 0.32, 0.5)));
        assert!(!pipes.contains_point(&id, p(0.0, 0.08, 0.5)));
        assert!(pipes.contains_point(&id, p(0.2, 0.0, 0.64)));
        assert!(!pipes.contains_point(&id, p(0.0, 0.0, 0.64)));

        let vessel = committed("vessel.stl").to_parry_trimesh().unwrap();
        assert!(vessel.contains_point(&id, p(0.0, 0.0, 0.4)));
        assert!(vessel.contains_point(&id, p(0.0, 0.0, 0.79)));
        assert!(vessel.contains_point(&id, p(0.29, 0.0, 0.25)));
        assert!(vessel.contains_point(&id, p(0.38, 0.0, 0.25)));
        assert!(vessel.contains_point(&id, p(0.44, 0.09, 0.25)));
        assert!(!vessel.contains_point(&id, p(0.38, 0.07, 0.25)));
        assert!(!vessel.contains_point(&id, p(0.25, 0.25, 0.75)));
    }

    #[test]
    fn committed_vessel_decomposes() {
        let mesh = committed("vessel.stl");
        let start = Instant::now();
        let decomposition = mesh.to_convex_decomposition().unwrap();
        let elapsed = start.elapsed();
        let id = Pose::IDENTITY;
        assert!(decomposition.contains_point(&id, p(0.0, 0.0, 0.4)));
        assert!(decomposition.contains_point(&id, p(0.38, 0.0, 0.25)));
        assert!(!decomposition.contains_point(&id, p(0.0, 0.0, 0.9)));
        let parts = decomposition.as_compound().unwrap().shapes().len();
        eprintln!("vessel decomposition: {parts} parts in {elapsed:?}");
    }
}
