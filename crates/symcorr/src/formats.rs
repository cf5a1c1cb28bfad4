//! The JSON files symcorr writes, as types (DESIGN.md, Data formats): `symcorr.correspondence/1`
//! ([`CorrespondenceFile`], written by `match`, `bench --out-dir` and `demo`) and
//! `symcorr.labels/1` ([`LabelsFile`], written by `label`). [`crate::output`] builds them; any
//! reader parses them back with [`CorrespondenceFile::read`] / [`LabelsFile::read`] (from text:
//! [`CorrespondenceFile::from_json_str`] / [`LabelsFile::from_json_str`]) or serde.
//!
//! Fields are declared in alphabetical order, which is the order of the keys in the files
//! (the files were first written through `serde_json::Value`, whose maps sort their keys);
//! `fixtures/formats/` holds files written that way, and the tests compare against them byte
//! for byte. An optional key that is absent is left out (`no_counterpart`, `bones`, `weights`);
//! a value that may be unknown is `null` (a label of a vertex the repair removed,
//! `convention_changes`, `joint_asymmetry`).

use crate::PipelineError;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The `format` tag of correspondence files.
pub const CORRESPONDENCE_FORMAT: &str = "symcorr.correspondence/1";
/// The `format` tag of label files.
pub const LABELS_FORMAT: &str = "symcorr.labels/1";
/// The `format` tag of `match --explain` files.
pub const EXPLAIN_FORMAT: &str = "symcorr.explain/1";

/// A `symcorr.explain/1` file (`match --method paper --explain POINT`): one template point
/// through the paper's stages, its Fig. 2. Vertex ids are the input files' ids.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExplainFile {
    /// Its candidates by si-HKS distance (§3.1), nearest first, before the filter; `kept`
    /// says which the filter left.
    pub candidates: Vec<ExplainedCandidate>,
    /// The filter removed every candidate and `filtered` is its fallback.
    pub fallback: bool,
    /// `off`, `strict` or `extended`.
    pub filter: String,
    /// What the filter left, nearest first (its fallback when it removed every candidate).
    pub filtered: Vec<ExplainedCandidate>,
    /// [`EXPLAIN_FORMAT`].
    pub format: String,
    /// The template point's segment.
    pub segment: String,
    /// The candidate eq. 8 selects, and its `|D̂(c) − D̂(p)|` (`null`: no candidate).
    pub selected: Option<ExplainedSelection>,
    /// The target mesh file.
    pub target: MeshRef,
    /// The template mesh file.
    pub template: MeshRef,
    /// The template point.
    pub template_point: u32,
}

/// A candidate of an [`ExplainFile`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExplainedCandidate {
    /// Euclidean si-HKS distance to the template point's descriptor.
    pub descriptor_distance: f64,
    /// The filter kept it.
    pub kept: bool,
    /// Its segment on the target.
    pub segment: String,
    /// The target vertex.
    pub target: u32,
}

/// The selected match of an [`ExplainFile`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExplainedSelection {
    /// Euclidean si-HKS distance.
    pub descriptor_distance: f64,
    /// `|D̂(c) − D̂(p)|` (eq. 8).
    pub profile_gap: f64,
    /// The target vertex.
    pub target: u32,
}

