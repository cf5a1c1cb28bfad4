//! Per-mesh preparation ([`PreparedMesh`]): the default repair, the skeleton attachment and
//! what the chosen methods need (the paper's descriptors, base vertex set and midline halves;
//! the refined method's eigenpairs, landmarks and symmetry halves), computed once per mesh and
//! reused for every pair it is in.

use crate::midline::{midline_halves, midline_sagittal, symmetric_midline_halves};
use crate::pipeline::Method;
use crate::{OptionError, PipelineError};
use nalgebra::Point3;
use std::time::Instant;
use symcorr_attach::{attach, AttachOptions, Attachment};
use symcorr_correspond::{
    base_profile, landmark_coordinates, skeleton_landmarks, Descriptors, PaperInputs,
};
use symcorr_mesh::{repair, RepairOptions, RepairReport, TriMesh};
use symcorr_skeleton::{BodySide, Segment, Skeleton};
use symcorr_spectral::{
    base_vertex_set, eigenpairs, gaussian_curvature, si_hks, EdgeGraph, EigenOptions,
    HeatGeodesics, Laplacian, SiHksParams,
};

/// Boundary length over √area above which a mesh counts as a partial view
/// ([`PreparedMesh::is_partial`]). Measured: 0 on the generated bodies, 25–34 on their
/// virtual-Kinect scans (58 views); a full-body scan with holes at the soles and the crown
/// stays far below 5.
pub const PARTIAL_BOUNDARY_RATIO: f64 = 5.0;

pub use symcorr_mesh::geometry::ORIGIN_FACING_FRACTION;

/// Metres per unit for a skeleton `height` units tall ([`PreparedMesh::metres_per_unit`]).
pub fn metres_per_unit(height: f64) -> f64 {
    if !(height.is_finite() && height > 0.0) {
        return 1.0;
    }
    10f64.powi(-((height / 0.3).log10().floor() as i32))
}

/// Per-mesh options: what [`PreparedMesh::new`] computes.
#[derive(Debug, Clone)]
pub struct PrepareOptions {
    /// Number of Laplace–Beltrami eigenpairs behind the si-HKS.
    pub eigenpairs: usize,
    /// si-HKS parameters. `tau_start`/`tau_end` are taken **relative to the mesh's area**:
    /// the times used are `t = area · α^τ` ([`SiHksParams::relative_to_area`]; default
    /// [`SiHksParams::area_relative`]).
    pub si_hks: SiHksParams,
    /// Radius of the base vertex set's greedy cover, in units of √area (§3.3).
    pub base_radius: f64,
    /// Skeleton attachment options.
    pub attach: AttachOptions,
    /// Half-width of the band around the skeleton's sagittal plane in which a midline vertex
    /// gets no half ([`midline_halves`]), in units of √area.
    pub midline_margin: f64,
    /// Keep the eigenpairs on disk and reuse them ([`crate::cache`]): `None` (the
    /// default) always runs the eigensolver. A file is used only if it was written for exactly
    /// this (repaired) mesh, eigenpair count and solver setting; a stale, corrupted or unreadable
    /// file is recomputed and rewritten (the policy's observer hears about it), never used.
    /// On a hit the `eigenpairs` timing is named `eigenpairs_cached`.
    pub cache: Option<crate::cache::CachePolicy>,
}

/// Default eigenpair count: 60. On the generated bodies 100 changed the mean error by < 0.003
/// (0.060 vs 0.062, 6-pair subset) at a higher eigensolve cost.
pub const DEFAULT_EIGENPAIRS: usize = 60;
/// Default base-set radius in √area units (measured: see the crate docs).
pub const DEFAULT_BASE_RADIUS: f64 = 0.1;
/// Default [`PrepareOptions::midline_margin`]: 0 — every midline vertex gets a half, so a
/// match never crosses the plane (a wrong plane costs small errors near it, not flips).
pub const DEFAULT_MIDLINE_MARGIN: f64 = 0.0;

