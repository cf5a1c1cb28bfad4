//! The pipeline API: the methods and their options ([`PipelineOptions`], [`Method`]) and
//! pairwise matching ([`Pipeline::run`]) of meshes prepared by [`crate::PreparedMesh`].

use crate::prepare::Timings;
use crate::prepare::{PrepareOptions, PreparedMesh};
use crate::{OptionError, PipelineError};
use nalgebra::Point3;
use std::time::Instant;
use symcorr_correspond::{
    articulated_match, articulated_match_indexed, coverage, explain_point, farthest_point_sample,
    match_points, outward_normals, refine_dense, ArticulatedIndex, ArticulatedInputs,
    ArticulatedMatches, ArticulatedOptions, ArticulatedStart, BoneTransforms, FilterStats, Match,
    MatchOptions, Pair, PaperFilter, PointExplanation, RefineOptions, RefinedInputs, SpectralBasis,
    ViewHold,
};
use symcorr_mesh::geometry::closest_on_triangle;
use symcorr_mesh::TriMesh;
use symcorr_skeleton::Skeleton;
use symcorr_spectral::EdgeGraph;

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
    /// for the refined one; `segment_pools`, `pool_trees` (unless the target's tables brought
    /// its index, [`ArticulatedTables::target_against`]), `articulated_icp`, `nonrigid`, `map`
    /// for the articulated one).
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
        /// A target seen from a viewpoint: how many template points the final pose shows to
        /// it, and how many of them found a counterpart ([`ArticulatedMatches::view_hold`]).
        view_hold: Option<ViewHold>,
        /// The template posed onto the target (final skinning plus the non-rigid step), per
        /// template vertex of its prepared mesh, in the target's frame and unit.
        posed: Vec<[f64; 3]>,
        /// The final bone transforms (template frame → target frame); a next frame of a
        /// recording starts from them ([`Pipeline::run_from`]). Boxed: one transform per bone
        /// is large next to the other variants.
        transforms: Box<BoneTransforms>,
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

    /// Per pair, the point of the target's surface that its template point reaches: the
    /// point nearest the posed template point (the articulated method's final fit) on the
    /// triangles around the matched vertex ([`closest_on_triangle`]). The matched vertex is
    /// the nearest *vertex* in the method's feature space; the surface point removes the
    /// target's sampling from the answer (a scan's pixel spacing, a coarse mesh's edges).
    /// `None` for the methods that pose no template (paper, refined), and when `target` is
    /// not the mesh the correspondence was computed onto (a pair names no vertex of it).
    ///
    /// ```
    /// use symcorr::{Mode, Pipeline, PipelineOptions};
    /// let (mesh, joints) = symcorr_attach::doc_example();
    /// let pipeline = Pipeline::new(PipelineOptions { mode: Mode::Dense, ..Default::default() });
    /// let template = pipeline.prepare(mesh.clone(), &joints).unwrap();
    /// let target = pipeline.prepare(mesh, &joints).unwrap();
    /// let corr = pipeline.run(&template, &target).unwrap(); // the articulated method
    /// let points = corr.surface_points(&target).unwrap();
    /// assert_eq!(points.len(), corr.pairs.len());
    /// // Each surface point lies on a triangle around its matched vertex.
    /// for (p, m) in points.iter().zip(&corr.pairs) {
    ///     assert!(p.corners.contains(&m.target));
    ///     assert!((p.weights.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    /// }
    /// ```
    pub fn surface_points(&self, target: &PreparedMesh) -> Option<Vec<SurfacePoint>> {
        let MethodReport::Articulated { posed, .. } = &self.report else {
            return None;
        };
        let mesh = &target.mesh;
        if self
            .pairs
            .iter()
            .any(|m| m.target as usize >= mesh.num_vertices())
        {
            return None;
        }
        let around = mesh.vertex_triangles();
        let at = |v: u32| Point3::from(mesh.positions[v as usize]);
        Some(
            self.pairs
                .iter()
                .map(|m| {
                    let p = posed
                        .get(m.template as usize)
                        .map_or_else(|| at(m.target), |x| Point3::from(*x));
                    let mut best = SurfacePoint::vertex(m.target);
                    let mut best_d = nalgebra::distance(&p, &at(m.target));
                    for &t in around.get(m.target as usize).into_iter().flatten() {
                        let corners = mesh.triangles[t as usize];
                        let [a, b, c] = corners.map(at);
                        let (weights, d) = closest_on_triangle(&p, &a, &b, &c);
                        if d < best_d {
                            (best, best_d) = (SurfacePoint { corners, weights }, d);
                        }
                    }
                    best
                })
                .collect(),
        )
    }

    /// A target seen from a viewpoint, the articulated method: the fraction of the template
    /// points its fit shows to the viewpoint that found a counterpart
    /// ([`ArticulatedMatches::view_held`]); `None` otherwise.
    pub fn view_held(&self) -> Option<f64> {
        self.view_hold().map(|h| h.fraction())
    }

    /// [`Correspondence::view_held`] as counts: the template points the fit shows the
    /// viewpoint and those of them with a counterpart ([`ArticulatedMatches::view_hold`]).
    pub fn view_hold(&self) -> Option<ViewHold> {
        match self.report {
            MethodReport::Articulated { view_hold, .. } => view_hold,
            _ => None,
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

/// A point on a mesh's surface: a triangle's corners (vertex ids of the prepared mesh) and
/// barycentric weights (non-negative, summing to 1). A vertex is the corner with weight 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// The triangle's corners.
    pub corners: [u32; 3],
    /// The weight of each corner.
    pub weights: [f64; 3],
}

impl SurfacePoint {
    /// The vertex `v` itself.
    pub fn vertex(v: u32) -> SurfacePoint {
        SurfacePoint {
            corners: [v; 3],
            weights: [1.0, 0.0, 0.0],
        }
    }
}

/// The tables of one mesh that the articulated method derives from it alone, per frame of a
/// recording no matter how many frames: its outward normals, and as a template its edge graph
/// (the non-rigid step) and vertex areas (what a fit lays on a view, [`ViewHold`]), as a
/// target its edge graph for the pools' band (its boundary flags are the prepared mesh's,
/// [`PreparedMesh::boundary_vertices`]).
/// Built once for a template and, for a recording's frame, on the thread that observes it
/// ([`Pipeline::run_with`]); [`Pipeline::run_from`] builds both for each call.
#[derive(Debug, Clone)]
pub struct ArticulatedTables {
    normals: Vec<[f64; 3]>,
    /// As a template: the vertex neighbours.
    neighbors: Option<Vec<Vec<u32>>>,
    /// As a template: the barycentric vertex areas ([`TriMesh::vertex_areas`]).
    vertex_areas: Option<Vec<f64>>,
    /// As a target: the edge graph unless the mesh was prepared for the refined method (which
    /// holds one).
    graph: Option<EdgeGraph>,
    /// As a target: its search index against one template ([`ArticulatedTables::target_against`]).
    index: Option<ArticulatedIndex>,
}

impl ArticulatedTables {
    /// The tables of `m` as the template of the articulated method.
    pub fn template(m: &PreparedMesh) -> ArticulatedTables {
        ArticulatedTables {
            normals: articulated_normals(m),
            neighbors: Some(m.mesh.vertex_neighbors()),
            vertex_areas: Some(m.mesh.vertex_areas()),
            graph: None,
            index: None,
        }
    }

    /// The tables of `m` as the target of the articulated method.
    pub fn target(m: &PreparedMesh) -> ArticulatedTables {
        ArticulatedTables {
            normals: articulated_normals(m),
            neighbors: None,
            vertex_areas: None,
            graph: m.refine.is_none().then(|| EdgeGraph::new(&m.mesh)),
            index: None,
        }
    }

    /// [`ArticulatedTables::target`] with the target's search index against `template` (its
    /// tables from [`ArticulatedTables::template`]) for `options` built as well
    /// ([`ArticulatedIndex`]: the segment pools and their k-d trees) — a recording's frame's on
    /// the thread that observed it, so that the thread that matches need not. Matching these
    /// tables against another template or with other options is refused
    /// ([`PipelineError::Correspond`] with [`symcorr_correspond::CorrespondError::IndexMismatch`]).
    ///
    /// Errors: those of [`ArticulatedIndex::new`].
    pub fn target_against(
        template: (&PreparedMesh, &ArticulatedTables),
        target: &PreparedMesh,
        options: &ArticulatedOptions,
    ) -> Result<ArticulatedTables, PipelineError> {
        let mut tables = ArticulatedTables::target(target);
        let index = with_sides(template, (target, &tables), |t, q, graph| {
            ArticulatedIndex::new(t, q, graph, options)
        })?;
        tables.index = Some(index);
        Ok(tables)
    }

    /// Seconds per stage of building [`ArticulatedTables::target_against`]'s index (empty
    /// without one).
    pub fn index_timings(&self) -> &[(&'static str, f64)] {
        self.index.as_ref().map_or(&[], |i| i.timings())
    }
}

/// A mesh's vertex normals turned out of the body ([`outward_normals`]).
fn articulated_normals(m: &PreparedMesh) -> Vec<[f64; 3]> {
    outward_normals(
        &m.mesh.positions,
        m.mesh.vertex_normals(),
        &m.attachment.labels,
        &m.attachment.joints,
    )
}

/// The articulated method: skeleton-driven articulated alignment of the
/// template onto the target (symcorr-correspond's `articulated_match`, or
/// `articulated_match_indexed` when the target's tables hold its index), with the tables of
/// both ([`ArticulatedTables::template`], [`ArticulatedTables::target`] or
/// [`ArticulatedTables::target_against`]).
fn articulated(
    template: (&PreparedMesh, &ArticulatedTables),
    target: (&PreparedMesh, &ArticulatedTables),
    options: &ArticulatedOptions,
    start: ArticulatedStart<'_>,
) -> Result<ArticulatedMatches, PipelineError> {
    let index = target.1.index.as_ref();
    let weights = &template.0.attachment.weights;
    Ok(with_sides(template, target, |t, q, graph| match index {
        Some(index) => articulated_match_indexed(t, weights, q, index, options, start),
        None => articulated_match(t, weights, q, graph, options, start),
    })?)
}

/// Calls `f` with the articulated method's view of both meshes (the template in the target's
/// unit) and the target's edge graph, each table taken from the meshes' [`ArticulatedTables`]
/// or built here when they lack it.
fn with_sides<R>(
    (template, tt): (&PreparedMesh, &ArticulatedTables),
    (target, qt): (&PreparedMesh, &ArticulatedTables),
    f: impl FnOnce(&ArticulatedInputs<'_>, &ArticulatedInputs<'_>, &EdgeGraph) -> R,
) -> R {
    let built;
    let graph = match (&target.refine, &qt.graph) {
        (Some(r), _) => &r.graph,
        (None, Some(g)) => g,
        (None, None) => {
            built = EdgeGraph::new(&target.mesh);
            &built
        }
    };
    let built_neighbors;
    let neighbors = match &tt.neighbors {
        Some(nb) => nb,
        None => {
            built_neighbors = template.mesh.vertex_neighbors();
            &built_neighbors
        }
    };
    let (tn, qn) = (&tt.normals, &qt.normals);
    // Each mesh's unit comes from its own skeleton: a template in metres matched onto a scan
    // in millimetres works in the target's unit.
    let ratio = template.metres_per_unit() / target.metres_per_unit();
    let scaled = (ratio != 1.0).then(|| {
        let positions: Vec<[f64; 3]> = template
            .mesh
            .positions
            .iter()
            .map(|p| p.map(|x| x * ratio))
            .collect();
        let mut joints = template.attachment.joints.clone();
        for p in joints.positions.iter_mut() {
            *p *= ratio;
        }
        (positions, joints)
    });
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
            triangles: Some(&m.mesh.triangles),
            viewpoint: m.view_point(),
        }
    }
    let mut template_side = side(template, tn, None, Some(neighbors));
    if let Some((positions, joints)) = &scaled {
        template_side.positions = positions;
        template_side.joints = joints;
        template_side.area = template.area * ratio * ratio;
    }
    f(
        &template_side,
        &side(target, qn, Some(&target.boundary_vertices), None),
        graph,
    )
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
        self.run_from(template, target, ArticulatedStart::Skeletons)
    }

    /// [`Pipeline::run`], the articulated method starting from `start` — a recording's next
    /// frame from the previous frame's fit ([`ArticulatedStart::Warm`]: that correspondence's
    /// [`MethodReport::Articulated`] `transforms` and that target's refined joints). The other
    /// methods have no start and ignore it.
    pub fn run_from(
        &self,
        template: &PreparedMesh,
        target: &PreparedMesh,
        start: ArticulatedStart<'_>,
    ) -> Result<Correspondence, PipelineError> {
        self.run_with(template, target, start, None)
    }

    /// [`Pipeline::run_from`] with the articulated method's tables of both meshes built
    /// beforehand (`tables`: the template's from [`ArticulatedTables::template`], the
    /// target's from [`ArticulatedTables::target`], each of that mesh; `None`: built here) —
    /// a recording's template once for every frame, a frame's on the thread that observed it.
    /// The result is the same. The other methods ignore `tables`.
    pub fn run_with(
        &self,
        template: &PreparedMesh,
        target: &PreparedMesh,
        start: ArticulatedStart<'_>,
        tables: Option<(&ArticulatedTables, &ArticulatedTables)>,
    ) -> Result<Correspondence, PipelineError> {
        self.options.check()?;
        let t = Instant::now();
        let points = self.points(template);
        let mut timings = vec![("sampling".to_string(), t.elapsed().as_secs_f64())];
        let (pairs, report, stage_timings) = match self.options.method {
            Method::Articulated => {
                let built;
                let (tt, qt) = match tables {
                    Some(t) => t,
                    None => {
                        built = (
                            ArticulatedTables::template(template),
                            ArticulatedTables::target(target),
                        );
                        (&built.0, &built.1)
                    }
                };
                run_articulated(
                    (template, tt),
                    (target, qt),
                    &self.options.articulated,
                    &points,
                    self.options.mode,
                    start,
                )?
            }
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

/// A fit on one view ([`Correspondence::view_held`]) that holds less than this fraction of the
/// template points it shows the camera may stand on a skeleton turned away from the camera
/// (the template then shows the scan its back): [`Pipeline::run_on_view`] and `symcorr track`
/// fit it again with the joints turned half a turn about their spine and keep the turned fit
/// when it holds [`TURN_KEEP_MARGIN`] more. Measured 2026-12-03: good fits hold 0.66–0.99
/// (bodies20_kinect, its tracker-joint and profile sets; 0.70–0.92 and 0.83–0.99 on two
/// synthetic recordings), fits on a skeleton turned away from the camera 0.27–0.70 on recordings
/// (docs/decisions/2026-12-03-track-turned-skeletons.md) and 0.23–0.80 on single scans, where
/// a higher threshold also turned correct fits into flipped ones
/// (docs/decisions/2026-12-04-turned-skeletons-in-match.md). Below the threshold a good fit
/// only costs the second fit, which holds less and is dropped.
pub const TURN_RETRY_BELOW: f64 = 0.75;

/// How much more of its view ([`Correspondence::view_held`]) the fit on the joints turned half a
/// turn must hold than the fit on the joints as given for [`Pipeline::run_on_view`] and
/// `symcorr track` to keep it ([`keeps_turned_fit`]). A turned fit that holds only a little
/// more is no evidence that the given joints faced away: a nearly symmetric body (arms down)
/// seen from behind lies on a scan almost as well as seen from the front. Measured 2026-12-04
/// (`view_turn_eval`, the kinect scan sets with joints as given and turned 180°): every turned
/// fit that mended a flipped one held 0.17–0.57 more (0.23 with tracker joints); a turned fit
/// that was itself mirrored held less. (docs/decisions/2026-12-04-turned-fit-margin.md.)
pub const TURN_KEEP_MARGIN: f64 = 0.1;

/// How many times as much template surface ([`ViewHold::held_area`]) the fit on the joints
/// turned half a turn must lay on the scan as the fit on the joints as given for
/// [`keeps_turned_fit`] to keep it, whatever share of its view each holds. On a coarse or noisy
/// scan every fit holds a small share of its view, the right one as well, and the shares of the
/// two fits differ by less than [`TURN_KEEP_MARGIN`] or even the wrong way; the right fit still
/// lays more of the template on the scan than the one with its back to it (1.10–1.79 times,
/// measured on a recording with its log turned about the vertical). Surface, not points: a
/// template's face is meshed far more finely than its back, and on a body that turns its back
/// to the camera, its log right, the fit turned to show the face laid 1.38–1.65 times as many
/// points as the right fit but 0.63–0.78 times its surface
/// (docs/decisions/2026-12-04-turned-fit-area.md).
pub const TURN_KEEP_AREA_RATIO: f64 = 1.1;

/// Is the fit on the joints turned half a turn about their spine, holding `turned` of its
/// view, kept over the fit on the joints as given, holding `given`? When it holds at least
/// [`TURN_KEEP_MARGIN`] more of its view, or lays [`TURN_KEEP_AREA_RATIO`] times as much
/// template surface on the scan. Without both views (`None`: no viewpoint, nothing in view)
/// there is nothing to compare, and the given fit stays.
///
/// ```
/// use symcorr::{keeps_turned_fit, ViewHold};
/// let hold = |held, shown, held_area, shown_area| {
///     Some(ViewHold { held, shown, held_area, shown_area })
/// };
/// // 0.55 → 0.90 of its view.
/// assert!(keeps_turned_fit(hold(2200, 4000, 0.3, 0.6), hold(3600, 4000, 0.5, 0.6)));
/// // 0.72 → 0.78 and the same surface: no clearer.
/// assert!(!keeps_turned_fit(hold(2880, 4000, 0.4, 0.6), hold(3120, 4000, 0.4, 0.6)));
/// // 0.57 → 0.52 of its view, but 1.5 times the surface.
/// assert!(keeps_turned_fit(hold(2030, 3560, 0.3, 0.5), hold(3600, 6900, 0.45, 0.7)));
/// // 1.5 times the points, 0.78 times the surface: the face turned onto a back.
/// assert!(!keeps_turned_fit(hold(2395, 3392, 0.67, 0.74), hold(3576, 6828, 0.52, 0.73)));
/// assert!(!keeps_turned_fit(hold(2400, 4000, 0.3, 0.6), None));
/// assert!(!keeps_turned_fit(None, hold(3600, 4000, 0.5, 0.6)));
/// ```
pub fn keeps_turned_fit(given: Option<ViewHold>, turned: Option<ViewHold>) -> bool {
    match (given, turned) {
        (Some(g), Some(t)) => {
            t.fraction() >= g.fraction() + TURN_KEEP_MARGIN
                || t.held_area >= TURN_KEEP_AREA_RATIO * g.held_area
        }
        _ => false,
    }
}

/// Which of the two fits on one view — on the joints as given and on them turned half a turn
/// about their spine — says how the body faces the camera ([`turn_verdict`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TurnVerdict {
    /// The fit on the joints as given: it holds clearly more than the turned one
    /// ([`turn_verdict`]), or there is no turned fit to compare.
    Given,
    /// The fit on the joints turned half a turn ([`keeps_turned_fit`]).
    Turned,
    /// Neither fit holds clearly more of its view or lays clearly more surface on the scan:
    /// the scan does not say which way the body faces. A body's back lies on a scan of its
    /// front nearly as well as its front, so keeping either would be a guess, and the wrong
    /// guess maps left onto right over the whole view.
    Undetermined,
}

/// Compares the fit on the joints as given (holding `given` of its view) with the fit on them
/// turned half a turn about their spine (`turned`): [`TurnVerdict::Turned`] by
/// [`keeps_turned_fit`]; [`TurnVerdict::Given`] when the given fit lays
/// [`TURN_KEEP_AREA_RATIO`] times the turned fit's surface on the scan, or holds
/// [`TURN_KEEP_MARGIN`] more of its view and no less surface; else
/// [`TurnVerdict::Undetermined`]. Without a turned fit (or without views to compare) the given
/// fit stands.
///
/// ```
/// use symcorr::{turn_verdict, TurnVerdict, ViewHold};
/// let hold = |held, shown, held_area, shown_area| {
///     Some(ViewHold { held, shown, held_area, shown_area })
/// };
/// // 0.55 → 0.90 of its view: turned.
/// assert_eq!(turn_verdict(hold(2200, 4000, 0.3, 0.6), hold(3600, 4000, 0.5, 0.6)), TurnVerdict::Turned);
/// // 0.75 → 0.36 of its view, two thirds of the surface: as given.
/// assert_eq!(turn_verdict(hold(2990, 4000, 0.67, 0.7), hold(2500, 7000, 0.45, 0.7)), TurnVerdict::Given);
/// // 0.51 and 0.48 of their views, 0.47 and 0.44 of surface: either could be the body's front.
/// assert_eq!(turn_verdict(hold(1538, 3005, 0.47, 0.73), hold(3166, 6530, 0.44, 0.70)), TurnVerdict::Undetermined);
/// // 0.54 against 0.43 of the points, but 0.91 times the surface: the share does not count.
/// assert_eq!(turn_verdict(hold(1610, 3005, 0.466, 0.73), hold(2808, 6530, 0.512, 0.74)), TurnVerdict::Undetermined);
/// assert_eq!(turn_verdict(hold(1538, 3005, 0.47, 0.73), None), TurnVerdict::Given);
/// ```
pub fn turn_verdict(given: Option<ViewHold>, turned: Option<ViewHold>) -> TurnVerdict {
    if keeps_turned_fit(given, turned) {
        return TurnVerdict::Turned;
    }
    let (Some(g), Some(t)) = (given, turned) else {
        return TurnVerdict::Given;
    };
    // The given fit's larger share of its view counts only if it lays no less surface: the
    // shares are of points, and a fit showing the template's finely meshed face holds a smaller
    // share of them than one showing its coarse back (the fixture's log turned about the
    // vertical, frame 4: 0.536 against 0.430 of the points, 0.91 times the surface — the given
    // fit was the mirrored one). Not asked of a turned fit: no turned fit kept on its share
    // against the surface was measured wrong, and two were right.
    let more_share = g.fraction() >= t.fraction() + TURN_KEEP_MARGIN && g.held_area >= t.held_area;
    if more_share || g.held_area >= TURN_KEEP_AREA_RATIO * t.held_area {
        TurnVerdict::Given
    } else {
        TurnVerdict::Undetermined
    }
}

/// A fit on one view whose kept fit holds less than this fraction of its view
/// ([`Correspondence::view_held`]) is refused ([`PipelineError::ViewNotHeld`]), never returned
/// as a match: the template does not lie on the scan
/// (docs/decisions/2026-12-03-track-turned-skeletons.md).
pub const MIN_VIEW_HELD: f64 = 0.5;

/// What [`Pipeline::run_on_view`] kept.
#[derive(Debug, Clone)]
pub struct ViewMatch {
    /// The correspondence, onto [`ViewMatch::turned_target`] when that is set, else onto the
    /// target as given (the vertex ids are the same: only the skeleton differs).
    pub correspondence: Correspondence,
    /// `Some`: the fit on the given joints held too little of its view, and the target was
    /// prepared anew on its joints turned half a turn about their spine
    /// ([`Skeleton::turned_about_spine`](symcorr_attach::Skeleton::turned_about_spine)), whose
    /// fit held more.
    pub turned_target: Option<PreparedMesh>,
}

impl ViewMatch {
    /// The target the correspondence refers to: the turned one, or `given`.
    pub fn target<'a>(&'a self, given: &'a PreparedMesh) -> &'a PreparedMesh {
        self.turned_target.as_ref().unwrap_or(given)
    }
}

impl Pipeline {
    /// `target` prepared anew ([`Pipeline::prepare`], from its input mesh) on its joints turned
    /// half a turn about their spine
    /// ([`Skeleton::turned_about_spine`](symcorr_attach::Skeleton::turned_about_spine)), seen
    /// from the same viewpoint: the other reading of a skeleton that may face away from the
    /// camera ([`Pipeline::run_on_view`], `symcorr track`). `None` when the skeleton's hip and
    /// shoulder centres coincide or the turned joints cannot be attached.
    pub fn prepare_turned(&self, target: &PreparedMesh) -> Option<PreparedMesh> {
        let joints = target
            .attachment
            .joints
            .turned_about_spine(std::f64::consts::PI)?;
        self.prepare_again(target, &joints, &self.options.prepare)
    }

    /// `target` prepared anew ([`Pipeline::prepare`], from its input mesh) on its joints with
    /// left and right exchanged ([`Skeleton::swap_sides`]), taken as they are: the handedness
    /// check is not asked again ([`symcorr_attach::MirrorPolicy::Ignore`]), the caller having
    /// decided the sides from more than this scan (`symcorr track`: the previous frames'
    /// evidence). Seen from the same viewpoint. `None` when the exchanged joints cannot be
    /// attached.
    pub fn prepare_sides_exchanged(&self, target: &PreparedMesh) -> Option<PreparedMesh> {
        let joints = target.attachment.joints.swap_sides();
        let mut options = self.options.prepare.clone();
        options.attach.mirror = symcorr_attach::MirrorPolicy::Ignore;
        self.prepare_again(target, &joints, &options)
    }

    /// `target`'s input mesh prepared anew for this pipeline's method on `joints` with
    /// `options`, seen from `target`'s viewpoint; `None` when it cannot be prepared.
    fn prepare_again(
        &self,
        target: &PreparedMesh,
        joints: &Skeleton,
        options: &PrepareOptions,
    ) -> Option<PreparedMesh> {
        let prepared = PreparedMesh::new(
            target.input_mesh().clone(),
            joints,
            &[self.options.method],
            options,
        )
        .ok()?;
        Some(match target.viewpoint {
            Some(eye) => prepared.seen_from(eye),
            None => prepared,
        })
    }

    /// [`Pipeline::run`], guarded against a target skeleton that faces away from the camera.
    /// On a target seen from one viewpoint (a depth scan, [`PreparedMesh::view_point`]) a
    /// skeleton turned half a turn about its spine — a log in a frame turned about the
    /// vertical, a tracker that took a back for a front — mirrors its limbs and passes the
    /// attachment's checks on about half of the frontal scans measured; the template posed on
    /// it shows the camera its back, which the scan does not hold. A fit that holds less than
    /// [`TURN_RETRY_BELOW`] of its view ([`Correspondence::view_held`]) is fitted again on the
    /// joints turned back, and kept when it holds clearly more ([`turn_verdict`]). A target
    /// that is not one view (or another method) is matched by [`Pipeline::run`] alone.
    ///
    /// After a retry the correspondence's timings end with `view_retry_dropped`: the seconds of
    /// the fit (or the turned preparation and fit) whose result was dropped.
    ///
    /// Errors: those of [`Pipeline::run`]; [`PipelineError::ViewNotHeld`] when the kept fit
    /// holds less than [`MIN_VIEW_HELD`] (the joints belong to another frame, body or camera);
    /// [`PipelineError::FacingUndetermined`] when neither fit holds clearly more
    /// ([`TurnVerdict::Undetermined`]). A turned target that cannot be prepared or matched
    /// leaves the fit on the given joints.
    ///
    /// ```no_run
    /// # let (pipeline, template, scan): (symcorr::Pipeline, symcorr::PreparedMesh, symcorr::PreparedMesh) = unimplemented!();
    /// let matched = pipeline.run_on_view(&template, &scan)?;
    /// if matched.turned_target.is_some() {
    ///     eprintln!("the scan's joints faced away from the camera and were turned back");
    /// }
    /// let target = matched.target(&scan); // the mesh the pairs' target ids refer to
    /// println!("{} of {} template points matched", matched.correspondence.pairs.len(), template.num_vertices());
    /// # let _ = target;
    /// # Ok::<(), symcorr::PipelineError>(())
    /// ```
    pub fn run_on_view(
        &self,
        template: &PreparedMesh,
        target: &PreparedMesh,
    ) -> Result<ViewMatch, PipelineError> {
        let t = Instant::now();
        let mut kept = ViewMatch {
            correspondence: self.run(template, target)?,
            turned_target: None,
        };
        let hold = kept.correspondence.view_hold();
        if hold.is_some_and(|h| h.fraction() < TURN_RETRY_BELOW) {
            let first_fit = t.elapsed().as_secs_f64();
            let t = Instant::now();
            if let Some(turned) = self.prepare_turned(target) {
                if let Ok(corr) = self.run(template, &turned) {
                    match turn_verdict(hold, corr.view_hold()) {
                        TurnVerdict::Turned => {
                            kept = ViewMatch {
                                correspondence: corr,
                                turned_target: Some(turned),
                            }
                        }
                        TurnVerdict::Given => {}
                        TurnVerdict::Undetermined => {
                            return Err(PipelineError::FacingUndetermined {
                                given: kept.correspondence.view_held().unwrap_or(0.0),
                                turned: corr.view_held().unwrap_or(0.0),
                            })
                        }
                    }
                }
            }
            // The work whose result was dropped: the first fit when the turned one is kept
            // (whose preparation the turned target's own timings hold), else the turned
            // preparation and fit.
            let dropped = match kept.turned_target {
                Some(_) => first_fit,
                None => t.elapsed().as_secs_f64(),
            };
            kept.correspondence
                .timings
                .push(("view_retry_dropped".to_string(), dropped));
        }
        match kept.correspondence.view_held() {
            Some(held) if held < MIN_VIEW_HELD => Err(PipelineError::ViewNotHeld { held }),
            _ => Ok(kept),
        }
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
    template: (&PreparedMesh, &ArticulatedTables),
    target: (&PreparedMesh, &ArticulatedTables),
    options: &ArticulatedOptions,
    points: &[u32],
    mode: Mode,
    start: ArticulatedStart<'_>,
) -> Result<MethodOutput, PipelineError> {
    let out = articulated(template, target, options, start)?;
    let view_hold = match &template.1.vertex_areas {
        Some(areas) => out.view_hold(areas),
        None => out.view_hold(&template.0.mesh.vertex_areas()),
    };
    let target = target.0;
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
        view_hold,
        has_counterpart: partial.then(|| pick(mode, points, out.has_counterpart)),
        posed: out.posed.iter().map(|p| p.coords.into()).collect(),
        transforms: Box::new(out.transforms),
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
    use crate::prepare::*;
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
                let q = Point3::from(p[v]);
                let q = Point3::new(-q.x, q.y, q.z);
                (0..p.len())
                    .min_by(|&a, &b| {
                        let d = |i: usize| nalgebra::distance_squared(&Point3::from(p[i]), &q);
                        d(a).total_cmp(&d(b))
                    })
                    .unwrap() as u32
            })
            .collect()
    }
}
