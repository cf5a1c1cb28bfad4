//! The pipeline API: per-mesh preparation ([`PreparedMesh`]) and pairwise matching
//! ([`Pipeline::run`]).

use crate::midline::{midline_halves, midline_sagittal, symmetric_midline_halves};
use crate::{OptionError, PipelineError};
use std::time::Instant;
use symcorr_attach::{attach, AttachOptions, Attachment};
use symcorr_correspond::{
    articulated_match, base_profile, coverage, explain_point, farthest_point_sample,
    landmark_coordinates, match_points, outward_normals, refine_dense, skeleton_landmarks,
    ArticulatedInputs, ArticulatedMatches, ArticulatedOptions, Descriptors, FilterStats, Match,
    MatchOptions, Pair, PaperFilter, PaperInputs, PointExplanation, RefineOptions, RefinedInputs,
    SpectralBasis,
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

fn boundary_length(mesh: &TriMesh) -> f64 {
    mesh.boundary_loops()
        .iter()
        .map(|l| {
            (0..l.len())
                .map(|i| {
                    symcorr_mesh::geometry::dist(
                        mesh.positions[l[i] as usize],
                        mesh.positions[l[(i + 1) % l.len()] as usize],
                    )
                })
                .sum::<f64>()
        })
        .sum()
}

/// Sparse (a farthest-point sample of template points) or dense (every template vertex).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Match this many farthest-point samples of the template.
    Sparse {
        /// Number of template points.
        samples: usize,
    },
    /// Match every template vertex.
    Dense,
}

impl Mode {
    /// The default sparse mode (1,000 samples).
    pub const DEFAULT_SPARSE: Mode = Mode::Sparse {
        samples: DEFAULT_SAMPLES,
    };
}