impl Default for PrepareOptions {
    /// si-HKS: [`SiHksParams::area_relative`] (Bronstein & Kokkinos's `α = 2`, step 1/16 and 6
    /// frequencies, over `t/area ∈ [2^-8, 2^3]`; why and the measurements: its docs and the
    /// README).
    fn default() -> Self {
        PrepareOptions {
            eigenpairs: DEFAULT_EIGENPAIRS,
            si_hks: SiHksParams::area_relative(),
            base_radius: DEFAULT_BASE_RADIUS,
            attach: AttachOptions::default(),
            midline_margin: DEFAULT_MIDLINE_MARGIN,
            cache: None,
        }
    }
}

/// Everything about one mesh that does not depend on the other mesh of a pair: computed once,
/// reused for every pair the mesh is in (`symcorr bench` prepares each mesh of a dataset once).
#[derive(Debug, Clone)]
pub struct PreparedMesh {
    /// The mesh every stage works on: the input after the default repair
    /// ([`RepairOptions::default`]: degenerate, zero-area and duplicate triangles and
    /// unreferenced vertices removed). Vertex ids of every field refer to this mesh;
    /// [`PreparedMesh::input_id`] maps them back to the input file's ids.
    pub mesh: TriMesh,
    /// What the repair found and changed (counts refer to the input).
    pub repair: RepairReport,
    /// `vertex_map[v]` = the input id of vertex `v` of [`PreparedMesh::mesh`].
    pub vertex_map: Vec<u32>,
    /// The input mesh, kept only when the repair changed it or components were left out
    /// (outputs are written in its ids).
    pub input: Option<TriMesh>,
    /// Vertices of the repaired input left out because no bone reaches their component
    /// ([`symcorr_attach::FitQuality::unreached`]): they have no label and no match.
    pub unreached: usize,
    /// Total surface area.
    pub area: f64,
    /// Skeleton attachment: segment labels, weights, refined joints.
    pub attachment: Attachment,
    /// What the paper's method needs (prepared for [`Method::Paper`]).
    pub paper: Option<PaperData>,
    /// What the refined method needs (prepared for [`Method::Refined`]).
    pub refine: Option<RefineData>,
    /// Total length of the mesh's boundary edges (0 for a closed surface): a single-view scan
    /// has a long one ([`PreparedMesh::is_partial`]).
    pub boundary_length: f64,
    /// Per vertex of [`PreparedMesh::mesh`]: does it lie on the boundary (an edge of one
    /// triangle)? The vertices of the repair's boundary loops, which hold every boundary
    /// edge; the articulated method reads it on every target.
    pub boundary_vertices: Vec<bool>,
    /// Where the mesh was seen from, when it is one view of a body (a depth scan's camera
    /// centre, in the mesh's frame: the origin for `symcorr scan`'s camera-space scans). As a
    /// target of the articulated method it turns on the occlusion test: template vertices
    /// hidden behind the posed template's own surface get no counterpart. `None` (the
    /// default): unknown, or not one view. Set with [`PreparedMesh::seen_from`].
    pub viewpoint: Option<nalgebra::Point3<f64>>,
    /// Seconds per stage (`laplacian`, `eigenpairs`, `si_hks`, `curvature`, `base_set`,
    /// `base_profile`, `attachment`). Attachment runs in parallel with the spectral stages.
    pub timings: Vec<(String, f64)>,
}

