//! Generates the obstacle meshes in `meshes/`: obstacles met when designing a
//! manipulator for a cluttered nuclear or medical cell.
//!
//! * `meshes/glovebox.stl` (binary STL): a glovebox shell, 1.0 × 0.6 × 0.7 m,
//!   20 mm walls, hollow, with two 200 mm glove ports through the front wall.
//! * `meshes/pipe_bundle.obj` (OBJ): five flanged parallel pipes, 1 m long,
//!   with a flanged header pipe crossing above them (not touching).
//! * `meshes/vessel.stl` (ASCII STL): a vertical pressure vessel, 0.3 m
//!   radius, 0.8 m tall, flat bottom, hemispherical head, with a flanged side
//!   nozzle.
//!
//! Every mesh is a closed surface (each edge shared by exactly two triangles)
//! with counter-clockwise, outward-facing triangles; the program checks this
//! before writing. Units are metres; each obstacle stands on the floor
//! (`z = 0`) or, for the pipes, above it, centred on the `z` axis.
//!
//! Run with `cargo run --example make_meshes`.

use std::collections::HashMap;
use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;

/// An indexed triangle mesh under construction.
#[derive(Default)]
struct Builder {
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    /// When set, triangles are added with reversed orientation.
    flip: bool,
}

impl Builder {
    fn vertex(&mut self, p: [f64; 3]) -> u32 {
        // `+ 0.0` turns -0.0 into 0.0, so equal positions have equal bits.
        self.vertices.push(p.map(|c| c + 0.0));
        u32::try_from(self.vertices.len() - 1).expect("too many vertices")
    }

    fn triangle(&mut self, a: u32, b: u32, c: u32) {
        self.triangles
            .push(if self.flip { [a, c, b] } else { [a, b, c] });
    }

    /// Two triangles `a b c` and `a c d`.
    fn quad(&mut self, a: u32, b: u32, c: u32, d: u32) {
        self.triangle(a, b, c);
        self.triangle(a, c, d);
    }

    /// A planar convex polygon, fanned from its first corner, oriented so that
    /// its normal points along `outward`. The first corner must not be on a
    /// side that has extra (collinear) points.
    fn polygon(&mut self, corners: &[u32], outward: [f64; 3]) {
        let p: Vec<[f64; 3]> = corners.iter().map(|&i| self.vertices[i as usize]).collect();
        let mut newell = [0.0; 3];
        for (k, a) in p.iter().enumerate() {
            let b = p[(k + 1) % p.len()];
            newell = add(newell, cross(*a, b));
        }
        let mut order = corners.to_vec();
        if dot(newell, outward) < 0.0 {
            order[1..].reverse();
        }
        for k in 1..order.len() - 1 {
            self.triangle(order[0], order[k], order[k + 1]);
        }
    }

    /// Connects two rings of equal length with quads `a_k a_k+1 b_k+1 b_k`.
    ///
    /// For rings counter-clockwise about an axis, the quads face
    /// `tangent × (b - a)`: outward when `b` is further along the axis.
    fn band(&mut self, a: &[u32], b: &[u32]) {
        let n = a.len();
        for k in 0..n {
            let k1 = (k + 1) % n;
            self.quad(a[k], a[k1], b[k1], b[k]);
        }
    }

    /// Closes the start of a surface of revolution with a fan from `apex`.
    fn cap_start(&mut self, apex: u32, ring: &[u32]) {
        let n = ring.len();
        for k in 0..n {
            self.triangle(apex, ring[(k + 1) % n], ring[k]);
        }
    }

    /// Closes the end of a surface of revolution with a fan to `apex`.
    fn cap_end(&mut self, ring: &[u32], apex: u32) {
        let n = ring.len();
        for k in 0..n {
            self.triangle(ring[k], ring[(k + 1) % n], apex);
        }
    }

