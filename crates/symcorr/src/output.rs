//! Output files: `symcorr.correspondence/1`, `symcorr.labels/1` and `symcorr.explain/1` JSON
//! ([`crate::formats`]),
//! match- and segment-coloured meshes, the cumulative error curve as SVG. Every file is written
//! through [`symcorr_mesh::io::atomic_write`] (temporary file in the same directory, then
//! rename), so a failure never leaves a half-written output.

use crate::formats::{
    Alignment, Component, CorrespondenceFile, ExplainFile, ExplainedCandidate, ExplainedSelection,
    FilterCounts, FitCheckEntry, FitEntry, JointMoveEntry, LabelDiagnostics, LabelsFile, MeshPair,
    MeshRef, RepairedJoint, EXPLAIN_FORMAT, LABELS_FORMAT,
};
use crate::{Correspondence, PreparedMesh};
use nalgebra::{distance_squared, Point3};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use symcorr_attach::{palette, Attachment};
use symcorr_correspond::{PaperFilter, PointExplanation};
use symcorr_skeleton::{Joint, Segment, BONES};

pub use crate::formats::CORRESPONDENCE_FORMAT;

/// Stage timings of a pair: each per-mesh stage summed over the two meshes, then the pair
/// stages, in pipeline order.
pub fn pair_timings(
    template: &PreparedMesh,
    target: &PreparedMesh,
    corr: &Correspondence,
) -> Vec<(String, f64)> {
    let mut out: Vec<(String, f64)> = Vec::new();
    for (name, s) in template.timings.iter().chain(&target.timings) {
        match out.iter_mut().find(|(n, _)| n == name) {
            Some((_, t)) => *t += s,
            None => out.push((name.clone(), *s)),
        }
    }
    out.extend(corr.timings.iter().cloned());
    out
}

/// The `symcorr.correspondence/1` document (DESIGN.md, Data formats). For a partial target
/// (a single-view scan) `pairs` holds only the template points the target shows; the others
/// are listed by template id under the extra key `no_counterpart`.
pub fn correspondence_json(
    template_path: &str,
    template: &PreparedMesh,
    target_path: &str,
    target: &PreparedMesh,
    corr: &Correspondence,
    timings: &[(String, f64)],
) -> CorrespondenceFile {
    // Ids in the file are the input files' ids (the stages ran on the repaired meshes).
    // Template points a partial target does not show are listed apart, not as pairs.
    let seen = |i: usize| corr.has_counterpart().is_none_or(|h| h[i]);
    let no_counterpart: Vec<u32> = corr
        .pairs
        .iter()
        .enumerate()
        .filter(|&(i, _)| !seen(i))
        .map(|(_, m)| template.input_id(m.template))
        .collect();
    let surface_points = corr.surface_points(target).map(|points| {
        points
            .iter()
            .enumerate()
            .filter(|&(i, _)| seen(i))
            .map(|(_, p)| (p.corners.map(|c| target.input_id(c)), p.weights.map(round6)))
            .collect()
    });
    let pairs = corr
        .pairs
        .iter()
        .enumerate()
        .filter(|&(i, _)| seen(i))
        .map(|(_, m)| {
            (
                template.input_id(m.template),
                target.input_id(m.target),
                round6(m.confidence),
            )
        })
        .collect();
    // One label per input vertex; `null` for a vertex the repair removed.
    let labels = |p: &PreparedMesh| -> Vec<Option<usize>> {
        let l: Vec<Option<usize>> = p.labels().iter().map(|s| Some(s.index())).collect();
        p.to_input(&l, None)
    };
    let mesh = |path: &str, p: &PreparedMesh| MeshRef {
        path: path.to_string(),
        vertices: p.input_mesh().num_vertices(),
    };
    let f = corr.filter_stats();
    CorrespondenceFile {
        fit: Some(MeshPair {
            target: FitEntry {
                view_held: corr.view_held().map(round6),
                ..fit_entry(&target.attachment.diagnostics, target.unreached)
            },
            template: fit_entry(&template.attachment.diagnostics, template.unreached),
        }),
        format: CORRESPONDENCE_FORMAT.to_string(),
        no_counterpart: corr.has_counterpart().map(|_| no_counterpart),
        pairs,
        segments: MeshPair {
            target: labels(target),
            template: labels(template),
        },
        surface_points,
        skeleton_filter: FilterCounts {
            fallbacks: f.fallbacks,
            kept: f.kept,
            points: f.points,
            removed: f.removed,
            segment_missing: f.segment_missing,
        },
        target: mesh(target_path, target),
        template: mesh(template_path, template),
        timings_s: timings
            .iter()
            .map(|(n, s)| (n.clone(), round6(*s)))
            .collect(),
    }
}