impl PreparedMesh {
    /// Runs the per-mesh stages that `methods` need: always the default mesh repair and
    /// skeleton attachment; for [`Method::Paper`] the Laplacian, eigenpairs, si-HKS, curvature,
    /// base vertex set and its distance profile, and the sagittal halves; for
    /// [`Method::Refined`] the eigenpairs, si-HKS, landmark coordinates and symmetry halves.
    /// The spectral stages run in parallel with the attachment. A mesh prepared for one method
    /// is refused by another that needs more.
    ///
    /// Errors: [`PipelineError::Mesh`] (broken invariants, nothing left after the repair),
    /// [`PipelineError::Spectral`] (e.g. a non-converging eigensolve), [`PipelineError::Attach`]
    /// (a skeleton that does not fit the mesh).
    pub fn new(
        input: TriMesh,
        skeleton: &Skeleton,
        methods: &[Method],
        options: &PrepareOptions,
    ) -> Result<PreparedMesh, PipelineError> {
        let needs = Needs::of(methods);
        if needs.spectral() && options.eigenpairs < 2 {
            return Err(OptionError::TooFewEigenpairs(options.eigenpairs).into());
        }
        // Scans and exported meshes carry degenerate faces and stray vertices that would make
        // the Laplacian singular; remove them and keep the map back to the input ids.
        let repaired = repair(&input, &RepairOptions::default())?;
        if repaired.mesh.num_triangles() == 0 {
            return Err(PipelineError::NothingLeftAfterRepair);
        }
        let (mesh, vertex_map, report) = (repaired.mesh, repaired.vertex_map, repaired.report);
        // The repair's report already traced the boundary of the mesh it returned.
        let boundary_length: f64 = report
            .after
            .boundary_loops
            .iter()
            .map(|l| mesh.loop_length(l))
            .sum();
        let mut boundary_vertices = vec![false; mesh.num_vertices()];
        for &v in report.after.boundary_loops.iter().flatten() {
            boundary_vertices[v as usize] = true;
        }
        let input = if report.unchanged() {
            None
        } else {
            Some(input)
        };
        let (spectral, attached) = rayon::join(
            || spectral_stages(&mesh, needs, options),
            || {
                let t = Instant::now();
                attach(&mesh, skeleton, &options.attach).map(|a| (a, t.elapsed().as_secs_f64()))
            },
        );
        let (sp, mut timings) = spectral?;
        let (attachment, t_attach) = attached?;
        let unreached = &attachment.diagnostics.fit.unreached;
        if !unreached.is_empty() && unreached.len() < mesh.num_vertices() {
            // Components no bone reaches (a stray object beside the body) get no label and are
            // never matched: prepare the rest, and map its ids back through this mesh's.
            let mut keep = vec![true; mesh.num_vertices()];
            for &v in unreached {
                keep[v as usize] = false;
            }
            let (sub, sub_map) = mesh.submesh(&keep)?;
            let mut p = PreparedMesh::new(sub, skeleton, methods, options)?;
            let composed: Vec<u32> = p
                .vertex_map
                .iter()
                .map(|&v| vertex_map[sub_map[v as usize] as usize])
                .collect();
            p.vertex_map = composed;
            p.repair = report;
            p.unreached = unreached.len();
            p.input = Some(input.unwrap_or(mesh));
            return Ok(p);
        }
        timings.push(("attachment".into(), t_attach));
        let area = mesh.total_area();
        let paper = match sp.paper {
            Some((descriptors, base_set, profile)) => Some(PaperData {
                halves: midline_halves(
                    &mesh,
                    &attachment.labels,
                    &attachment.joints,
                    options.midline_margin * area.sqrt(),
                ),
                sagittal: midline_sagittal(&mesh, &attachment.labels, &attachment.joints),
                descriptors,
                curvature: sp.curvature,
                base_set,
                profile,
            }),
            None => None,
        };
        let refine = match sp.refine {
            Some(r) => Some(RefineData::new(&mesh, &attachment, r, &mut timings)?),
            None => None,
        };
        Ok(PreparedMesh {
            unreached: 0,
            viewpoint: None,
            boundary_length,
            boundary_vertices,
            paper,
            refine,
            area,
            mesh,
            repair: report,
            vertex_map,
            input,
            attachment,
            timings,
        })
    }