    /// Triangulates the strip between two parallel chains of points, each
    /// given with its position along the common direction. The outer chain
    /// runs counter-clockwise around the region, the inner chain the same way.
    fn zip(&mut self, outer: &[(u32, f64)], inner: &[(u32, f64)]) {
        let (mut i, mut j) = (0, 0);
        while i + 1 < outer.len() || j + 1 < inner.len() {
            let advance_outer =
                j + 1 == inner.len() || (i + 1 < outer.len() && outer[i + 1].1 <= inner[j + 1].1);
            if advance_outer {
                self.triangle(outer[i].0, outer[i + 1].0, inner[j].0);
                i += 1;
            } else {
                self.triangle(outer[i].0, inner[j + 1].0, inner[j].0);
                j += 1;
            }
        }
    }

    /// A rectangular region of a surface with a round hole, triangulated in
    /// the surface parameters `(u, v)`; counter-clockwise in `(u, v)` must be
    /// outward on the surface.
    ///
    /// * `sides`: the region boundary, counter-clockwise: bottom (left to
    ///   right), right (bottom to top), top (right to left), left (top to
    ///   bottom); consecutive sides share their corner vertex.
    /// * `hole`: the hole boundary, `m` vertices (a multiple of 8) at angles
    ///   `2πk/m` about `center`, counter-clockwise.
    /// * `half`: half-size of an intermediate square ring between hole and
    ///   boundary; must lie strictly between them.
    /// * `map`: surface point of a parameter pair.
    fn holed_patch(
        &mut self,
        sides: &[Vec<(u32, [f64; 2])>; 4],
        hole: &[u32],
        center: [f64; 2],
        half: f64,
        map: &dyn Fn([f64; 2]) -> [f64; 3],
    ) {
        let m = hole.len();
        assert!(m % 8 == 0, "hole needs a multiple of 8 vertices");
        // Square ring: the hole's angles projected onto the square, so its
        // corners are vertices k = m/8, 3m/8, 5m/8, 7m/8.
        let square: Vec<(u32, [f64; 2])> = (0..m)
            .map(|k| {
                let (s, c) = (TAU * k as f64 / m as f64).sin_cos();
                let scale = half / c.abs().max(s.abs());
                let uv = [center[0] + c * scale, center[1] + s * scale];
                (self.vertex(map(uv)), uv)
            })
            .collect();
        for k in 0..m {
            let k1 = (k + 1) % m;
            self.triangle(square[k].0, square[k1].0, hole[k]);
            self.triangle(square[k1].0, hole[k1], hole[k]);
        }
        // Four trapezoids between the boundary sides and the square's sides.
        for (s, side) in sides.iter().enumerate() {
            let first = side[0].1;
            let last = side[side.len() - 1].1;
            let dir = [last[0] - first[0], last[1] - first[1]];
            let along = |uv: [f64; 2]| uv[0] * dir[0] + uv[1] * dir[1];
            let outer: Vec<(u32, f64)> = side.iter().map(|&(id, uv)| (id, along(uv))).collect();
            let start = (5 + 2 * s) * m / 8;
            let inner: Vec<(u32, f64)> = (0..=m / 4)
                .map(|j| {
                    let (id, uv) = square[(start + j) % m];
                    (id, along(uv))
                })
                .collect();
            self.zip(&outer, &inner);
        }
    }