/// A `symcorr.correspondence/1` file. Vertex ids are the input files' ids.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CorrespondenceFile {
    /// [`CORRESPONDENCE_FORMAT`].
    /// How well each skeleton fits its mesh (absent in files written before fit checks).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<MeshPair<FitEntry>>,
    /// [`CORRESPONDENCE_FORMAT`].
    pub format: String,
    /// For a partial target (a single-view scan): the template points it does not show, by
    /// template id (absent for a whole target).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub no_counterpart: Option<Vec<u32>>,
    /// `[template vertex, target vertex, confidence]` per match (confidence rounded to 1e-6).
    pub pairs: Vec<(u32, u32, f64)>,
    /// Segment label index per input vertex of each mesh (`null`: removed by the repair, or in
    /// a component no bone reaches).
    pub segments: MeshPair<Vec<Option<usize>>>,
    /// What the paper's skeleton filter did (all zero for the other methods).
    pub skeleton_filter: FilterCounts,
    /// The articulated method only: per pair (same order as `pairs`), the point of the target's
    /// surface the template point reaches, `[[a, b, c], [wa, wb, wc]]` — a triangle's corners
    /// (target input ids) and barycentric weights (rounded to 1e-6); `pairs` holds the matched
    /// vertex, one of the corners. Absent for the other methods and in older files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface_points: Option<Vec<([u32; 3], [f64; 3])>>,
    /// The target mesh file.
    pub target: MeshRef,
    /// The template mesh file.
    pub template: MeshRef,
    /// Seconds per stage (rounded to 1e-6), by stage name.
    pub timings_s: BTreeMap<String, f64>,
}

/// One value per mesh of a pair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeshPair<T> {
    /// The target's.
    pub target: T,
    /// The template's.
    pub template: T,
}

/// A mesh file and its vertex count.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct MeshRef {
    /// The path as given on the command line (or the dataset's).
    pub path: String,
    /// Vertices of the file.
    pub vertices: usize,
}

/// The skeleton filter's counts (symcorr-correspond's `FilterStats`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FilterCounts {
    /// Points whose candidate lists fell back to the nearest same-segment vertex.
    pub fallbacks: usize,
    /// Candidates kept.
    pub kept: usize,
    /// Template points filtered.
    pub points: usize,
    /// Candidates removed.
    pub removed: usize,
    /// Points whose segment the target lacks.
    pub segment_missing: usize,
}

/// A `symcorr.labels/1` file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LabelsFile {
    /// With `--weights`: the bones, `"parent-child"` joint names, in the order weights name them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bones: Option<Vec<String>>,
    /// How the attachment went.
    pub diagnostics: LabelDiagnostics,
    /// [`LABELS_FORMAT`].
    pub format: String,
    /// Refined joint positions (mesh units) of the tracked or interpolated joints, by name.
    pub joints: BTreeMap<String, [f64; 3]>,
    /// Segment index per vertex (into `segments`); `null` for a vertex in a component no bone
    /// reaches.
    pub labels: Vec<Option<usize>>,
    /// The mesh file.
    pub mesh: MeshRef,
    /// The 17 segment names, in index order.
    pub segments: Vec<String>,
    /// With `--weights`: per vertex, its non-zero `[bone, weight]` pairs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weights: Option<Vec<Vec<(usize, f64)>>>,
}

/// The `diagnostics` object of a [`LabelsFile`] (symcorr-attach's `Diagnostics`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LabelDiagnostics {
    /// How the skeleton was brought into the mesh's frame.
    pub alignment: Alignment,
    /// Where neighbouring segments end: `"joint-planes"` or `"makehuman"`.
    pub boundaries: String,
    /// Per connected component of the mesh.
    pub components: Vec<Component>,
    /// Vertices the boundary convention moved to another segment (`null` without one).
    pub convention_changes: Option<usize>,
    /// How well the skeleton fits the mesh (absent in files written before fit checks).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<FitEntry>,
    /// Left/right asymmetry of the joints, mesh units (`null` when not measurable).
    pub joint_asymmetry: Option<f64>,
    /// Joints moved by the refinement.
    pub joint_moves: Vec<JointMoveEntry>,
    /// True when the skeleton's left and right were swapped to fit the mesh.
    pub mirrored_fixed: bool,
    /// Vertices labelled by their nearest bone (no bone visible).
    pub nearest_bone_vertices: usize,
    /// Joints repaired before the attachment.
    pub repaired_joints: Vec<RepairedJoint>,
}