/// The `fit` block of the output files; `unreached` counts the vertices left out because no bone
/// reaches their component.
pub fn fit_entry(d: &symcorr_attach::Diagnostics, unreached: usize) -> FitEntry {
    let fit = &d.fit;
    FitEntry {
        accepted_poor_fit: fit.accepted_poor_fit,
        checks: fit
            .checks
            .iter()
            .map(|c| {
                (
                    c.kind.name().to_string(),
                    FitCheckEntry {
                        limit: c.limit,
                        passed: c.passed,
                        value: c.value.is_finite().then(|| round6(c.value)),
                    },
                )
            })
            .collect(),
        score: round6(fit.score),
        unreached_vertices: unreached.max(fit.unreached.len()),
        view_held: None,
        turned_about_spine: false,
        sides_swapped: d.mirror.swapped,
        limbs_swapped: d.mirror.swapped_limbs.map(|p| p.name().to_string()),
    }
}

/// The `symcorr.labels/1` document of `mesh_path` (with `vertices` vertices) and its attachment
/// (DESIGN.md, Data formats). `boundaries` names the segment-boundary convention used
/// (`"joint-planes"` or `"makehuman"`); `weights` adds the bones and the sparse bone-heat
/// weights per vertex.
pub fn labels_file(
    mesh_path: &str,
    vertices: usize,
    attachment: &Attachment,
    boundaries: &str,
    weights: bool,
) -> LabelsFile {
    let att = attachment;
    let d = &att.diagnostics;
    let al = &d.alignment;
    let joints: BTreeMap<String, [f64; 3]> = Joint::ALL
        .iter()
        .filter(|&&j| att.joints.tracks(j))
        .map(|&j| {
            (
                j.name().to_string(),
                <[f64; 3]>::from(att.joints.position(j)),
            )
        })
        .collect();
    LabelsFile {
        bones: weights.then(|| {
            BONES
                .iter()
                .map(|b| format!("{}-{}", b.parent.name(), b.child.name()))
                .collect()
        }),
        diagnostics: LabelDiagnostics {
            alignment: Alignment {
                fit_after: al.fit_after,
                fit_before: al.fit_before,
                // Row-major, as the file has always stored it.
                rotation: std::array::from_fn(|i| {
                    std::array::from_fn(|j| al.rotation.matrix()[(i, j)])
                }),
                scale: al.scale,
                translation: al.translation.into(),
            },
            boundaries: boundaries.to_string(),
            components: d
                .components
                .iter()
                .map(|c| Component {
                    fallback: c.fallback,
                    vertices: c.vertices,
                    visible_vertices: c.visible_vertices,
                })
                .collect(),
            convention_changes: d.convention_changes,
            fit: Some(fit_entry(d, 0)),
            joint_asymmetry: d.joint_asymmetry,
            joint_moves: d
                .joint_moves
                .iter()
                .map(|m| JointMoveEntry {
                    distance: m.distance(),
                    joint: m.joint.name().to_string(),
                    reason: m.reason.to_string(),
                })
                .collect(),
            mirrored_fixed: d.mirror.swapped,
            nearest_bone_vertices: d.nearest_bone_vertices,
            repaired_joints: d
                .repaired_joints
                .iter()
                .map(|(j, r)| RepairedJoint {
                    joint: j.name().to_string(),
                    repair: format!("{r:?}").to_lowercase(),
                })
                .collect(),
        },
        format: LABELS_FORMAT.to_string(),
        joints,
        labels: crate::label::segment_labels(att),
        mesh: MeshRef {
            path: mesh_path.to_string(),
            vertices,
        },
        segments: Segment::ALL.iter().map(|s| s.name().to_string()).collect(),
        weights: weights.then(|| (0..vertices).map(|v| att.weights.row(v).to_vec()).collect()),
    }
}