    /// A closed surface of revolution about the axis through `origin` along
    /// the unit vector `axis`; `profile` lists `(position along the axis,
    /// radius)` pairs, starting and ending with radius 0.
    fn lathe(&mut self, origin: [f64; 3], axis: [f64; 3], profile: &[(f64, f64)], segments: usize) {
        let (e1, e2) = frame(axis);
        let ring = |b: &mut Builder, s: f64, r: f64| -> Vec<u32> {
            (0..segments)
                .map(|k| {
                    let (sn, cs) = (TAU * k as f64 / segments as f64).sin_cos();
                    b.vertex(add(
                        add(origin, scale(axis, s)),
                        add(scale(e1, r * cs), scale(e2, r * sn)),
                    ))
                })
                .collect()
        };
        let (s0, r0) = profile[0];
        assert!(r0 == 0.0 && profile[profile.len() - 1].1 == 0.0);
        let apex = self.vertex(add(origin, scale(axis, s0)));
        let mut previous = ring(self, profile[1].0, profile[1].1);
        self.cap_start(apex, &previous);
        for &(s, r) in &profile[2..profile.len() - 1] {
            let next = ring(self, s, r);
            self.band(&previous, &next);
            previous = next;
        }
        let (s1, _) = profile[profile.len() - 1];
        let apex = self.vertex(add(origin, scale(axis, s1)));
        self.cap_end(&previous, apex);
    }
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    scale(a, 1.0 / dot(a, a).sqrt())
}

/// Unit vectors `e1`, `e2` with `e1 × e2 = axis`.
fn frame(axis: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let helper = if axis[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 0.0, 1.0]
    };
    let e1 = normalize(cross(helper, axis));
    (e1, cross(axis, e1))
}

/// Outer size of the glovebox (x, y, z), metres.
const GLOVEBOX_SIZE: [f64; 3] = [1.0, 0.6, 0.7];
/// Wall thickness of the glovebox.
const GLOVEBOX_WALL: f64 = 0.02;
/// `x` of the glove port centres.
const PORT_X: [f64; 2] = [-0.25, 0.25];
/// Height of the glove port centres.
const PORT_Z: f64 = 0.35;
/// Glove port radius.
const PORT_RADIUS: f64 = 0.1;
/// Vertices around a glove port.
const PORT_SEGMENTS: usize = 48;
/// Half-size of the square ring around a glove port.
const PORT_SQUARE_HALF: f64 = 0.16;

/// Glovebox: outer size 1.0 (x) × 0.6 (y) × 0.7 (z) m, 20 mm walls, two
/// 200 mm glove ports through the front wall (`y = -0.3`).
fn glovebox() -> Builder {
    let mut b = Builder::default();
    let outer_min = [-GLOVEBOX_SIZE[0] / 2.0, -GLOVEBOX_SIZE[1] / 2.0, 0.0];
    let outer_max = [
        GLOVEBOX_SIZE[0] / 2.0,
        GLOVEBOX_SIZE[1] / 2.0,
        GLOVEBOX_SIZE[2],
    ];
    let inner_min = add(outer_min, [GLOVEBOX_WALL; 3]);
    let inner_max = sub(outer_max, [GLOVEBOX_WALL; 3]);

    let outer_holes = box_with_ports(&mut b, outer_min, outer_max);
    // The cavity surface faces inwards.
    b.flip = true;
    let inner_holes = box_with_ports(&mut b, inner_min, inner_max);
    b.flip = false;
    // Port tunnels through the front wall, facing the port axis.
    for (outer, inner) in outer_holes.iter().zip(&inner_holes) {
        b.band(outer, inner);
    }
    b
}

/// The ring of glove port `port` on the front plane `y`.
fn port_ring(b: &mut Builder, port: usize, y: f64) -> Vec<u32> {
    (0..PORT_SEGMENTS)
        .map(|k| {
            let (s, c) = (TAU * k as f64 / PORT_SEGMENTS as f64).sin_cos();
            b.vertex([PORT_X[port] + PORT_RADIUS * c, y, PORT_Z + PORT_RADIUS * s])
        })
        .collect()
}