/// Default number of template points in sparse mode.
pub const DEFAULT_SAMPLES: usize = 1000;

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
    /// The input mesh, kept only when the repair changed it (outputs are written in its ids).
    pub input: Option<TriMesh>,
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
        let boundary_length = boundary_length(&mesh);
        Ok(PreparedMesh {
            boundary_length,
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

    /// True when the mesh is a partial view of a body (a single-view scan): its boundary is
    /// longer than [`PARTIAL_BOUNDARY_RATIO`]·√area. A closed body has no boundary; a full-body
    /// scan with a few holes (soles, crown) stays well below; the silhouette of one view alone
    /// is several body heights long.
    pub fn is_partial(&self) -> bool {
        self.boundary_length > PARTIAL_BOUNDARY_RATIO * self.area.sqrt()
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
                symcorr_mesh::geometry::norm(symcorr_mesh::geometry::sub(
                    mesh.positions[*a as usize],
                    mesh.positions[*b as usize],
                ))
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

type Timings = Vec<(String, f64)>;

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

/// Options of a [`Pipeline`].
#[derive(Debug, Clone)]
pub struct PipelineOptions {
    /// Per-mesh stages.
    pub prepare: PrepareOptions,
    /// Candidates and the skeleton filter (switch it off for the ablation).
    pub matching: MatchOptions,
    /// Sparse or dense.
    pub mode: Mode,
    /// The paper's method or the refined one.
    pub method: Method,
    /// Options of the refined method.
    pub refine: RefineOptions,
    /// Options of the articulated method.
    pub articulated: ArticulatedOptions,
}

impl PipelineOptions {
    /// Refuses options out of range and combinations that would silently run something else
    /// than asked: the paper's filter choice (`matching.filter`: its ablation
    /// [`PaperFilter::Off`], or [`PaperFilter::Strict`]) has no meaning for [`Method::Refined`] and [`Method::Articulated`], whose
    /// segment pools are their skeleton constraint. [`Pipeline::run`] calls it; callers that
    /// want to fail before reading any file call it first.
    pub fn check(&self) -> Result<(), OptionError> {
        if matches!(self.mode, Mode::Sparse { samples: 0 }) {
            return Err(OptionError::NoSamples);
        }
        if self.method == Method::Paper {
            if self.matching.candidates.nearest == Some(0) {
                return Err(OptionError::NoCandidates);
            }
            if let Some(t) = self.matching.candidates.threshold {
                if !(t.is_finite() && t >= 1.0) {
                    return Err(OptionError::CandidateThreshold(t));
                }
            }
        }
        let r = self.prepare.base_radius;
        if self.method == Method::Paper && !(r.is_finite() && r > 0.0) {
            return Err(OptionError::BaseRadius(r));
        }
        if self.method != Method::Articulated && self.prepare.eigenpairs < 2 {
            return Err(OptionError::TooFewEigenpairs(self.prepare.eigenpairs));
        }
        if self.method != Method::Paper {
            match self.matching.filter {
                PaperFilter::Off => return Err(OptionError::AblationNeedsPaper),
                f if f != PaperFilter::DEFAULT => return Err(OptionError::PaperFilterNeedsPaper),
                _ => {}
            }
        }
        Ok(())
    }
}

impl Default for PipelineOptions {
    fn default() -> Self {
        PipelineOptions {
            prepare: PrepareOptions::default(),
            matching: MatchOptions::default(),
            mode: Mode::DEFAULT_SPARSE,
            method: Method::Articulated,
            refine: RefineOptions::default(),
            articulated: ArticulatedOptions::default(),
        }
    }
}

/// Which matching method [`Pipeline::run`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Beyond the paper, the default: skeleton-driven articulated alignment
    /// (symcorr-correspond's `articulated_match`): the template, skinned with its bone-heat
    /// weights, is posed onto the target's skeleton and fitted bone by bone (ICP within
    /// segment pools, the head's twist searched), then every template vertex takes the nearest
    /// target vertex of its pool. Whole surfaces and partial views (single-view scans) alike;
    /// on a partial target ([`PreparedMesh::is_partial`]) [`Correspondence::has_counterpart`]
    /// says which template points it shows. Needs no spectral data.
    #[default]
    Articulated,
    /// The paper: si-HKS candidates, skeleton filter, eq. 8 selection.
    Paper,
    /// Beyond the paper (DESIGN.md, Algorithm 7; symcorr-correspond's `refine_dense`): an
    /// initial map by nearest neighbour in skeleton-landmark + si-HKS space within each segment,
    /// refined by segment-constrained ZoomOut. Dense by nature; in sparse mode the sample's
    /// matches are returned. [`Correspondence::coverage`] reports the fraction of target
    /// vertices hit.
    Refined,
}

/// A correspondence between two prepared meshes: one pair per template point (sparse: the
/// sample; dense: every vertex), and what its method knows about it.
#[derive(Debug, Clone)]
pub struct Correspondence {
    /// One pair per template point, in template-point order.
    pub pairs: Vec<Pair>,
    /// Seconds per pair stage (`sampling`, then the method's own: `candidates`,
    /// `skeleton_filter`, `selection` for the paper's; `segment_pools`, `initial_map`, `zoomout`
    /// for the refined one; `segment_pools`, `articulated_icp`, `nonrigid`, `map` for the
    /// articulated one).
    pub timings: Vec<(String, f64)>,
    /// What the method reports beside the pairs.
    pub report: MethodReport,
}

/// What each method knows about its correspondence beyond the pairs.
#[derive(Debug, Clone)]
pub enum MethodReport {
    /// The paper's pipeline.
    Paper {
        /// What the skeleton filter did.
        filter: FilterStats,
        /// Mean candidates per point before the filter.
        mean_candidates: f64,
        /// The selected matches with what eq. 8 knows about each (same order as the pairs).
        matches: Vec<Match>,
    },
    /// The refined method.
    Refined {
        /// Fraction of target vertices hit by the dense map.
        coverage: f64,
    },
    /// The articulated method.
    Articulated {
        /// Fraction of target vertices hit by the matches of template points it shows.
        coverage: f64,
        /// Partial targets only (a single-view scan): per pair, whether the target shows the
        /// template point at all (`false`: no counterpart; the pair is then only the nearest
        /// guess). `None` for a whole surface, where every point has one.
        has_counterpart: Option<Vec<bool>>,
    },
}

impl Correspondence {
    /// The skeleton filter's statistics: the paper's, or all zero for the methods whose
    /// segment pools replace the filter (the `symcorr.correspondence/1` file always carries
    /// the block).
    pub fn filter_stats(&self) -> FilterStats {
        match &self.report {
            MethodReport::Paper { filter, .. } => *filter,
            _ => FilterStats::default(),
        }
    }

    /// Fraction of target vertices hit (articulated and refined methods).
    pub fn coverage(&self) -> Option<f64> {
        match self.report {
            MethodReport::Paper { .. } => None,
            MethodReport::Refined { coverage } | MethodReport::Articulated { coverage, .. } => {
                Some(coverage)
            }
        }
    }

    /// Per pair, whether the target shows the template point (partial targets of the
    /// articulated method; `None` otherwise).
    pub fn has_counterpart(&self) -> Option<&[bool]> {
        match &self.report {
            MethodReport::Articulated {
                has_counterpart: Some(h),
                ..
            } => Some(h),
            _ => None,
        }
    }
}

/// The articulated method: skeleton-driven articulated alignment of the
/// template onto the target (symcorr-correspond's `articulated_match`).
fn articulated(
    template: &PreparedMesh,
    target: &PreparedMesh,
    options: &ArticulatedOptions,
) -> Result<ArticulatedMatches, PipelineError> {
    let graph = match &target.refine {
        Some(r) => std::borrow::Cow::Borrowed(&r.graph),
        None => std::borrow::Cow::Owned(EdgeGraph::new(&target.mesh)),
    };
    let normals = |m: &PreparedMesh| {
        outward_normals(
            &m.mesh.positions,
            m.mesh.vertex_normals(),
            &m.attachment.labels,
            &m.attachment.joints,
        )
    };
    let (tn, qn) = (normals(template), normals(target));
    let boundary = target.mesh.boundary_vertices();
    let neighbors = template.mesh.vertex_neighbors();
    fn side<'a>(
        m: &'a PreparedMesh,
        normals: &'a [[f64; 3]],
        boundary: Option<&'a [bool]>,
        neighbors: Option<&'a [Vec<u32>]>,
    ) -> ArticulatedInputs<'a> {
        ArticulatedInputs {
            boundary,
            neighbors,
            positions: &m.mesh.positions,
            normals,
            labels: &m.attachment.labels,
            joints: &m.attachment.joints,
            area: m.area,
        }
    }
    Ok(articulated_match(
        &side(template, &tn, None, Some(&neighbors)),
        &template.attachment.weights,
        &side(target, &qn, Some(&boundary), None),
        &graph,
        options,
    )?)
}

