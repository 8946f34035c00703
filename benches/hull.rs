//! Convex hulls of large meshes (the `hull` representation of a mesh obstacle): a bumpy closed
//! blob of 1,000,000 triangles, generated with a fixed seed and written as a binary STL into a
//! temporary directory, then loaded and hulled as a scenario does; and the hull alone.

use criterion::{criterion_group, criterion_main, Criterion};
use kinsynth::world::mesh::{load_mesh, MeshData};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::io::Write;
use std::time::Duration;

/// A closed, outward-oriented UV sphere of radius about 0.5 m with `rings × sectors` quads
/// (`2·rings·sectors − 2·sectors` triangles), every vertex pushed in or out by up to 2 %.
fn bumpy_sphere(rings: usize, sectors: usize, seed: u64) -> MeshData {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut vertices = vec![[0.0, 0.0, 0.5]];
    for i in 1..rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..sectors {
            let phi = std::f64::consts::TAU * j as f64 / sectors as f64;
            let r = 0.5 * (1.0 + 0.02 * (rng.random::<f64>() - 0.5));
            vertices.push([
                r * theta.sin() * phi.cos(),
                r * theta.sin() * phi.sin(),
                r * theta.cos(),
            ]);
        }
    }
    vertices.push([0.0, 0.0, -0.5]);
    let south = (vertices.len() - 1) as u32;
    let at = |i: usize, j: usize| (1 + (i - 1) * sectors + j % sectors) as u32;
    let mut triangles = Vec::new();
    for j in 0..sectors {
        triangles.push([0, at(1, j), at(1, j + 1)]);
        triangles.push([south, at(rings - 1, j + 1), at(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..sectors {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    MeshData {
        vertices,
        triangles,
    }
}

fn binary_stl(mesh: &MeshData) -> Vec<u8> {
    let mut bytes = vec![0u8; 80];
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

fn hull(c: &mut Criterion) {
    // 501 rings × 1000 sectors: 1,000,000 triangles, 500,002 vertices.
    let mesh = bumpy_sphere(501, 1000, 13);
    assert_eq!(mesh.triangles.len(), 1_000_000);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("blob.stl");
    std::fs::File::create(&path)
        .unwrap()
        .write_all(&binary_stl(&mesh))
        .unwrap();
    let mut g = c.benchmark_group("hull");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(20))
        .warm_up_time(Duration::from_secs(1));
    g.bench_function("hull of a 1M-triangle mesh", |b| {
        b.iter(|| black_box(mesh.to_convex_hull().expect("a hull")))
    });
    g.bench_function("load + hull of a 1M-triangle binary STL", |b| {
        b.iter(|| {
            let m = load_mesh(black_box(&path)).unwrap();
            black_box(m.to_convex_hull().expect("a hull"))
        })
    });
    g.finish();
}

criterion_group!(benches, hull);
criterion_main!(benches);