/// The closed surface of a box whose front face (`y = min[1]`) is split at
/// `x = 0` into two halves, each with a glove port hole. Faces point out of
/// the box (unless the builder is flipped). Returns the two hole rings.
fn box_with_ports(b: &mut Builder, min: [f64; 3], max: [f64; 3]) -> Vec<Vec<u32>> {
    let [x0, y0, z0] = min;
    let [x1, y1, z1] = max;
    let xm = 0.0;
    let fbl = b.vertex([x0, y0, z0]);
    let fbm = b.vertex([xm, y0, z0]);
    let fbr = b.vertex([x1, y0, z0]);
    let ftl = b.vertex([x0, y0, z1]);
    let ftm = b.vertex([xm, y0, z1]);
    let ftr = b.vertex([x1, y0, z1]);
    let bbl = b.vertex([x0, y1, z0]);
    let bbr = b.vertex([x1, y1, z0]);
    let btl = b.vertex([x0, y1, z1]);
    let btr = b.vertex([x1, y1, z1]);

    b.polygon(&[bbl, bbr, btr, btl], [0.0, 1.0, 0.0]);
    b.polygon(&[fbl, ftl, btl, bbl], [-1.0, 0.0, 0.0]);
    b.polygon(&[fbr, bbr, btr, ftr], [1.0, 0.0, 0.0]);
    b.polygon(&[btl, ftl, ftm, ftr, btr], [0.0, 0.0, 1.0]);
    b.polygon(&[bbl, fbl, fbm, fbr, bbr], [0.0, 0.0, -1.0]);

    // Front face in (u, v) = (x, z): counter-clockwise faces -y.
    let map = move |uv: [f64; 2]| [uv[0], y0, uv[1]];
    let uv = |b: &Builder, id: u32| {
        let p = b.vertices[id as usize];
        (id, [p[0], p[2]])
    };
    let halves = [[fbl, fbm, ftm, ftl], [fbm, fbr, ftr, ftm]];
    let mut rings = Vec::new();
    for (port, [bl, br, tr, tl]) in halves.into_iter().enumerate() {
        let sides = [
            vec![uv(b, bl), uv(b, br)],
            vec![uv(b, br), uv(b, tr)],
            vec![uv(b, tr), uv(b, tl)],
            vec![uv(b, tl), uv(b, bl)],
        ];
        let ring = port_ring(b, port, y0);
        b.holed_patch(
            &sides,
            &ring,
            [PORT_X[port], PORT_Z],
            PORT_SQUARE_HALF,
            &map,
        );
        rings.push(ring);
    }
    rings
}

/// Five flanged pipes along `x` (1 m long, radii 40–60 mm, 160 mm apart) at
/// 0.5 m height, and a flanged header pipe along `y` crossing 30 mm above
/// them. Returns one closed component per pipe.
fn pipe_bundle() -> Vec<(String, Builder)> {
    const SEGMENTS: usize = 24;
    const FLANGE_EXTRA: f64 = 0.02;
    const FLANGE_THICKNESS: f64 = 0.02;
    const HEIGHT: f64 = 0.5;
    let radii = [0.05, 0.04, 0.06, 0.045, 0.055];

    let flanged = |length: f64, radius: f64| {
        let flange = radius + FLANGE_EXTRA;
        vec![
            (0.0, 0.0),
            (0.0, flange),
            (FLANGE_THICKNESS, flange),
            (FLANGE_THICKNESS, radius),
            (length - FLANGE_THICKNESS, radius),
            (length - FLANGE_THICKNESS, flange),
            (length, flange),
            (length, 0.0),
        ]
    };

    let mut pipes = Vec::new();
    for (i, &radius) in radii.iter().enumerate() {
        let y = 0.16 * (i as f64 - 2.0);
        let mut b = Builder::default();
        b.lathe(
            [-0.5, y, HEIGHT],
            [1.0, 0.0, 0.0],
            &flanged(1.0, radius),
            SEGMENTS,
        );
        pipes.push((format!("pipe_{}", i + 1), b));
    }
    let header_radius = 0.05;
    let largest = radii.iter().copied().fold(0.0, f64::max);
    let header_z = HEIGHT + largest + 0.03 + header_radius;
    let mut b = Builder::default();
    b.lathe(
        [0.2, -0.45, header_z],
        [0.0, 1.0, 0.0],
        &flanged(0.9, header_radius),
        SEGMENTS,
    );
    pipes.push(("header".to_string(), b));
    pipes
}