/// The paper's pipeline, configured once and run on many pairs.
///
/// ```no_run
/// use symcorr::{Pipeline, PipelineOptions};
/// # fn load() -> (symcorr_mesh::TriMesh, symcorr_attach::Skeleton) { unimplemented!() }
/// let (mesh_a, joints_a) = load();
/// let (mesh_b, joints_b) = load();
/// let pipeline = Pipeline::new(PipelineOptions::default());
/// let a = pipeline.prepare(mesh_a, &joints_a).unwrap();
/// let b = pipeline.prepare(mesh_b, &joints_b).unwrap();
/// let corr = pipeline.run(&a, &b).unwrap();
/// println!("{} matches", corr.pairs.len());
/// ```
#[derive(Debug, Clone, Default)]
pub struct Pipeline {
    /// The options.
    pub options: PipelineOptions,
}

impl Pipeline {
    /// A pipeline with the given options.
    pub fn new(options: PipelineOptions) -> Pipeline {
        Pipeline { options }
    }

    /// Per-mesh stages ([`PreparedMesh::new`]) for this pipeline's method and options.
    pub fn prepare(
        &self,
        mesh: TriMesh,
        skeleton: &Skeleton,
    ) -> Result<PreparedMesh, PipelineError> {
        PreparedMesh::new(
            mesh,
            skeleton,
            &[self.options.method],
            &self.options.prepare,
        )
    }

    /// The template points this pipeline matches on `template` (sample or all vertices).
    pub fn points(&self, template: &PreparedMesh) -> Vec<u32> {
        match self.options.mode {
            Mode::Dense => (0..template.num_vertices() as u32).collect(),
            Mode::Sparse { samples } => farthest_point_sample(&template.mesh, samples),
        }
    }

