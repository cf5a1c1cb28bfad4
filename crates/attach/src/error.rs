use thiserror::Error;

/// Everything that can make attachment fail. Each message says what was wrong and what to do.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum AttachError {
    /// The mesh has no vertices or no triangles.
    #[error("the mesh is empty ({vertices} vertices, {triangles} triangles)")]
    EmptyMesh {
        /// Vertices in the mesh.
        vertices: usize,
        /// Triangles in the mesh.
        triangles: usize,
    },
    /// Too few usable joints (finite, tracked or interpolated) to define a skeleton, or all
    /// joints at one point.
    #[error("the skeleton is empty: {usable} of 20 joints are usable (finite and tracked) and they span {extent:.3e} units; a skeleton needs the torso joints and a non-zero extent")]
    EmptySkeleton {
        /// Usable joints.
        usable: usize,
        /// Diagonal of their bounding box.
        extent: f64,
    },
    /// The skeleton and the mesh differ in size by more than a unit conversion explains.
    #[error("the skeleton spans {skeleton_extent:.4} units but the mesh {mesh_extent:.4}: no unit conversion (powers of ten) reconciles them; convert one of them")]
    ScaleMismatch {
        /// Joint bounding-box diagonal.
        skeleton_extent: f64,
        /// Mesh bounding-box diagonal.
        mesh_extent: f64,
    },
    /// After the best scale, offset and axis rotation the joints still do not sit in the mesh.
    #[error("the skeleton does not fit the mesh: after the best scale ({scale}), axis rotation and offset the median joint is {residual:.3} skeleton heights from the surface (at most 0.08 accepted) and the median vertex {coverage:.3} from a bone (at most 0.12); are the joints from another frame or another subject?")]
    AlignmentFailed {
        /// Scale tried.
        scale: f64,
        /// Median joint-to-surface distance in skeleton heights.
        residual: f64,
        /// Median vertex-to-bone distance in skeleton heights.
        coverage: f64,
    },
    /// The skeleton's left and right are exchanged relative to the mesh and the options say
    /// to refuse rather than fix.
    #[error("the skeleton's left and right are swapped relative to the mesh (the feet point backwards in the skeleton's torso frame: evidence {evidence:.2}); swap the joint names or allow the fix")]
    MirroredSkeleton {
        /// Combined facing evidence (negative: mirrored).
        evidence: f64,
    },
    /// The linear solve of bone heat failed.
    #[error("bone heat: {0}")]
    Solver(String),
    /// Options out of range.
    #[error("invalid attachment option: {0}")]
    InvalidOption(String),
}