/// Vertical pressure vessel: radius 0.3 m, flat bottom at `z = 0`,
/// cylindrical shell up to 0.5 m, hemispherical head up to 0.8 m, and a
/// flanged nozzle (radius 60 mm, flange radius 100 mm) along `+x` at 0.25 m
/// height, reaching `x = 0.45`.
fn vessel() -> Builder {
    const RADIUS: f64 = 0.3;
    const SHELL_HEIGHT: f64 = 0.5;
    const COLUMNS: usize = 36;
    const ROWS: usize = 8;
    const HEAD_RINGS: usize = 5;
    const NOZZLE_Z: f64 = 0.25;
    const NOZZLE_RADIUS: f64 = 0.06;
    const NOZZLE_SEGMENTS: usize = 32;
    const NOZZLE_END: f64 = 0.42;
    const FLANGE_RADIUS: f64 = 0.1;
    const FLANGE_END: f64 = 0.45;
    // The patch around the nozzle: columns -2..=2 and rows 2..=6 of the shell.
    const PATCH_COLUMNS: i64 = 2;
    const PATCH_ROWS: [usize; 2] = [2, 6];
    const SQUARE_HALF: f64 = 0.085;

    let mut b = Builder::default();
    let row_z = |l: usize| SHELL_HEIGHT * l as f64 / ROWS as f64;
    let phi = |k: i64| TAU * k as f64 / COLUMNS as f64;
    let column = |k: i64| k.rem_euclid(COLUMNS as i64) as usize;

    // Shell rings, counter-clockwise about +z.
    let rings: Vec<Vec<u32>> = (0..=ROWS)
        .map(|l| {
            (0..COLUMNS as i64)
                .map(|k| {
                    let (s, c) = phi(k).sin_cos();
                    b.vertex([RADIUS * c, RADIUS * s, row_z(l)])
                })
                .collect()
        })
        .collect();
    let bottom = b.vertex([0.0, 0.0, 0.0]);
    b.cap_start(bottom, &rings[0]);
    for l in 0..ROWS {
        for k in 0..COLUMNS as i64 {
            // Column index in -COLUMNS/2..COLUMNS/2, 0 facing +x.
            let signed = if k >= COLUMNS as i64 / 2 {
                k - COLUMNS as i64
            } else {
                k
            };
            let in_patch = (-PATCH_COLUMNS..PATCH_COLUMNS).contains(&signed)
                && (PATCH_ROWS[0]..PATCH_ROWS[1]).contains(&l);
            if in_patch {
                continue;
            }
            let (k0, k1) = (column(k), column(k + 1));
            b.quad(
                rings[l][k0],
                rings[l][k1],
                rings[l + 1][k1],
                rings[l + 1][k0],
            );
        }
    }

    // Hemispherical head.
    let mut previous = rings[ROWS].clone();
    for m in 1..=HEAD_RINGS {
        let elevation = TAU / 4.0 * m as f64 / (HEAD_RINGS + 1) as f64;
        let (s, c) = elevation.sin_cos();
        let ring: Vec<u32> = (0..COLUMNS as i64)
            .map(|k| {
                let (sp, cp) = phi(k).sin_cos();
                b.vertex([RADIUS * c * cp, RADIUS * c * sp, SHELL_HEIGHT + RADIUS * s])
            })
            .collect();
        b.band(&previous, &ring);
        previous = ring;
    }
    let pole = b.vertex([0.0, 0.0, SHELL_HEIGHT + RADIUS]);
    b.cap_end(&previous, pole);

    // Nozzle: its root ring is the intersection of the nozzle and shell
    // cylinders, counter-clockwise about +x.
    let nozzle_point = |x: Option<f64>, radius: f64, k: usize| {
        let (s, c) = (TAU * k as f64 / NOZZLE_SEGMENTS as f64).sin_cos();
        let y = radius * c;
        let x = x.unwrap_or_else(|| (RADIUS * RADIUS - y * y).sqrt());
        [x, y, NOZZLE_Z + radius * s]
    };
    let root: Vec<u32> = (0..NOZZLE_SEGMENTS)
        .map(|k| b.vertex(nozzle_point(None, NOZZLE_RADIUS, k)))
        .collect();

    // Shell patch with the nozzle hole, in (u, v) = (RADIUS * phi, z).
    let uv_of = |b: &Builder, id: u32| {
        let p = b.vertices[id as usize];
        (id, [RADIUS * p[1].atan2(p[0]), p[2]])
    };
    let [r0, r1] = PATCH_ROWS;
    let (c0, c1) = (-PATCH_COLUMNS, PATCH_COLUMNS);
    let sides = [
        (c0..=c1).map(|k| uv_of(&b, rings[r0][column(k)])).collect(),
        (r0..=r1).map(|l| uv_of(&b, rings[l][column(c1)])).collect(),
        (c0..=c1)
            .rev()
            .map(|k| uv_of(&b, rings[r1][column(k)]))
            .collect(),
        (r0..=r1)
            .rev()
            .map(|l| uv_of(&b, rings[l][column(c0)]))
            .collect(),
    ];
    let cylinder = |uv: [f64; 2]| {
        let (s, c) = (uv[0] / RADIUS).sin_cos();
        [RADIUS * c, RADIUS * s, uv[1]]
    };
    b.holed_patch(&sides, &root, [0.0, NOZZLE_Z], SQUARE_HALF, &cylinder);

    let ring_at = |b: &mut Builder, x: f64, radius: f64| -> Vec<u32> {
        (0..NOZZLE_SEGMENTS)
            .map(|k| b.vertex(nozzle_point(Some(x), radius, k)))
            .collect()
    };
    let pipe_end = ring_at(&mut b, NOZZLE_END, NOZZLE_RADIUS);
    let flange_back = ring_at(&mut b, NOZZLE_END, FLANGE_RADIUS);
    let flange_front = ring_at(&mut b, FLANGE_END, FLANGE_RADIUS);
    let centre = b.vertex([FLANGE_END, 0.0, NOZZLE_Z]);
    b.band(&root, &pipe_end);
    b.band(&pipe_end, &flange_back);
    b.band(&flange_back, &flange_front);
    b.cap_end(&flange_front, centre);
    b
}

