use thiserror::Error;

/// Everything that can go wrong building, reading, writing, validating or repairing a mesh.
///
/// Errors from files always carry the file name (`<memory>` for [`crate::io::read_from_bytes`])
/// and, for text formats, the 1-based line; for binary/structured formats the element
/// (`vertex 12`, `face 3`, `accessor 2`, `byte 1024`).
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
    /// The file could not be opened, read, or written.
    #[error("{file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// A text file (OFF, OBJ, PLY header or ascii body) is malformed at a line (1-based).
    #[error("{file}:{line}: {message}")]
    Parse {
        file: String,
        line: usize,
        message: String,
    },
    /// A binary or structured file (binary PLY, glTF/GLB) is malformed at an element.
    #[error("{file}: {element}: {message}")]
    Malformed {
        file: String,
        element: String,
        message: String,
    },
    /// The file extension names no supported mesh format.
    #[error(
        "{file}: unrecognised mesh format (extension {extension:?}); expected .off, .obj, .ply, .gltf or .glb"
    )]
    UnknownFormat { file: String, extension: String },
    /// A mesh read from a file is invalid as a whole (empty, non-finite, index out of range).
    #[error("{file}: {source}")]
    InFile {
        file: String,
        #[source]
        source: Box<MeshError>,
    },
    /// The number of per-vertex colours does not match the number of vertices.
    #[error("{colors} colours given for {vertices} vertices")]
    ColorCount { colors: usize, vertices: usize },
    /// A coordinate cannot be stored in the output format (glTF positions are 32-bit floats).
    #[error("vertex {vertex}: coordinate {value} does not fit a 32-bit float ({format} stores positions as f32)")]
    NotRepresentable {
        vertex: usize,
        value: f64,
        format: &'static str,
    },
    /// A repair removed every triangle (e.g. all of them were degenerate).
    #[error("repair left no triangles: {reason}")]
    NothingLeft { reason: String },
    /// A result would have more vertices than 32-bit vertex ids can name.
    #[error("{vertices} vertices do not fit 32-bit vertex ids")]
    TooLarge { vertices: usize },
}