/// How well a skeleton fits its mesh (symcorr-attach's `FitQuality`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitEntry {
    /// True when a check failed and the fit was used anyway (`--accept-poor-fit`).
    pub accepted_poor_fit: bool,
    /// The checks that applied, by name.
    pub checks: BTreeMap<String, FitCheckEntry>,
    /// The smallest check quality in [0, 1]; at least 0.5 when every check passed.
    pub score: f64,
    /// Vertices in components no bone reaches (labelled `null`, never matched).
    pub unreached_vertices: usize,
    /// The target of a correspondence seen from one viewpoint (articulated method): the
    /// fraction of the template points the fit shows the camera that lie on the scan
    /// (`Correspondence::view_held`). Absent elsewhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view_held: Option<f64>,
    /// The target's joints were turned half a turn about their spine before the match: the
    /// fit on them as given held less than `TURN_RETRY_BELOW` of its view, the fit on the
    /// turned joints held more (`Pipeline::run_on_view`). Absent when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub turned_about_spine: bool,
    /// The skeleton's left and right were swapped to fit the mesh (symcorr-attach's handedness
    /// check: the feet pointed backwards). Absent when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sides_swapped: bool,
    /// `"arms"` or `"legs"`: that limb pair's left and right were swapped back alone — the
    /// shoulders and the hips pointed opposite ways across the spine (a tracker's arm or leg
    /// swap). Absent when none was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limbs_swapped: Option<String>,
}

/// One fit check of a [`FitEntry`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FitCheckEntry {
    /// Its limit.
    pub limit: f64,
    /// `value <= limit`.
    pub passed: bool,
    /// The measured value (rounded to 1e-6; `null` when not finite).
    pub value: Option<f64>,
}

/// The skeleton-to-mesh alignment (symcorr-attach's `FrameAlignment`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Alignment {
    /// Median joint-to-mesh distance after the alignment, in skeleton heights.
    pub fit_after: f64,
    /// The same before it (after the scale only).
    pub fit_before: f64,
    /// Rotation, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Uniform scale.
    pub scale: f64,
    /// Translation, mesh units.
    pub translation: [f64; 3],
}

/// One connected component of a labelled mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Component {
    /// True when no bone was visible from it and it was labelled by nearest bone.
    pub fallback: bool,
    /// Its vertices.
    pub vertices: usize,
    /// Those that see a bone.
    pub visible_vertices: usize,
}

/// A joint moved by the refinement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointMoveEntry {
    /// How far, mesh units.
    pub distance: f64,
    /// The joint's name.
    pub joint: String,
    /// Why.
    pub reason: String,
}

/// A joint repaired before the attachment.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RepairedJoint {
    /// The joint's name.
    pub joint: String,
    /// `"interpolated"` or `"dropped"`.
    pub repair: String,
}

fn parse_json<T: serde::de::DeserializeOwned>(
    text: &str,
    file: &str,
    format: &str,
    tag: impl Fn(&T) -> &str,
) -> Result<T, PipelineError> {
    let err = |message: String| PipelineError::File {
        file: file.to_string(),
        message,
    };
    let doc: T =
        serde_json::from_str(text).map_err(|e| err(format!("not a {format} file: {e}")))?;
    match tag(&doc) {
        t if t == format => Ok(doc),
        t => Err(err(format!("format {t:?}, expected {format:?}"))),
    }
}

fn read_text(path: &Path) -> Result<(String, String), PipelineError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| PipelineError::File {
        file: file.clone(),
        message: e.to_string(),
    })?;
    Ok((text, file))
}

impl CorrespondenceFile {
    /// Reads a `symcorr.correspondence/1` file (see [`CorrespondenceFile::from_json_str`]).
    ///
    /// Errors ([`PipelineError::File`], naming the file): unreadable, not JSON of this shape,
    /// or another `format`.
    pub fn read(path: &Path) -> Result<CorrespondenceFile, PipelineError> {
        let (text, file) = read_text(path)?;
        CorrespondenceFile::from_json_str(&text, &file)
    }

