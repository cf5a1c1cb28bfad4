use thiserror::Error;

/// Everything that can go wrong building, reading, writing or validating a mesh.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum MeshError {
    /// No vertices or no triangles.
    #[error("empty mesh: {vertices} vertices, {triangles} triangles")]
    Empty { vertices: usize, triangles: usize },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite { vertex: usize },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        triangle: usize,
        index: usize,
        vertices: usize,
    },
}
