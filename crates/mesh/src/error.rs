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
    Empty {
        /// Number of vertices.
        vertices: usize,
        /// Number of triangles.
        triangles: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite {
        /// The vertex (0-based).
        vertex: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// The triangle (0-based).
        triangle: usize,
        /// The vertex id it names.
        index: usize,
        /// Number of vertices.
        vertices: usize,
    },
    /// The file could not be opened, read, or written.
    #[error("{file}: {source}")]
    Io {
        /// The file (`<memory>` for bytes).
        file: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A text file (OFF, OBJ, PLY header or ascii body) is malformed at a line (1-based).
    #[error("{file}:{line}: {message}")]
    Parse {
        /// The file (`<memory>` for bytes).
        file: String,
        /// The line (1-based).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A binary or structured file (binary PLY, glTF/GLB) is malformed at an element.
    #[error("{file}: {element}: {message}")]
    Malformed {
        /// The file (`<memory>` for bytes).
        file: String,
        /// The element (`vertex 12`, `face 3`, `accessor 2`, `byte 1024`).
        element: String,
        /// What is wrong.
        message: String,
    },
    /// The file extension names no supported mesh format.
    #[error(
        "{file}: unrecognised mesh format (extension {extension:?}); expected .off, .obj, .ply, .gltf or .glb"
    )]
    UnknownFormat {
        /// The file (`<memory>` for bytes).
        file: String,
        /// The extension found.
        extension: String,
    },
    /// A mesh read from a file is invalid as a whole (empty, non-finite, index out of range).
    #[error("{file}: {source}")]
    InFile {
        /// The file (`<memory>` for bytes).
        file: String,
        /// The underlying error.
        #[source]
        source: Box<MeshError>,
    },
    /// The number of per-vertex colours does not match the number of vertices.
    #[error("{colors} colours given for {vertices} vertices")]
    ColorCount {
        /// Number of colours given.
        colors: usize,
        /// Number of vertices.
        vertices: usize,
    },
    /// A coordinate cannot be stored in the output format (glTF positions are 32-bit floats).
    #[error("vertex {vertex}: coordinate {value} does not fit a 32-bit float ({format} stores positions as f32)")]
    NotRepresentable {
        /// The vertex (0-based).
        vertex: usize,
        /// The coordinate.
        value: f64,
        /// The output format.
        format: &'static str,
    },
    /// A repair removed every triangle (e.g. all of them were degenerate).
    #[error("repair left no triangles: {reason}")]
    NothingLeft {
        /// Why nothing is left.
        reason: String,
    },
    /// A result would have more vertices than 32-bit vertex ids can name.
    #[error("{vertices} vertices do not fit 32-bit vertex ids")]
    TooLarge {
        /// Number of vertices.
        vertices: usize,
    },
    /// An input file (or a glTF file with its external buffers) is larger than the input size
    /// limit ([`crate::io::ReadOptions::max_input_bytes`], default
    /// [`crate::io::DEFAULT_MAX_INPUT_BYTES`]). Nothing beyond the limit was read.
    #[error("{file}: is larger than the {} input limit; pass --max-input-size to read it", crate::io::format_bytes(*.limit))]
    InputTooLarge {
        /// The file (for a glTF external buffer: the glTF file and the buffer's uri).
        file: String,
        /// The limit in bytes.
        limit: u64,
    },
    /// A glTF buffer `uri` names a file that may not or cannot be read: outside the glTF file's
    /// folder (absolute, `..`, a symlink leading out), not a regular file, or shorter than the
    /// buffer's `byteLength`.
    #[error("{file}: buffer uri {uri:?}: {message}")]
    ExternalBuffer {
        /// The glTF file.
        file: String,
        /// The buffer's uri as written in the file.
        uri: String,
        /// Why it is refused.
        message: String,
    },
    /// An output path is a directory.
    #[error("{file}: is a directory, not an output file")]
    OutputIsDirectory {
        /// The output path as given.
        file: String,
    },
    /// An output path leads to one of the command's inputs (it would destroy it).
    #[error("{file}: is the input {input}; choose another output path")]
    OutputIsInput {
        /// The output path as given.
        file: String,
        /// The input it leads to.
        input: String,
    },
    /// Two outputs of one command lead to the same file.
    #[error("{file}: written twice by one command")]
    DuplicateOutput {
        /// The output path as given.
        file: String,
    },
    /// A frame of a morph animation ([`crate::io::gltf::MorphAnimationWriter`]) cannot be
    /// written: positions of another count than the rest mesh's vertices, a non-finite
    /// coordinate, a time that is not finite or not after the previous frame's.
    #[error("morph target {target}: {message}")]
    MorphTarget {
        /// The target (0-based, in the order pushed).
        target: usize,
        /// What is wrong.
        message: String,
    },
    /// A morph animation without a single frame: glTF has no empty animation.
    #[error("a morph animation needs at least one frame")]
    NoMorphTargets,
    /// A GLB file would exceed 4 GiB, the most its 32-bit length field can say.
    #[error("the GLB file would have {bytes} bytes, more than the format's 4 GiB")]
    GlbTooLarge {
        /// The size it would have.
        bytes: u64,
    },
}