/// Panics unless the mesh is closed and consistently oriented (every
/// directed edge appears once, and its reverse once), has no repeated or
/// coincident vertices, and encloses a positive volume. Returns the volume.
fn check_closed(name: &str, b: &Builder) -> f64 {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &b.triangles {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "{name}: repeated vertex in {t:?}"
        );
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, c), &count) in &directed {
        assert_eq!(count, 1, "{name}: edge {a}->{c} used {count} times");
        assert_eq!(
            directed.get(&(c, a)),
            Some(&1),
            "{name}: edge {a}->{c} has no opposite edge"
        );
    }
    let mut seen = HashMap::new();
    for (i, v) in b.vertices.iter().enumerate() {
        assert!(v.iter().all(|c| c.is_finite()), "{name}: vertex {i} {v:?}");
        let key = v.map(|c| (c as f32).to_bits());
        if let Some(j) = seen.insert(key, i) {
            panic!("{name}: vertices {j} and {i} coincide at {v:?}");
        }
    }
    let volume: f64 = b
        .triangles
        .iter()
        .map(|t| {
            let [p, q, r] = t.map(|i| b.vertices[i as usize]);
            dot(p, cross(q, r)) / 6.0
        })
        .sum();
    assert!(volume > 0.0, "{name}: volume {volume} is not positive");
    volume
}

