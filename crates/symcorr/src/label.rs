//! One mesh labelled as `symcorr label` labels it: inconsistently oriented triangles turned
//! (bone heat and the handedness check read the surface's orientation; nothing else is
//! repaired, so vertex ids stay the input's), then the skeleton attached (symcorr-attach).

use crate::PipelineError;
use symcorr_attach::{attach, AttachOptions, Attachment};
use symcorr_mesh::TriMesh;
use symcorr_skeleton::Skeleton;

/// A labelled mesh ([`label_mesh`]).
#[derive(Debug, Clone)]
pub struct Labelled {
    /// The mesh with its triangles consistently oriented; same vertices, same ids, as the input.
    pub mesh: TriMesh,
    /// Triangles turned to a consistent orientation.
    pub turned_triangles: usize,
    /// The attachment: labels, bone-heat weights, refined joints, diagnostics.
    pub attachment: Attachment,
}

impl Labelled {
    /// Segment index per vertex; `None` for a vertex in a component no bone reaches.
    pub fn segments(&self) -> Vec<Option<usize>> {
        segment_labels(&self.attachment)
    }
}

/// Segment index per vertex of an attachment; `None` for a vertex in a component no bone
/// reaches (what `symcorr.labels/1` writes as `null`).
pub fn segment_labels(attachment: &Attachment) -> Vec<Option<usize>> {
    let mut l: Vec<Option<usize>> = attachment.labels.iter().map(|s| Some(s.index())).collect();
    for &v in &attachment.diagnostics.fit.unreached {
        if let Some(x) = l.get_mut(v as usize) {
            *x = None;
        }
    }
    l
}

/// Orients `mesh`'s triangles consistently and attaches `skeleton` with `options`.
///
/// Errors: [`PipelineError::Mesh`] when the orientation repair fails, [`PipelineError::Attach`]
/// for a skeleton that does not fit (naming the failed check) or is unusable.
pub fn label_mesh(
    mesh: &TriMesh,
    skeleton: &Skeleton,
    options: &AttachOptions,
) -> Result<Labelled, PipelineError> {
    let only_orientation = symcorr_mesh::RepairOptions {
        remove_degenerate: false,
        remove_duplicates: false,
        remove_non_manifold_edge_triangles: false,
        split_non_manifold_vertices: false,
        keep_largest_component: false,
        min_component_triangles: 0,
        remove_unreferenced: false,
        orient_consistently: true,
        ..symcorr_mesh::RepairOptions::default()
    };
    let oriented = symcorr_mesh::repair(mesh, &only_orientation)?;
    let turned_triangles = oriented.report.turned_triangles;
    let attachment = attach(&oriented.mesh, skeleton, options)?;
    Ok(Labelled {
        mesh: oriented.mesh,
        turned_triangles,
        attachment,
    })
}
