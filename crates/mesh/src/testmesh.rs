//! Small meshes built from first principles, shared by the tests, benches and examples of the
//! workspace's crates (not part of the public API: hidden from the docs, may change without
//! notice).

use crate::TriMesh;

const PHI: f64 = 1.618_033_988_749_895; // (1 + √5) / 2

/// The 12 vertices of a regular icosahedron (not normalised).
pub const ICO_VERTICES: [[f64; 3]; 12] = [
    [-1.0, PHI, 0.0],
    [1.0, PHI, 0.0],
    [-1.0, -PHI, 0.0],
    [1.0, -PHI, 0.0],
    [0.0, -1.0, PHI],
    [0.0, 1.0, PHI],
    [0.0, -1.0, -PHI],
    [0.0, 1.0, -PHI],
    [PHI, 0.0, -1.0],
    [PHI, 0.0, 1.0],
    [-PHI, 0.0, -1.0],
    [-PHI, 0.0, 1.0],
];

/// The 20 outward-oriented faces of the icosahedron.
pub const ICO_FACES: [[u32; 3]; 20] = [
    [0, 11, 5],
    [0, 5, 1],
    [0, 1, 7],
    [0, 7, 10],
    [0, 10, 11],
    [1, 5, 9],
    [5, 11, 4],
    [11, 10, 2],
    [10, 7, 6],
    [7, 1, 8],
    [3, 9, 4],
    [3, 4, 2],
    [3, 2, 6],
    [3, 6, 8],
    [3, 8, 9],
    [4, 9, 5],
    [2, 4, 11],
    [6, 2, 10],
    [8, 6, 7],
    [9, 8, 1],
];

/// Unit vector of a non-zero vector.
pub fn normalize(p: [f64; 3]) -> [f64; 3] {
    nalgebra::Vector3::from(p).normalize().into()
}

fn build(positions: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> TriMesh {
    // Invariant: the generators emit finite positions and in-range indices, which is all
    // `TriMesh::new` checks.
    TriMesh::new(positions, triangles).expect("generated meshes are valid by construction")
}

/// The corner tetrahedron: the origin and the three unit points on the axes, faces outward.
pub fn tetrahedron() -> TriMesh {
    build(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    )
}

/// The regular icosahedron inscribed in the unit sphere.
pub fn icosahedron() -> TriMesh {
    build(
        ICO_VERTICES.iter().map(|&p| normalize(p)).collect(),
        ICO_FACES.to_vec(),
    )
}

/// A flat `w × h` grid of rectangles `spacing[0] × spacing[1]` (two triangles each) in the
/// z = 0 plane, vertex `(i, j)` at id `j·(w + 1) + i`.
pub fn grid(w: usize, h: usize, spacing: [f64; 2]) -> TriMesh {
    let mut positions = Vec::with_capacity((w + 1) * (h + 1));
    for j in 0..=h {
        for i in 0..=w {
            positions.push([i as f64 * spacing[0], j as f64 * spacing[1], 0.0]);
        }
    }
    let id = |i: usize, j: usize| (j * (w + 1) + i) as u32;
    let mut triangles = Vec::with_capacity(2 * w * h);
    for j in 0..h {
        for i in 0..w {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    build(positions, triangles)
}