    /// This mesh, seen from `eye` ([`PreparedMesh::viewpoint`]).
    ///
    /// ```no_run
    /// # let (pipeline, scan, joints): (symcorr::Pipeline, symcorr_mesh::TriMesh, symcorr_attach::Skeleton) = unimplemented!();
    /// // A camera-space depth scan: the camera sits at the origin.
    /// let target = pipeline.prepare(scan, &joints)?.seen_from(nalgebra::Point3::origin());
    /// # Ok::<(), symcorr::PipelineError>(())
    /// ```
    pub fn seen_from(mut self, eye: nalgebra::Point3<f64>) -> PreparedMesh {
        self.viewpoint = Some(eye);
        self
    }

    /// Where this mesh was seen from: [`PreparedMesh::viewpoint`] when set; else, for a
    /// partial view ([`PreparedMesh::is_partial`]), the origin when it looks like a
    /// camera-space depth scan (what `symcorr scan` writes, [`symcorr_attach::camera_side`]): at
    /// least [`ORIGIN_FACING_FRACTION`] of its area faces the origin, all from the same side,
    /// from a distance, with the torso's joints not in front of the surface. `None` otherwise.
    pub fn view_point(&self) -> Option<Point3<f64>> {
        if self.viewpoint.is_some() || !self.is_partial() {
            return self.viewpoint;
        }
        symcorr_attach::camera_side(&self.mesh, &self.attachment.joints).map(|_| Point3::origin())
    }

    /// True when the mesh is a partial view of a body (a single-view scan): its boundary is
    /// longer than [`PARTIAL_BOUNDARY_RATIO`]·√area. A closed body has no boundary; a full-body
    /// scan with a few holes (soles, crown) stays well below; the silhouette of one view alone
    /// is several body heights long.
    pub fn is_partial(&self) -> bool {
        self.boundary_length > PARTIAL_BOUNDARY_RATIO * self.area.sqrt()
    }

    /// Metres per unit of this mesh, from its own skeleton: the power of ten that puts the
    /// skeleton's height (in the mesh's units, after alignment) in [0.3, 3) m. Template and
    /// target may come in different units (a bundled body in metres, a scan in millimetres);
    /// the articulated method brings the template into the target's.
    ///
    /// ```
    /// assert_eq!(symcorr::metres_per_unit(1.7), 1.0);
    /// assert_eq!(symcorr::metres_per_unit(1700.0), 1e-3);
    /// assert_eq!(symcorr::metres_per_unit(170.0), 1e-2);
    /// ```
    pub fn metres_per_unit(&self) -> f64 {
        metres_per_unit(self.attachment.diagnostics.skeleton_height)
    }

    /// Segment label per vertex.
    pub fn labels(&self) -> &[Segment] {
        &self.attachment.labels
    }

    /// Number of vertices (of the repaired mesh the stages work on).
    pub fn num_vertices(&self) -> usize {
        self.mesh.num_vertices()
    }

    /// The input file's id of vertex `v` of [`PreparedMesh::mesh`].
    pub fn input_id(&self, v: u32) -> u32 {
        self.vertex_map[v as usize]
    }

    /// The mesh as read, before the repair (the same as [`PreparedMesh::mesh`] when the repair
    /// changed nothing).
    pub fn input_mesh(&self) -> &TriMesh {
        self.input.as_ref().unwrap_or(&self.mesh)
    }

    /// Per-vertex `values` of [`PreparedMesh::mesh`] carried onto the input mesh's vertices,
    /// `fill` where the repair removed a vertex: what every output written in the input file's
    /// ids needs.
    pub fn to_input<T: Clone>(&self, values: &[T], fill: T) -> Vec<T> {
        let mut out = vec![fill; self.input_mesh().num_vertices()];
        for (v, x) in values.iter().enumerate() {
            out[self.input_id(v as u32) as usize] = x.clone();
        }
        out
    }

    /// `input → prepared` id map: `None` for input vertices the repair removed. A split vertex
    /// maps to its first copy.
    pub fn prepared_ids(&self) -> Vec<Option<u32>> {
        let mut out = vec![None; self.input_mesh().num_vertices()];
        for (v, &i) in self.vertex_map.iter().enumerate() {
            if out[i as usize].is_none() {
                out[i as usize] = Some(v as u32);
            }
        }
        out
    }