    /// One template point (`point`, a vertex of `template.mesh`) through the paper's stages
    /// with this pipeline's candidate rule and filter: the candidates before and after the
    /// filter and the selected one (the paper's Fig. 2; symcorr-correspond's `explain_point`).
    ///
    /// Errors: [`PipelineError::NotPreparedFor`] unless both meshes were prepared for
    /// [`Method::Paper`]; [`PipelineError::Correspond`] for a point out of range.
    pub fn explain(
        &self,
        template: &PreparedMesh,
        target: &PreparedMesh,
        point: u32,
    ) -> Result<PointExplanation, PipelineError> {
        Ok(explain_point(
            &template.paper_side()?,
            &target.paper_side()?,
            point,
            &self.options.matching,
        )?)
    }

    /// Matches `template` onto `target` with this pipeline's method.
    ///
    /// Errors: [`PipelineError::NotPreparedFor`] when a mesh lacks the method's data,
    /// [`PipelineError::Option`] for options [`PipelineOptions::check`] refuses, and the
    /// method's own errors.
    pub fn run(
        &self,
        template: &PreparedMesh,
        target: &PreparedMesh,
    ) -> Result<Correspondence, PipelineError> {
        self.options.check()?;
        let t = Instant::now();
        let points = self.points(template);
        let mut timings = vec![("sampling".to_string(), t.elapsed().as_secs_f64())];
        let (pairs, report, stage_timings) = match self.options.method {
            Method::Articulated => run_articulated(
                template,
                target,
                &self.options.articulated,
                &points,
                self.options.mode,
            )?,
            Method::Refined => run_refined(
                template,
                target,
                &self.options.refine,
                &points,
                self.options.mode,
            )?,
            Method::Paper => run_paper(template, target, &self.options.matching, &points)?,
        };
        timings.extend(stage_timings);
        Ok(Correspondence {
            pairs,
            timings,
            report,
        })
    }
}

type MethodOutput = (Vec<Pair>, MethodReport, Timings);

/// The dense per-vertex values `v` restricted to the sparse sample `points` (dense: all).
fn pick<T: Copy>(mode: Mode, points: &[u32], v: Vec<T>) -> Vec<T> {
    match mode {
        Mode::Dense => v,
        Mode::Sparse { .. } => points.iter().map(|&p| v[p as usize]).collect(),
    }
}