/// The repair report as JSON (stable keys; counts refer to the input mesh).
pub fn repair_json(r: &symcorr_mesh::RepairReport, mesh: &symcorr_mesh::TriMesh) -> Value {
    json!({
        "changed": !r.unchanged(),
        "removed_degenerate_triangles": r.removed_degenerate_triangles,
        "removed_zero_area_triangles": r.removed_zero_area_triangles,
        "removed_duplicate_triangles": r.removed_duplicate_triangles,
        "removed_non_manifold_edge_triangles": r.removed_non_manifold_edge_triangles,
        "removed_components": r.removed_components,
        "removed_vertices": r.removed_vertices,
        "added_split_vertices": r.added_split_vertices,
        "turned_triangles": r.turned_triangles,
        "components": r.after.components(),
        "boundary_loops": r.after.boundary_loops.len(),
        "non_manifold_edges": r.after.non_manifold_edges.len(),
        "non_manifold_vertices": r.after.non_manifold_vertices.len(),
        "vertices_after": mesh.num_vertices(),
        "triangles_after": mesh.num_triangles(),
    })
}

fn round6(x: f64) -> f64 {
    (x * 1e6).round() / 1e6
}

/// A smooth colour field over the template: position in the bounding box → RGB, so that nearby
/// points have similar colours and distant ones different.
fn field_colour(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> [u8; 3] {
    let mut c = [0u8; 3];
    for k in 0..3 {
        let t = ((p[k] - lo[k]) / (hi[k] - lo[k]).max(1e-300)).clamp(0.0, 1.0);
        c[k] = (40.0 + 215.0 * t).round() as u8;
    }
    c
}

/// The `symcorr.explain/1` file of one template point's [`PointExplanation`] (prepared ids, as
/// [`crate::Pipeline::explain`] returns it), in the input files' ids.
pub fn explain_file(
    (template_path, template): (&str, &PreparedMesh),
    (target_path, target): (&str, &PreparedMesh),
    filter: PaperFilter,
    e: &PointExplanation,
) -> ExplainFile {
    let mesh = |path: &str, p: &PreparedMesh| MeshRef {
        path: path.to_string(),
        vertices: p.input_mesh().num_vertices(),
    };
    let candidate = |c: &symcorr_correspond::Candidate| ExplainedCandidate {
        descriptor_distance: c.distance,
        kept: e.filtered.iter().any(|f| f.vertex == c.vertex),
        segment: target.labels()[c.vertex as usize].name().to_string(),
        target: target.input_id(c.vertex),
    };
    ExplainFile {
        candidates: e.candidates.iter().map(candidate).collect(),
        fallback: e.fallback,
        filter: match filter {
            PaperFilter::Off => "off",
            PaperFilter::Strict => "strict",
            PaperFilter::Extended { .. } => "extended",
        }
        .to_string(),
        filtered: e.filtered.iter().map(candidate).collect(),
        format: EXPLAIN_FORMAT.to_string(),
        segment: template.labels()[e.point as usize].name().to_string(),
        selected: e.selected.as_ref().map(|(c, gap)| ExplainedSelection {
            descriptor_distance: c.distance,
            profile_gap: *gap,
            target: target.input_id(c.vertex),
        }),
        target: mesh(target_path, target),
        template: mesh(template_path, template),
        template_point: template.input_id(e.point),
    }
}

/// Per-vertex colours of the template and the target in which matched points share a colour:
/// each template point gets the colour of its position; every template vertex shows its nearest
/// matched point's colour, and every target vertex the colour of the match whose target point is
/// nearest (Euclidean). In dense mode this is exactly "vertex `q` has the colour of the template
/// vertex matched to it".
pub fn match_colours(
    template: &PreparedMesh,
    target: &PreparedMesh,
    corr: &Correspondence,
) -> (Vec<[u8; 3]>, Vec<[u8; 3]>) {
    let (lo, hi) = template.mesh.bounding_box();
    let tp = &template.mesh.positions;
    let colours: Vec<[u8; 3]> = corr
        .pairs
        .iter()
        .map(|m| field_colour(tp[m.template as usize], lo, hi))
        .collect();
    let spread = |mesh: &symcorr_mesh::TriMesh, anchor: &(dyn Fn(usize) -> usize + Sync)| {
        let grey = [128u8, 128, 128];
        let mut out = vec![grey; mesh.num_vertices()];
        // Exact anchors first, then nearest anchor for the rest.
        let mut has = vec![false; mesh.num_vertices()];
        for (i, c) in colours.iter().enumerate() {
            let v = anchor(i);
            out[v] = *c;
            has[v] = true;
        }
        let anchors: Vec<usize> = (0..colours.len()).collect();
        if anchors.is_empty() {
            return out;
        }
        use rayon::prelude::*;
        let fill: Vec<Option<[u8; 3]>> = (0..mesh.num_vertices())
            .into_par_iter()
            .map(|v| {
                if has[v] {
                    return None;
                }
                let p = Point3::from(mesh.positions[v]);
                let d2 = |i: usize| distance_squared(&p, &Point3::from(mesh.positions[i]));
                let best = anchors
                    .iter()
                    .min_by(|&&a, &&b| {
                        let da = d2(anchor(a));
                        let db = d2(anchor(b));
                        da.total_cmp(&db)
                    })
                    .copied()
                    .unwrap_or(0);
                Some(colours[best])
            })
            .collect();
        for (v, c) in fill.into_iter().enumerate() {
            if let Some(c) = c {
                out[v] = c;
            }
        }
        out
    };
    let m = &corr.pairs;
    let t_col = spread(&template.mesh, &|i| m[i].template as usize);
    let u_col = spread(&target.mesh, &|i| m[i].target as usize);
    (t_col, u_col)
}

/// Per-vertex colours of `p`'s repaired mesh spread onto the input mesh's vertices (grey for a
/// vertex the repair removed), so that a coloured output has the input file's vertex ids.
pub fn input_colours(p: &PreparedMesh, colours: &[[u8; 3]]) -> Vec<[u8; 3]> {
    p.to_input(colours, [128u8, 128, 128])
}

/// Segment colours (symcorr-attach's palette) per vertex.
pub fn segment_colours(p: &PreparedMesh) -> Vec<[u8; 3]> {
    p.labels().iter().map(|&s| palette::colour(s)).collect()
}

/// The cumulative error curve(s) as a self-contained SVG plot: x = normalised geodesic error in
/// [0, `max_x`], y = fraction of matches. `curves` are `(label, points)`.
pub fn curve_svg(title: &str, curves: &[(String, Vec<(f64, f64)>)], max_x: f64) -> String {
    line_plot_svg(
        &PlotAxes {
            title,
            x_label: "geodesic error / sqrt(area)",
            y_label: "% of matches",
            max_x,
        },
        curves,
    )
}

/// The frame of a [`line_plot_svg`]: x in `[0, max_x]`, y in `[0, 1]` shown as percent.
#[derive(Debug, Clone, Copy)]
pub struct PlotAxes<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// Label under the x axis.
    pub x_label: &'a str,
    /// Label beside the y axis.
    pub y_label: &'a str,
    /// Right end of the x axis.
    pub max_x: f64,
}