    /// The paper method's per-mesh data. Errors unless the mesh was prepared for
    /// [`Method::Paper`].
    pub fn paper_data(&self) -> Result<&PaperData, PipelineError> {
        self.paper
            .as_ref()
            .ok_or(PipelineError::NotPreparedFor(Method::Paper))
    }

    /// This mesh as one side of the paper's matching stages (symcorr-correspond's
    /// `match_points`): descriptors, labels, base-set profile, halves, sagittal coordinates and
    /// positions. Errors unless the mesh was prepared for [`Method::Paper`].
    pub fn paper_side(&self) -> Result<PaperInputs<'_>, PipelineError> {
        let p = self.paper_data()?;
        Ok(PaperInputs {
            descriptors: &p.descriptors,
            labels: &self.attachment.labels,
            profile: &p.profile,
            halves: Some(&p.halves),
            sagittal: Some(&p.sagittal),
            positions: Some(&self.mesh.positions),
        })
    }
}

/// Per-mesh data of the paper's method (§3.1–3.3) and its sagittal constraint.
#[derive(Debug, Clone)]
pub struct PaperData {
    /// si-HKS descriptor per vertex (§3.1).
    pub descriptors: Descriptors,
    /// Gaussian curvature per vertex (eq. 4).
    pub curvature: Vec<f64>,
    /// The base vertex set (§3.3).
    pub base_set: Vec<u32>,
    /// `D̂(v)`: mean edge-geodesic distance to the base set over √area (eq. 7).
    pub profile: Vec<f64>,
    /// Sagittal half per vertex of the midline segments ([`midline_halves`]).
    pub halves: Vec<BodySide>,
    /// Sagittal coordinate per vertex of the midline segments ([`midline_sagittal`]).
    pub sagittal: Vec<f64>,
}

/// Which per-mesh stages a set of methods needs.
#[derive(Debug, Clone, Copy, Default)]
struct Needs {
    paper: bool,
    refine: bool,
}

impl Needs {
    fn of(methods: &[Method]) -> Needs {
        Needs {
            paper: methods.contains(&Method::Paper),
            refine: methods.contains(&Method::Refined),
        }
    }

    fn spectral(self) -> bool {
        self.paper || self.refine
    }
}

struct Spectral {
    curvature: Vec<f64>,
    /// Descriptors, base set and profile (the paper's).
    paper: Option<(Descriptors, Vec<u32>, Vec<f64>)>,
    /// Eigenpairs, mass, heat geodesics and descriptors (the refined method's).
    refine: Option<(
        symcorr_spectral::Eigenpairs,
        Vec<f64>,
        HeatGeodesics,
        Descriptors,
    )>,
}

/// Per-mesh data of the refined method ([`Method::Refined`], DESIGN.md Algorithm 7).
#[derive(Debug, Clone)]
pub struct RefineData {
    /// M-orthonormal Laplace–Beltrami eigenvectors (`n × k`, the same eigenpairs as the si-HKS).
    pub basis: faer::Mat<f64>,
    /// Lumped mass per vertex.
    pub mass: Vec<f64>,
    /// Skeleton landmark coordinates: geodesic distance (heat method) over √area to each
    /// joint's landmark ([`skeleton_landmarks`] — rings and tips — then the nearest surface
    /// vertex of each joint), `n × 40`, columns in joint order.
    pub landmarks: faer::Mat<f64>,
    /// Sagittal halves with each midline plane refined by the surface's symmetry
    /// ([`symmetric_midline_halves`]).
    pub halves: Vec<BodySide>,
    /// The edge graph (geodesic bands around segments).
    pub graph: EdgeGraph,
    /// si-HKS descriptor per vertex (joined to the landmark coordinates).
    pub descriptors: Descriptors,
}