fn stage_timings(t: &[(&'static str, f64)]) -> Timings {
    t.iter().map(|(n, s)| (n.to_string(), *s)).collect()
}

fn run_articulated(
    template: &PreparedMesh,
    target: &PreparedMesh,
    options: &ArticulatedOptions,
    points: &[u32],
    mode: Mode,
) -> Result<MethodOutput, PipelineError> {
    let out = articulated(template, target, options)?;
    // Only a partial view leaves template points without a counterpart; on a whole surface
    // every point has one, however far the fit left it.
    let partial = target.is_partial();
    let shown: Vec<u32> = out
        .pairs
        .iter()
        .zip(&out.has_counterpart)
        .filter(|(_, &h)| h || !partial)
        .map(|(m, _)| m.target)
        .collect();
    let report = MethodReport::Articulated {
        coverage: coverage(&shown, target.num_vertices()),
        has_counterpart: partial.then(|| pick(mode, points, out.has_counterpart)),
    };
    Ok((
        pick(mode, points, out.pairs),
        report,
        stage_timings(&out.timings),
    ))
}

fn run_refined(
    template: &PreparedMesh,
    target: &PreparedMesh,
    options: &RefineOptions,
    points: &[u32],
    mode: Mode,
) -> Result<MethodOutput, PipelineError> {
    fn side(m: &PreparedMesh) -> Result<RefinedInputs<'_>, PipelineError> {
        let r = m
            .refine
            .as_ref()
            .ok_or(PipelineError::NotPreparedFor(Method::Refined))?;
        Ok(RefinedInputs {
            basis: SpectralBasis {
                vectors: r.basis.as_ref(),
                mass: &r.mass,
            },
            landmarks: r.landmarks.as_ref(),
            descriptors: &r.descriptors,
            labels: &m.attachment.labels,
            halves: Some(&r.halves),
            graph: &r.graph,
            area: m.area,
        })
    }
    let out = refine_dense(&side(template)?, &side(target)?, options)?;
    let report = MethodReport::Refined {
        coverage: out.coverage,
    };
    Ok((
        pick(mode, points, out.pairs),
        report,
        stage_timings(&out.timings),
    ))
}

fn run_paper(
    template: &PreparedMesh,
    target: &PreparedMesh,
    options: &MatchOptions,
    points: &[u32],
) -> Result<MethodOutput, PipelineError> {
    let out = match_points(
        &template.paper_side()?,
        &target.paper_side()?,
        points,
        options,
    )?;
    let pairs = out.matches.iter().map(Pair::from).collect();
    let report = MethodReport::Paper {
        filter: out.filter,
        mean_candidates: out.mean_candidates,
        matches: out.matches,
    };
    Ok((pairs, report, stage_timings(&out.timings)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;
    use symcorr_attach::testbody::{capsule_body, t_pose};
    use symcorr_eval::{evaluate, EvalGraph};

    /// The capsule body against a stretched, jittered copy of itself (same connectivity, so
    /// the identity is the truth). The body is left/right symmetric, so the descriptors cannot
    /// tell the sides apart; the skeleton filter must remove the flips the ablation makes.
    #[test]
    fn capsule_body_self_match_has_no_flips_with_the_filter() {
        let sk = t_pose(1.0);
        let (mesh, _) = capsule_body(&sk, 0.035);
        let mirror = mirror_map(&mesh);
        let pipeline = Pipeline::new(PipelineOptions {
            mode: Mode::Sparse { samples: 200 },
            method: Method::Paper,
            ..PipelineOptions::default()
        });
        let p = pipeline.prepare(mesh.clone(), &sk).unwrap();
        let mut seed = 7u64;
        let mut jitter = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.004
        };
        let moved: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .map(|q| {
                [
                    1.05 * q[0] + jitter(),
                    0.97 * q[1] + jitter(),
                    q[2] + jitter(),
                ]
            })
            .collect();
        let target_mesh = TriMesh::new(moved, mesh.triangles.clone()).unwrap();
        let mut tsk = sk.clone();
        for j in tsk.positions.iter_mut() {
            *j = Point3::new(1.05 * j[0], 0.97 * j[1], j[2]);
        }
        let q = pipeline.prepare(target_mesh.clone(), &tsk).unwrap();
        let graph = EvalGraph::new(&target_mesh);
        let corr = pipeline.run(&p, &q).unwrap();
        assert_eq!(corr.pairs.len(), 200);
        let pairs: Vec<(u32, u32)> = corr.pairs.iter().map(|m| (m.template, m.target)).collect();
        let e = evaluate(&graph, q.area, &pairs, |v| v, Some(&mirror));
        let mut off = pipeline.clone();
        off.options.matching.filter = PaperFilter::Off;
        let corr_off = off.run(&p, &q).unwrap();
        let pairs: Vec<(u32, u32)> = corr_off
            .pairs
            .iter()
            .map(|m| (m.template, m.target))
            .collect();
        let e_off = evaluate(&graph, q.area, &pairs, |v| v, Some(&mirror));
        eprintln!(
            "n = {}, filter: mean {:.4} flips {:?}; ablation: mean {:.4} flips {:?}; timings {:?}",
            mesh.num_vertices(),
            e.mean_error(),
            e.flip_rate(),
            e_off.mean_error(),
            e_off.flip_rate(),
            p.timings
        );
        assert!(
            e_off.flip_rate().unwrap() > 0.05,
            "the ablation should flip"
        );
        assert!(e.flip_rate().unwrap() < 0.01);
        assert!(e.mean_error() < e_off.mean_error());
    }

    /// A template with a stray vertex in front (every id shifted by one) and a degenerate
    /// triangle: the stages run on the repaired mesh, and the correspondence file speaks the
    /// input's ids.
    #[test]
    fn repaired_input_ids_reach_the_correspondence_file() {
        let sk = t_pose(1.0);
        let (mesh, _) = capsule_body(&sk, 0.035);
        let n = mesh.num_vertices();
        let mut positions = vec![[5.0, 5.0, 5.0]];
        positions.extend_from_slice(&mesh.positions);
        let mut triangles: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .map(|t| [t[0] + 1, t[1] + 1, t[2] + 1])
            .collect();
        triangles.push([1, 1, 2]);
        let broken = TriMesh::new(positions, triangles).unwrap();
        let pipeline = Pipeline::new(PipelineOptions {
            mode: Mode::Sparse { samples: 100 },
            ..PipelineOptions::default()
        });
        let a = pipeline.prepare(broken, &sk).unwrap();
        assert_eq!(a.num_vertices(), n);
        assert_eq!(a.repair.removed_vertices, 1);
        assert_eq!(a.repair.removed_degenerate_triangles, 1);
        assert_eq!(a.input_mesh().num_vertices(), n + 1);
        assert_eq!(a.input_id(0), 1);
        assert_eq!(a.prepared_ids()[0], None);
        assert_eq!(a.prepared_ids()[1], Some(0));
        let b = pipeline.prepare(mesh, &sk).unwrap();
        assert!(b.input.is_none(), "a clean mesh is not copied");
        let corr = pipeline.run(&a, &b).unwrap();
        let doc = serde_json::to_value(crate::output::correspondence_json(
            "a",
            &a,
            "b",
            &b,
            &corr,
            &[],
        ))
        .unwrap();
        assert_eq!(doc["template"]["vertices"], n + 1);
        assert_eq!(doc["target"]["vertices"], n);
        let labels = doc["segments"]["template"].as_array().unwrap();
        assert_eq!(labels.len(), n + 1);
        assert!(labels[0].is_null());
        assert!(labels[1..].iter().all(|l| l.is_u64()));
        // Same surface on both sides: nearly every point matches itself, i.e. input id i of
        // the template onto id i − 1 of the target.
        let pairs = doc["pairs"].as_array().unwrap();
        let own = pairs
            .iter()
            .filter(|p| p[0].as_u64().unwrap() == p[1].as_u64().unwrap() + 1)
            .count();
        assert!(pairs.iter().all(|p| p[0].as_u64().unwrap() >= 1));
        assert!(own * 10 >= pairs.len() * 9, "{own} of {}", pairs.len());
    }

    /// The refined method on the capsule body against a stretched, jittered, vertex-permuted
    /// copy (ids shuffled, so nothing can lean on a shared vertex order): dense, every vertex
    /// matched, small error and no flips, beating the paper's method on the same pair.
    #[test]
    fn refined_method_is_accurate_without_flips_on_a_permuted_target() {
        let sk = t_pose(1.0);
        let (mesh, _) = capsule_body(&sk, 0.035);
        let n = mesh.num_vertices();
        let mirror = mirror_map(&mesh);
        let mut seed = 11u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            seed >> 11
        };
        // perm[old] = new.
        let mut perm: Vec<u32> = (0..n as u32).collect();
        for i in (1..n).rev() {
            perm.swap(i, next() as usize % (i + 1));
        }
        let mut moved = vec![[0.0; 3]; n];
        for (o, q) in mesh.positions.iter().enumerate() {
            let j = (next() as f64 / (1u64 << 53) as f64 - 0.5) * 0.004;
            moved[perm[o] as usize] = [1.05 * q[0] + j, 0.97 * q[1] - j, q[2] + j];
        }
        let tris = mesh
            .triangles
            .iter()
            .map(|t| t.map(|v| perm[v as usize]))
            .collect();
        let target_mesh = TriMesh::new(moved, tris).unwrap();
        let mut tsk = sk.clone();
        for j in tsk.positions.iter_mut() {
            *j = Point3::new(1.05 * j[0], 0.97 * j[1], j[2]);
        }
        // Mirror map in the target's ids.
        let mut inv = vec![0u32; n];
        for (o, &p) in perm.iter().enumerate() {
            inv[p as usize] = o as u32;
        }
        let tmirror: Vec<u32> = (0..n)
            .map(|v| perm[mirror[inv[v] as usize] as usize])
            .collect();
        let refined = Pipeline::new(PipelineOptions {
            mode: Mode::Dense,
            method: Method::Refined,
            ..PipelineOptions::default()
        });
        // Both methods' data, so that the paper's method can run on the same meshes.
        let both = [Method::Refined, Method::Paper];
        let opts = PrepareOptions::default();
        let a = PreparedMesh::new(mesh.clone(), &sk, &both, &opts).unwrap();
        let b = PreparedMesh::new(target_mesh.clone(), &tsk, &both, &opts).unwrap();
        // The refined pipeline's own preparation skips the paper's data.
        let lean = refined.prepare(mesh.clone(), &sk).unwrap();
        assert!(lean.refine.is_some() && lean.paper.is_none());
        assert!(paper_rejects(&lean));
        assert!(a.refine.is_some() && b.refine.is_some());
        let graph = EvalGraph::new(&target_mesh);
        let corr = refined.run(&a, &b).unwrap();
        assert_eq!(corr.pairs.len(), n);
        assert!(corr.pairs.iter().all(|m| m.confidence > 0.0));
        let pairs: Vec<(u32, u32)> = corr.pairs.iter().map(|m| (m.template, m.target)).collect();
        let e = evaluate(&graph, b.area, &pairs, |v| perm[v as usize], Some(&tmirror));
        // The paper's method, dense, on the same prepared meshes.
        let mut paper = refined.clone();
        paper.options.method = Method::Paper;
        let cp = paper.run(&a, &b).unwrap();
        let pp: Vec<(u32, u32)> = cp.pairs.iter().map(|m| (m.template, m.target)).collect();
        let ep = evaluate(&graph, b.area, &pp, |v| perm[v as usize], Some(&tmirror));
        eprintln!(
            "n = {n}: refined mean {:.4} flips {:?} coverage {:?}; paper mean {:.4} flips {:?}",
            e.mean_error(),
            e.flip_rate(),
            corr.coverage(),
            ep.mean_error(),
            ep.flip_rate()
        );
        assert_eq!(e.flip_counts().1, 0, "no flips");
        assert!(e.mean_error() < 0.03, "mean error {}", e.mean_error());
        assert!(e.mean_error() < ep.mean_error());
        assert!(corr.coverage().unwrap() > 0.3);
    }

    fn paper_rejects(m: &PreparedMesh) -> bool {
        Pipeline::new(PipelineOptions {
            method: Method::Paper,
            ..PipelineOptions::default()
        })
        .run(m, m)
        .is_err()
    }

    /// The ablation switch belongs to the paper's method; with the articulated (default) and
    /// refined methods it is an error, not a silently different run.
    #[test]
    fn refined_method_refuses_the_filter_ablation() {
        let mut o = PipelineOptions::default();
        assert_eq!(o.method, Method::Articulated);
        for method in [Method::Articulated, Method::Refined] {
            o.method = method;
            o.matching.filter = PaperFilter::DEFAULT;
            assert!(o.check().is_ok());
            o.matching.filter = PaperFilter::Strict;
            assert_eq!(o.check(), Err(OptionError::PaperFilterNeedsPaper));
            o.matching.filter = PaperFilter::Off;
            assert_eq!(o.check(), Err(OptionError::AblationNeedsPaper));
        }
        o.method = Method::Paper;
        assert!(o.check().is_ok());
    }

    /// Mirror map of a mesh symmetric under x ↦ −x: nearest vertex of the reflected position.
    fn mirror_map(mesh: &TriMesh) -> Vec<u32> {
        let p = &mesh.positions;
        (0..p.len())
            .map(|v| {
                let q = [-p[v][0], p[v][1], p[v][2]];
                (0..p.len())
                    .min_by(|&a, &b| {
                        let d = |i: usize| {
                            (p[i][0] - q[0]).powi(2)
                                + (p[i][1] - q[1]).powi(2)
                                + (p[i][2] - q[2]).powi(2)
                        };
                        d(a).total_cmp(&d(b))
                    })
                    .unwrap() as u32
            })
            .collect()
    }
}
