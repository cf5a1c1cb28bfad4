use symcorr_skeleton::LimbPair;
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
    /// The skeleton fails a fit check (`FitQuality`) in every placement the rotation search
    /// tried, and the options say to refuse.
    #[error("the skeleton does not fit the mesh: {check} is {value:.3} (at most {limit} accepted): {meaning}; {}(--accept-poor-fit uses them anyway)", likely_cause(*two_large_parts))]
    PoorFit {
        /// The worst failed check's name.
        check: &'static str,
        /// Its measured value.
        value: f64,
        /// Its limit.
        limit: f64,
        /// What its failure usually means.
        meaning: &'static str,
        /// The vertex counts of the mesh's two largest connected parts when the second holds
        /// at least a third as many as the first: the mesh may hold two bodies, which no one
        /// skeleton fits, and the message asks about the mesh before the joints.
        two_large_parts: Option<(usize, usize)>,
    },
    /// The skeleton's left and right are exchanged relative to the mesh and the options say
    /// to refuse rather than fix.
    #[error("the skeleton's left and right are swapped relative to the mesh (the feet point backwards in the skeleton's torso frame: evidence {evidence:.2}); swap the joint names or allow the fix")]
    MirroredSkeleton {
        /// Combined facing evidence (negative: mirrored).
        evidence: f64,
    },
    /// One limb pair's left and right are exchanged against the other pair's (a tracker's
    /// arm or leg swap) and the options say to refuse rather than fix.
    #[error("the {}' left and right are swapped against the rest of the skeleton (the shoulders and the hips point opposite ways across the spine); swap the joint names or allow the fix", .pair.name())]
    SwappedLimbs {
        /// The exchanged pair.
        pair: LimbPair,
    },
    /// The shoulders and the hips point opposite ways across the spine — one limb pair's left
    /// and right are exchanged — and nothing in the mesh or the joints tells which.
    #[error("the arms' and the legs' left and right disagree (the shoulders and the hips point opposite ways across the spine, cosine {cosine:.2}) and neither the feet nor the knees tell which pair the tracker swapped (facing evidence {evidence:.2}); fix the joint names of one pair")]
    LimbSidesUndetermined {
        /// Cosine between the shoulders' and the hips' left → right directions.
        cosine: f64,
        /// The facing evidence of the better of the two corrections.
        evidence: f64,
    },
    /// The linear solve of bone heat failed.
    #[error("bone heat: {0}")]
    Solver(String),
    /// An option is out of its range.
    #[error("invalid attachment option: {name} = {value} is out of range")]
    OptionOutOfRange {
        /// The option's field name in `AttachOptions`.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// A boundary convention with joint planes off: the convention would be ignored.
    #[error("invalid attachment option: a boundary convention replaces joint planes: it needs joint_planes = true")]
    ConventionNeedsJointPlanes,
    /// A boundary rule that cannot separate anything.
    #[error("invalid attachment option: boundary rule {a} / {b} at {joint}: the segments must differ and not be left/right twins, and the plane must be finite ({plane:?})")]
    InvalidBoundaryRule {
        /// One segment's name.
        a: &'static str,
        /// The other's.
        b: &'static str,
        /// The joint the rule is anchored at.
        joint: &'static str,
        /// The rule's plane coefficients.
        plane: [f64; 5],
    },
    /// A labelled training body whose label table does not match its mesh.
    #[error("a labelled body has {labels} labels for {vertices} vertices")]
    LabelCount {
        /// Labels given.
        labels: usize,
        /// Vertices of the mesh.
        vertices: usize,
    },
    /// No boundary rule could be learned from the labelled bodies.
    #[error("no segment boundary could be learned from the labelled bodies")]
    NothingLearned,
}

/// The question a [`AttachError::PoorFit`] message ends with: about the mesh when it has two
/// large parts, else about the joints.
fn likely_cause(two_large_parts: Option<(usize, usize)>) -> String {
    match two_large_parts {
        Some((a, b)) => format!(
            "the mesh has two large connected parts ({a} and {b} vertices): does it hold more \
             than one body? A skeleton is one body's; cut the mesh down to that body. "
        ),
        None => "are the joints from another frame, pose or subject? ".to_string(),
    }
}