impl RefineData {
    fn new(
        mesh: &TriMesh,
        attachment: &Attachment,
        (eig, mass, heat, descriptors): (
            symcorr_spectral::Eigenpairs,
            Vec<f64>,
            HeatGeodesics,
            Descriptors,
        ),
        timings: &mut Timings,
    ) -> Result<RefineData, PipelineError> {
        let t = Instant::now();
        let edges = mesh.edges();
        let edge = edges
            .iter()
            .map(|[a, b]| {
                nalgebra::distance(
                    &Point3::from(mesh.positions[*a as usize]),
                    &Point3::from(mesh.positions[*b as usize]),
                )
            })
            .sum::<f64>()
            / edges.len().max(1) as f64;
        let mut sources = skeleton_landmarks(
            &mesh.positions,
            &attachment.labels,
            &attachment.joints,
            edge,
        );
        sources.extend(
            symcorr_correspond::joint_landmarks(&mesh.positions, &attachment.joints)
                .into_iter()
                .map(|v| vec![v]),
        );
        let landmarks = landmark_coordinates(&heat, &sources, mesh.total_area())?;
        timings.push(("landmarks".into(), t.elapsed().as_secs_f64()));
        let t = Instant::now();
        let halves = symmetric_midline_halves(mesh, &attachment.labels, &attachment.joints);
        timings.push(("symmetry_planes".into(), t.elapsed().as_secs_f64()));
        Ok(RefineData {
            basis: eig.vectors,
            mass,
            landmarks,
            halves,
            graph: EdgeGraph::new(mesh),
            descriptors,
        })
    }
}

/// Seconds per named stage.
pub(crate) type Timings = Vec<(String, f64)>;

fn spectral_stages(
    mesh: &TriMesh,
    needs: Needs,
    options: &PrepareOptions,
) -> Result<(Spectral, Timings), PipelineError> {
    let mut timings = Vec::new();
    if !needs.spectral() {
        return Ok((
            Spectral {
                curvature: Vec::new(),
                paper: None,
                refine: None,
            },
            timings,
        ));
    }
    let mut clock = Instant::now();
    let mut lap = |name: &str, timings: &mut Timings| {
        timings.push((name.to_string(), clock.elapsed().as_secs_f64()));
        clock = Instant::now();
    };
    let laplacian = Laplacian::new(mesh)?;
    lap("laplacian", &mut timings);
    let k = options
        .eigenpairs
        .min(mesh.num_vertices().saturating_sub(1))
        .max(1);
    let eig = match &options.cache {
        None => {
            let eig = eigenpairs(&laplacian, k, &EigenOptions::default())?;
            lap("eigenpairs", &mut timings);
            eig
        }
        Some(policy) => {
            let (eig, outcome) =
                policy.eigenpairs(mesh, &laplacian, k, &EigenOptions::default())?;
            let name = if outcome.is_hit() {
                "eigenpairs_cached"
            } else {
                "eigenpairs"
            };
            lap(name, &mut timings);
            eig
        }
    };
    // Times relative to the area: t = area·α^τ.
    let desc = si_hks(&eig, &options.si_hks.relative_to_area(mesh.total_area()))?;
    let descriptors = Descriptors::from_mat(desc.as_ref())?;
    lap("si_hks", &mut timings);
    let curvature = gaussian_curvature(mesh);
    lap("curvature", &mut timings);
    let paper = if needs.paper {
        let base_set = base_vertex_set(mesh, &curvature, options.base_radius)?;
        lap("base_set", &mut timings);
        let rows = EdgeGraph::new(mesh).distances_many(&base_set)?;
        let profile = base_profile(&rows, mesh.total_area());
        lap("base_profile", &mut timings);
        Some((descriptors.clone(), base_set, profile))
    } else {
        None
    };
    let refine = if needs.refine {
        let heat = HeatGeodesics::with_laplacian(mesh, &laplacian, 1.0)?;
        lap("heat_factor", &mut timings);
        Some((eig, laplacian.mass.clone(), heat, descriptors))
    } else {
        None
    };
    Ok((
        Spectral {
            curvature,
            paper,
            refine,
        },
        timings,
    ))
}