fn stl_triangles(b: &Builder) -> Vec<stl_io::Triangle> {
    b.triangles
        .iter()
        .map(|t| {
            let [p, q, r] = t.map(|i| b.vertices[i as usize]);
            let n = normalize(cross(sub(q, p), sub(r, p)));
            stl_io::Triangle {
                normal: stl_io::Normal::new(n.map(|c| c as f32)),
                vertices: [p, q, r].map(|v| stl_io::Vertex::new(v.map(|c| c as f32))),
            }
        })
        .collect()
}

fn write_binary_stl(path: &Path, b: &Builder) -> std::io::Result<()> {
    let mut file = std::fs::File::create(path)?;
    stl_io::write_stl(&mut file, stl_triangles(b).iter())
}

fn write_ascii_stl(path: &Path, name: &str, b: &Builder) -> std::io::Result<()> {
    let mut text = format!("solid {name}\n");
    for t in stl_triangles(b) {
        let [nx, ny, nz] = t.normal.0;
        writeln!(text, "  facet normal {nx} {ny} {nz}").unwrap();
        text.push_str("    outer loop\n");
        for v in t.vertices {
            let [x, y, z] = v.0;
            writeln!(text, "      vertex {x} {y} {z}").unwrap();
        }
        text.push_str("    endloop\n  endfacet\n");
    }
    writeln!(text, "endsolid {name}").unwrap();
    std::fs::write(path, text)
}

fn write_obj(path: &Path, header: &str, parts: &[(String, Builder)]) -> std::io::Result<()> {
    let mut text = String::new();
    for line in header.lines() {
        writeln!(text, "# {line}").unwrap();
    }
    let mut base = 1;
    for (name, b) in parts {
        writeln!(text, "o {name}").unwrap();
        for [x, y, z] in &b.vertices {
            writeln!(text, "v {x} {y} {z}").unwrap();
        }
        for [i, j, k] in &b.triangles {
            writeln!(text, "f {} {} {}", i + base, j + base, k + base).unwrap();
        }
        base += u32::try_from(b.vertices.len()).expect("too many vertices");
    }
    std::fs::write(path, text)
}

fn report(name: &str, b: &Builder, volume: f64) {
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for v in &b.vertices {
        for k in 0..3 {
            min[k] = min[k].min(v[k]);
            max[k] = max[k].max(v[k]);
        }
    }
    println!(
        "{name}: {} vertices, {} triangles, volume {volume:.4} m³, \
         extent {:.3} × {:.3} × {:.3} m",
        b.vertices.len(),
        b.triangles.len(),
        max[0] - min[0],
        max[1] - min[1],
        max[2] - min[2],
    );
}

fn main() -> std::io::Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes");
    std::fs::create_dir_all(&dir)?;

    let glovebox = glovebox();
    let volume = check_closed("glovebox", &glovebox);
    write_binary_stl(&dir.join("glovebox.stl"), &glovebox)?;
    report("meshes/glovebox.stl", &glovebox, volume);

    let pipes = pipe_bundle();
    let mut all = Builder::default();
    for (name, b) in &pipes {
        check_closed(name, b);
        let base = u32::try_from(all.vertices.len()).expect("too many vertices");
        all.vertices.extend_from_slice(&b.vertices);
        all.triangles
            .extend(b.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    let volume = check_closed("pipe_bundle", &all);
    write_obj(
        &dir.join("pipe_bundle.obj"),
        "Pipe bundle: five flanged pipes and a crossing header pipe (metres).\n\
         Generated by examples/make_meshes.rs.",
        &pipes,
    )?;
    report("meshes/pipe_bundle.obj", &all, volume);

    let vessel = vessel();
    let volume = check_closed("vessel", &vessel);
    write_ascii_stl(&dir.join("vessel.stl"), "vessel", &vessel)?;
    report("meshes/vessel.stl", &vessel, volume);
    Ok(())
}