/// Curves `(label, points)` with y in `[0, 1]` as a self-contained SVG line plot.
pub fn line_plot_svg(axes: &PlotAxes<'_>, curves: &[(String, Vec<(f64, f64)>)]) -> String {
    let (title, max_x) = (axes.title, axes.max_x);
    let (w, h) = (640.0, 440.0);
    let (l, r, t, b) = (70.0, 20.0, 40.0, 60.0);
    let pw = w - l - r;
    let ph = h - t - b;
    let sx = |x: f64| l + pw * (x / max_x);
    let sy = |y: f64| t + ph * (1.0 - y);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\" font-size=\"12\">\n\
         <rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n\
         <text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">{}</text>\n",
        w / 2.0,
        xml_escape(title)
    );
    // Grid and axes.
    for i in 0..=5 {
        let x = max_x * i as f64 / 5.0;
        let px = sx(x);
        s += &format!(
            "<line x1=\"{px:.1}\" y1=\"{:.1}\" x2=\"{px:.1}\" y2=\"{:.1}\" stroke=\"#ddd\"/>\n<text x=\"{px:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>\n",
            sy(0.0),
            sy(1.0),
            sy(0.0) + 18.0,
            if max_x >= 10.0 {
                format!("{x:.0}")
            } else {
                format!("{x:.2}")
            }
        );
        let y = i as f64 / 5.0;
        let py = sy(y);
        s += &format!(
            "<line x1=\"{:.1}\" y1=\"{py:.1}\" x2=\"{:.1}\" y2=\"{py:.1}\" stroke=\"#ddd\"/>\n<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{:.0}%</text>\n",
            sx(0.0),
            sx(max_x),
            sx(0.0) - 6.0,
            py + 4.0,
            y * 100.0
        );
    }
    s += &format!(
        "<rect x=\"{l}\" y=\"{t}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"black\"/>\n\
         <text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n\
         <text x=\"18\" y=\"{}\" text-anchor=\"middle\" transform=\"rotate(-90 18 {})\">{}</text>\n",
        l + pw / 2.0,
        h - 15.0,
        xml_escape(axes.x_label),
        t + ph / 2.0,
        t + ph / 2.0,
        xml_escape(axes.y_label)
    );
    const COLOURS: [&str; 6] = [
        "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b",
    ];
    for (i, (label, pts)) in curves.iter().enumerate() {
        let c = COLOURS[i % COLOURS.len()];
        let path: Vec<String> = pts
            .iter()
            .map(|&(x, y)| format!("{:.2},{:.2}", sx(x), sy(y)))
            .collect();
        s += &format!(
            "<polyline fill=\"none\" stroke=\"{c}\" stroke-width=\"2\" points=\"{}\"/>\n\
             <line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{c}\" stroke-width=\"2\"/>\n\
             <text x=\"{:.1}\" y=\"{:.1}\">{}</text>\n",
            path.join(" "),
            l + pw - 200.0,
            t + ph - 20.0 - 18.0 * i as f64,
            l + pw - 175.0,
            t + ph - 20.0 - 18.0 * i as f64,
            l + pw - 170.0,
            t + ph - 16.0 - 18.0 * i as f64,
            xml_escape(label)
        );
    }
    s += "</svg>\n";
    s
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_has_one_polyline_per_curve_and_escapes() {
        let c = vec![
            ("a<b".to_string(), vec![(0.0, 0.0), (0.25, 1.0)]),
            ("c".to_string(), vec![(0.0, 0.5), (0.25, 0.5)]),
        ];
        let s = curve_svg("t & u", &c, 0.25);
        assert_eq!(s.matches("<polyline").count(), 2);
        assert!(s.contains("a&lt;b") && s.contains("t &amp; u"));
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
    }
}