    /// Parses the text of a `symcorr.correspondence/1` file; `file` names it in errors.
    ///
    /// Errors ([`PipelineError::File`], naming `file`): not JSON of this shape, or another
    /// `format`.
    ///
    /// ```
    /// use symcorr::formats::CorrespondenceFile;
    /// let text = r#"{"format":"symcorr.correspondence/1","pairs":[[0,3,0.9]],
    ///   "segments":{"target":[0,1,null,2],"template":[0]},
    ///   "skeleton_filter":{"fallbacks":0,"kept":0,"points":0,"removed":0,"segment_missing":0},
    ///   "target":{"path":"b.ply","vertices":4},"template":{"path":"a.ply","vertices":1},
    ///   "timings_s":{"articulated":0.5}}"#;
    /// let doc = CorrespondenceFile::from_json_str(text, "<memory>").unwrap();
    /// assert_eq!(doc.pairs, vec![(0, 3, 0.9)]);
    /// assert_eq!(CorrespondenceFile::from_json_str(&doc.to_json(), "<memory>").unwrap(), doc);
    /// let e = CorrespondenceFile::from_json_str("{}", "c.json").unwrap_err();
    /// assert!(e.to_string().starts_with("c.json: not a symcorr.correspondence/1 file"));
    /// ```
    pub fn from_json_str(text: &str, file: &str) -> Result<CorrespondenceFile, PipelineError> {
        parse_json(
            text,
            file,
            CORRESPONDENCE_FORMAT,
            |d: &CorrespondenceFile| &d.format,
        )
    }

    /// The file as compact JSON (what the commands write).
    pub fn to_json(&self) -> String {
        // Invariant: plain numbers, strings, arrays and string-keyed maps always serialise.
        serde_json::to_string(self).unwrap_or_default()
    }
}

impl LabelsFile {
    /// Reads a `symcorr.labels/1` file (see [`LabelsFile::from_json_str`]).
    ///
    /// Errors ([`PipelineError::File`], naming the file): unreadable, not JSON of this shape,
    /// or another `format`.
    pub fn read(path: &Path) -> Result<LabelsFile, PipelineError> {
        let (text, file) = read_text(path)?;
        LabelsFile::from_json_str(&text, &file)
    }

    /// Parses the text of a `symcorr.labels/1` file; `file` names it in errors.
    ///
    /// Errors ([`PipelineError::File`], naming `file`): not JSON of this shape, or another
    /// `format`.
    ///
    /// ```
    /// use symcorr::formats::LabelsFile;
    /// let text = r#"{"diagnostics":{"alignment":{"fit_after":0.01,"fit_before":0.02,
    ///     "rotation":[[1,0,0],[0,1,0],[0,0,1]],"scale":1.0,"translation":[0,0,0]},
    ///   "boundaries":"joint-planes","components":[{"fallback":false,"vertices":3,
    ///     "visible_vertices":3}],"convention_changes":null,"joint_asymmetry":null,
    ///   "joint_moves":[],"mirrored_fixed":false,"nearest_bone_vertices":0,"repaired_joints":[]},
    ///   "format":"symcorr.labels/1","joints":{"head":[0,1.7,0]},"labels":[0,0,1],
    ///   "mesh":{"path":"body.ply","vertices":3},"segments":["head","torso"]}"#;
    /// let doc = LabelsFile::from_json_str(text, "<memory>").unwrap();
    /// assert_eq!(doc.labels, vec![Some(0), Some(0), Some(1)]);
    /// assert_eq!(LabelsFile::from_json_str(&doc.to_json(), "<memory>").unwrap(), doc);
    /// let e = LabelsFile::from_json_str("[]", "l.json").unwrap_err();
    /// assert!(e.to_string().starts_with("l.json: not a symcorr.labels/1 file"));
    /// ```
    pub fn from_json_str(text: &str, file: &str) -> Result<LabelsFile, PipelineError> {
        parse_json(text, file, LABELS_FORMAT, |d: &LabelsFile| &d.format)
    }

    /// The file as compact JSON (what `symcorr label` writes).
    pub fn to_json(&self) -> String {
        // Invariant: plain numbers, strings, arrays and string-keyed maps always serialise.
        serde_json::to_string(self).unwrap_or_default()
    }
}
