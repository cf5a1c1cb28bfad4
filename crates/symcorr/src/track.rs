//! Recorded sessions frame by frame ([`Tracker`]): each depth frame of a recording is matched
//! with one prepared template, with the skeleton tracker's log read at the frame's time.
//!
//! Per frame (DESIGN.md, Algorithms, Recorded sessions):
//! 1. **Joints at the frame's time** ([`symcorr_kinect::JointTrack::at`], shifted by
//!    [`TrackOptions::joint_offset_s`]): interpolated between the two nearest log frames; a frame
//!    with no log frame within 1.5 log periods, or whose skeleton has no tracked joint, is
//!    skipped with that reason — never matched to garbage.
//! 2. **Left/right swaps** the tracker makes when the body turns sideways: each limb pair (legs,
//!    arms) is compared with the previous frame's skeleton; if it fits better with left and
//!    right exchanged ([`symcorr_kinect::limb_swap_evidence`] above
//!    [`symcorr_kinect::recording::SWAP_EVIDENCE_THRESHOLD`]) it is swapped back, and the frame says so. The
//!    attachment's handedness check against the scan then fixes a whole-body swap.
//!    Joints the tracker lost in this frame (confidence 0) but tracked in the previous one are
//!    borrowed from it, moved with the joints it did track (a torso joint dropped for a frame
//!    would otherwise leave a skeleton the attachment refuses).
//! 3. **Smoothing**: a one-euro filter per joint coordinate ([`symcorr_kinect::SkeletonFilter`],
//!    Casiez et al. 2012: little jitter at rest, little lag in fast motion), reset after a
//!    frame the observer skipped.
//! 4. **Scan** ([`symcorr_kinect::scan_mesh`]) of the depth frame with those joints and
//!    **prepare** it (skeleton attachment; joints and depth share the camera frame, so no
//!    alignment, and a poor fit is recorded, not refused: a profile view's far-side joints lie
//!    behind the only surface the camera sees; the camera at the origin is its viewpoint, for
//!    the occlusion test; bone heat on 1 cm clusters of the scan,
//!    [`TrackOptions::scan_heat_mesh`]), with its search index against the template
//!    ([`ArticulatedTables::target_against`]). The attachment's refinement re-centres each
//!    joint in its limb's cross-section of this one frame; the fit is anchored at the smoothed
//!    joints plus those moves low-passed over time ([`TrackOptions::refinement_smoothing`]):
//!    a circle fitted to one frame's half-ring of a head 3.2 m away moved the head joint by
//!    4–9 cm, each frame another way.
//! 5. **Match** the template onto it with the pipeline's method — **warm-started** from the
//!    previous frame's fit ([`ArticulatedStart::Warm`]: its bone transforms moved by the
//!    joints' motion, what the joints cannot say, a bone's roll and the head's twist, carried
//!    over; fewer ICP rounds, each bone's step over-relaxed,
//!    [`symcorr_correspond::ArticulatedOptions::warm_relaxation`]), and started afresh from the
//!    skeletons after a skipped frame or when a joint jumped more than
//!    [`TrackOptions::max_warm_jump_m`]. The match refuses a pair
//!    whose target point is nearer another part of the posed template
//!    ([`TrackOptions::reciprocal_radius`]: the far cheek of a head posed turned too little
//!    would take the near one), and a warm-started frame drops a match that moved more than
//!    [`TrackOptions::max_match_shift_m`] against its posed vertex since the previous frame
//!    (it slid to another part of the surface).
//!    A fit that holds less than [`crate::TURN_RETRY_BELOW`] of what it shows the camera
//!    ([`crate::Correspondence::view_held`]) may stand on a skeleton facing away from the
//!    camera: the frame is prepared and fitted again with the joints turned half a turn about
//!    their spine, and the turned fit is kept when it holds [`crate::TURN_KEEP_MARGIN`] more
//!    or lays [`crate::TURN_KEEP_AREA_RATIO`] times as much template surface on the scan
//!    ([`crate::keeps_turned_fit`]). When neither fit holds clearly more
//!    ([`crate::TurnVerdict::Undetermined`]) the fit warm-started from the previous frame is
//!    kept (a body does not turn half a turn between frames); without one the frame is
//!    skipped. A kept fit that holds less than [`crate::MIN_VIEW_HELD`] skips the frame —
//!    never matched to garbage. The handedness check's evidence is fused over time
//!    ([`TrackOptions::sides_memory`]): a frame whose kept skeleton has the previous frames'
//!    sides exchanged on less evidence than they carry is prepared again with its sides
//!    exchanged back ([`Pipeline::prepare_sides_exchanged`], [`Correction::SidesContinued`]).
//!
//! Before a run, [`log_check::check_log`] observes a few frames on their own and refuses a
//! joint log that does not belong to the depth frames (another recording or clock, mirrored
//! axes): such a log's skeletons stick out of the body the camera sees, while every frame
//! alone can pass the guards above; a log with no frame near any depth frame's time is
//! refused naming both clocks' time ranges, and one whose joints lie off the body in most
//! sampled frames naming the ratio of the depths when it is another unit.
//!
//! Steps 1–4 ([`Observer`]) follow the joint log and the depth frames only, never a match;
//! step 5 ([`Fitter`]) follows the previous fit. The two can run on two threads, frame k + 1
//! observed while frame k is matched ([`Tracker::parts`]; `symcorr track` does), with the same
//! outcomes as one after the other ([`Tracker::frame`]).
//!
//! The result per frame ([`FrameOutcome`]) is the row of the correspondence — for every
//! template input vertex the scan vertex it matches, or −1 where the frame does not show it —
//! with a confidence, and what was corrected.

pub mod animation;
pub mod log_check;

use crate::{
    turn_verdict, ArticulatedStart, ArticulatedTables, BoneTransforms, Correspondence, Method,
    MethodReport, Pipeline, PipelineError, PreparedMesh, TurnVerdict, MIN_VIEW_HELD,
    TURN_RETRY_BELOW,
};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{channel, sync_channel};
use std::sync::Arc;
use std::time::Instant;
use symcorr_attach::{HeatMesh, PoorFitPolicy};
use symcorr_kinect::recording::SWAP_EVIDENCE_THRESHOLD;
use symcorr_kinect::{
    limb_swap_evidence, scan_mesh_with_rays, DepthFrame, DepthSource, Intrinsics, JointMoveFilter,
    JointTrack, LimbPair, PixelRays, ScanMesh, ScanOptions, SkeletonFilter, SkipReason,
};
use symcorr_skeleton::Skeleton;

/// Options of a [`Tracker`].
#[derive(Debug, Clone)]
pub struct TrackOptions {
    /// Added to every depth frame's time before the joint log is read (the log's clock minus the
    /// depth stream's), seconds.
    pub joint_offset_s: f64,
    /// Swap limbs back when they fit the previous frame better exchanged.
    pub fix_swaps: bool,
    /// Temporal smoothing of the joints (`None`: raw joints).
    pub smoothing: Option<symcorr_kinect::OneEuroFilter>,
    /// Scan meshing options.
    pub scan: ScanOptions,
    /// Start each frame's fit from the previous frame's ([`ArticulatedStart::Warm`]).
    pub warm_start: bool,
    /// A frame whose joints moved farther than this (metres, the largest joint displacement
    /// since the previous frame) starts afresh from the skeletons: the previous fit is no
    /// longer near.
    pub max_warm_jump_m: f64,
    /// The articulated method's reciprocal check
    /// ([`symcorr_correspond::ArticulatedOptions::reciprocal_radius`], √area of the template;
    /// `None`: the pipeline's setting): a template vertex the frame does not show takes the
    /// nearest shown surface, another part of the body, and turns the fit and its match.
    pub reciprocal_radius: Option<f64>,
    /// Temporal check (`None`: off): in a warm-started frame a template vertex whose match moved
    /// farther than this (metres) against the posed template since the previous frame has no
    /// counterpart in this frame. The posed template follows the body's motion, so a match
    /// that moved against it slid to another part of the surface.
    pub max_match_shift_m: Option<f64>,
    /// The mesh each frame's bone heat is solved on ([`HeatMesh`]).
    pub scan_heat_mesh: HeatMesh,
    /// Low-pass of the attachment's joint refinement over time (`None`: each frame's own
    /// refinement): the fit is anchored at the smoothed joints plus the low-passed moves of the
    /// refinement ([`JointMoveFilter`]), reset with the joint smoothing.
    pub refinement_smoothing: Option<JointMoveFilter>,
    /// Memory of the sides evidence over time (`None`: each frame's handedness check decides
    /// alone): each kept frame's facing evidence for its skeleton's sides
    /// ([`symcorr_attach::MirrorCheck::evidence`]) is added to this share of the previous
    /// frames' fused evidence. A frame whose kept skeleton has its left and right where the
    /// previous frame's right and left were keeps that exchange only when its own evidence
    /// outweighs the fused evidence for the previous sides; otherwise its sides are exchanged
    /// back ([`Pipeline::prepare_sides_exchanged`], `sides_continued`). A body does not swap
    /// its sides between two frames, while one frame's feet cue can mislead: at 3.8 m from
    /// a Kinect v1 a frame's noisy feet swapped a correct skeleton, every match mirrored.
    pub sides_memory: Option<SidesMemory>,
}

impl Default for TrackOptions {
    fn default() -> Self {
        TrackOptions {
            joint_offset_s: 0.0,
            fix_swaps: true,
            smoothing: Some(symcorr_kinect::OneEuroFilter::default()),
            scan: ScanOptions::default(),
            warm_start: true,
            max_warm_jump_m: 0.15,
            reciprocal_radius: Some(RECIPROCAL_RADIUS),
            max_match_shift_m: Some(MAX_MATCH_SHIFT_M),
            scan_heat_mesh: SCAN_HEAT_MESH,
            refinement_smoothing: Some(JointMoveFilter::DEFAULT),
            sides_memory: Some(SIDES_MEMORY),
        }
    }
}

/// The share of the fused sides evidence carried over to the next frame
/// ([`TrackOptions::sides_memory`]), in [0, 1): at 1 or more the first frames' evidence would
/// never be outweighed.
///
/// ```
/// use symcorr::track::SidesMemory;
/// assert_eq!(SidesMemory::new(0.5).unwrap().share(), 0.5);
/// assert!(SidesMemory::new(1.0).is_err());
/// assert!(SidesMemory::new(f64::NAN).is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SidesMemory(f64);

impl SidesMemory {
    /// A memory of `share`; [`crate::OptionError::SidesMemory`] unless `share` is in [0, 1).
    pub fn new(share: f64) -> Result<SidesMemory, crate::OptionError> {
        if (0.0..1.0).contains(&share) {
            Ok(SidesMemory(share))
        } else {
            Err(crate::OptionError::SidesMemory(share))
        }
    }

    /// The share carried over.
    pub fn share(self) -> f64 {
        self.0
    }
}

/// Default [`TrackOptions::sides_memory`]: two thirds of the fused evidence carry over to the
/// next frame. A kept frame's evidence for its sides is 1–2 with a clear view of the feet and
/// 0.1–1 with a poor one (the handedness check swaps below −0.45); a steady run then holds
/// twice its frames' evidence for its sides, so a frame exchanges them at once only on more
/// than twice that evidence, and two frames of contrary evidence as strong as the run's
/// exchange them. Measured: docs/decisions/2026-12-06-sides-evidence-over-time.md.
pub const SIDES_MEMORY: SidesMemory = SidesMemory(2.0 / 3.0);

/// Default [`TrackOptions::reciprocal_radius`] (√area of the template).
/// Measured: docs/decisions/2026-12-03-track-flips-and-jumps.md.
pub const RECIPROCAL_RADIUS: f64 = 0.03;

/// Default [`TrackOptions::scan_heat_mesh`]: clusters within 0.6 % of the skeleton's height
/// (about 1 cm; a 640×480 frame's pixels are 5 mm apart at 2.8 m). Measured:
/// docs/decisions/2026-12-04-track-heat-clusters-and-warm-rounds.md.
pub const SCAN_HEAT_MESH: HeatMesh = HeatMesh::Clustered { radius: 0.006 };

/// Default [`TrackOptions::max_match_shift_m`], metres.
/// Measured: docs/decisions/2026-12-03-track-flips-and-jumps.md.
pub const MAX_MATCH_SHIFT_M: f64 = 0.03;

/// Something the tracker corrected in a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Correction {
    /// The joints were interpolated between two log frames.
    JointsInterpolated,
    /// Joints the tracker lost in this frame were borrowed from the previous frame, moved with
    /// the joints it did track.
    JointsBorrowed,
    /// The legs' left and right were swapped back: by continuity with the previous frame, or
    /// because the hips pointed opposite to the shoulders across the spine (the attachment's
    /// handedness check).
    LegsSwapped,
    /// The arms' left and right were swapped back (as the legs', [`Correction::LegsSwapped`]).
    ArmsSwapped,
    /// The whole skeleton's sides were swapped to fit the scan (handedness check).
    SidesSwapped,
    /// The frame's handedness check was overruled by the previous frames' evidence: its
    /// skeleton's sides were exchanged back to continue theirs ([`TrackOptions::sides_memory`]).
    /// With [`Correction::SidesSwapped`] when the sides kept are the log's exchanged.
    SidesContinued,
    /// The skeleton failed a fit check and was used anyway.
    PoorFitAccepted,
    /// The skeleton was turned half a turn about its spine: as logged, it faced away from the
    /// side of the body the scan shows (its fit held less of its view than the turned one's).
    SkeletonTurned,
}

impl Correction {
    /// The correction of a limb pair swapped back: [`Correction::LegsSwapped`] or
    /// [`Correction::ArmsSwapped`].
    pub fn limbs_swapped(pair: LimbPair) -> Correction {
        match pair {
            LimbPair::Legs => Correction::LegsSwapped,
            LimbPair::Arms => Correction::ArmsSwapped,
        }
    }

    /// The name in `track.json`.
    pub fn name(self) -> &'static str {
        match self {
            Correction::JointsInterpolated => "joints_interpolated",
            Correction::JointsBorrowed => "joints_borrowed",
            Correction::LegsSwapped => "legs_swap_fixed",
            Correction::ArmsSwapped => "arms_swap_fixed",
            Correction::SidesSwapped => "sides_swap_fixed",
            Correction::SidesContinued => "sides_continued",
            Correction::PoorFitAccepted => "poor_fit_accepted",
            Correction::SkeletonTurned => "skeleton_turn_fixed",
        }
    }
}

/// A frame that was matched.
#[derive(Debug, Clone)]
pub struct MatchedFrame {
    /// Per template input vertex, the scan vertex it matches, or −1 where the frame does not
    /// show it.
    pub target_of: Vec<i32>,
    /// Per template input vertex, the match's confidence (0 where `target_of` is −1).
    pub confidence: Vec<f32>,
    /// What was corrected.
    pub corrections: Vec<Correction>,
    /// Fraction of the template's vertices the frame shows (matched, not −1).
    pub coverage: f64,
    /// Mean confidence of the matched vertices.
    pub mean_confidence: f64,
    /// The target skeleton's fit score ([`symcorr_attach::FitQuality::score`]).
    pub fit_score: f64,
    /// The fraction of the template points the fit shows to the camera that found a
    /// counterpart ([`crate::Correspondence::view_held`]; `None` for the methods that pose no
    /// template).
    pub view_held: Option<f64>,
    /// The scan, its vertex ids being those of `target_of`.
    pub scan: ScanMesh,
    /// Per template input vertex, the template posed onto this frame (camera space, metres):
    /// the articulated method's final skinning plus its non-rigid step; other methods pose
    /// nothing (`None`).
    pub posed: Option<Vec<[f32; 3]>>,
    /// Whether the fit started from the previous frame's.
    pub warm: bool,
    /// Per scan vertex, its segment label index (`None` where the attachment left it out).
    pub scan_labels: Vec<Option<usize>>,
    /// Seconds per stage: `scan`, `prepare`, `match`, then the sub-stages of the attachment
    /// (`prepare.attach.…`) and of the matching method (`match.…`).
    pub timings: Vec<(String, f64)>,
}

/// What happened to one frame.
#[derive(Debug, Clone)]
pub enum FrameOutcome {
    /// Matched.
    Matched(Box<MatchedFrame>),
    /// Skipped, with the reason (no skeleton near its time, no body, a scan or match that
    /// failed).
    Skipped(String),
}

/// A frame observed and not yet matched ([`Observer::observe`]): the joints used at its time,
/// what was corrected in them, and its scan, prepared.
pub struct Observation {
    /// What the observer corrected in the joints; the attachment's corrections are added from
    /// the prepared scan the fitter keeps.
    corrections: Vec<Correction>,
    scan: ScanMesh,
    target: PreparedMesh,
    /// The articulated method's tables of `target` (`None` for the other methods), built here
    /// rather than on the fitter's thread.
    tables: Option<ArticulatedTables>,
    timings: Vec<(String, f64)>,
}

/// Steps 1–4 of a frame (module docs): the joints at its time, corrected and smoothed, and its
/// scan, prepared. It follows the joint log and the depth frames only — never a match — so it
/// can run one frame ahead of the [`Fitter`], on another thread.
pub struct Observer<'a> {
    pipeline: Pipeline,
    /// The template and its articulated tables: each frame's search index is built against
    /// them here ([`ArticulatedTables::target_against`]), not on the fitter's thread.
    template: (&'a PreparedMesh, Arc<ArticulatedTables>),
    /// The camera's pixel rays, found once (with a lens model, a table).
    rays: PixelRays,
    joints: JointTrack,
    options: TrackOptions,
    filter: Option<SkeletonFilter>,
    /// The low-pass of the refinement's joint moves ([`TrackOptions::refinement_smoothing`]).
    refinement: Option<JointMoveFilter>,
    /// The previous observed frame's joints, as used (corrected and smoothed).
    previous: Option<Skeleton>,
}

/// Step 5 of a frame (module docs): the match against the template, warm-started from the
/// previous frame's fit.
pub struct Fitter<'a> {
    pipeline: Pipeline,
    template: &'a PreparedMesh,
    /// The articulated method's tables of the template, built once.
    template_tables: Arc<ArticulatedTables>,
    options: TrackOptions,
    /// The previous frame's fit: its bone transforms and the refined joints they pose onto.
    previous_fit: Option<(BoneTransforms, Skeleton)>,
    /// The previous frames' fused evidence for the previous fit's sides
    /// ([`TrackOptions::sides_memory`]).
    previous_sides: Option<SidesEvidence>,
    /// Per template input vertex, the previous frame's match minus its posed position (camera
    /// space, metres; `None` where it had no match): the temporal check's reference.
    previous_offsets: Option<Vec<Option<[f64; 3]>>>,
}

/// Matches the frames of one recording, in time order, against one prepared template: an
/// [`Observer`] and a [`Fitter`], one after the other ([`Tracker::frame`]), or apart
/// ([`Tracker::parts`]) so that the next frame is observed while this one is matched.
pub struct Tracker<'a> {
    observer: Observer<'a>,
    fitter: Fitter<'a>,
}

impl<'a> Tracker<'a> {
    /// A tracker for frames seen through `intrinsics`, with the joints of `joints`; `pipeline`
    /// prepared `template` (its method and mode are used for every frame).
    pub fn new(
        pipeline: &Pipeline,
        template: &'a PreparedMesh,
        intrinsics: Intrinsics,
        joints: JointTrack,
        options: TrackOptions,
    ) -> Tracker<'a> {
        let mut pipeline = pipeline.clone();
        // Joints and depth share the camera frame: no alignment search; a profile view's fit is
        // recorded, not refused.
        pipeline.options.prepare.attach.align = false;
        pipeline.options.prepare.attach.poor_fit = PoorFitPolicy::Accept;
        pipeline.options.prepare.cache = None;
        pipeline.options.prepare.attach.heat_mesh = options.scan_heat_mesh;
        // A frame keeps only the matches of the template vertices it shows (`target_of` −1
        // elsewhere): the final map need not guess the others'.
        pipeline.options.articulated.guess_hidden = false;
        if options.reciprocal_radius.is_some() {
            pipeline.options.articulated.reciprocal_radius = options.reciprocal_radius;
        }
        let template_tables = Arc::new(ArticulatedTables::template(template));
        Tracker {
            observer: Observer {
                pipeline: pipeline.clone(),
                template: (template, Arc::clone(&template_tables)),
                rays: intrinsics.pixel_rays(),
                joints,
                filter: options.smoothing.map(SkeletonFilter::new),
                refinement: options.refinement_smoothing.clone(),
                options: options.clone(),
                previous: None,
            },
            fitter: Fitter {
                template_tables,
                pipeline,
                template,
                options,
                previous_fit: None,
                previous_sides: None,
                previous_offsets: None,
            },
        }
    }

    /// Forgets the previous frame (after a skipped frame, or before a jump in time).
    pub fn reset(&mut self) {
        self.observer.reset();
        self.fitter.reset();
    }

    /// Observes and matches the depth frame taken at `time_s` (depth stream clock).
    pub fn frame(&mut self, time_s: f64, depth: &DepthFrame) -> FrameOutcome {
        match self.observer.observe(time_s, depth) {
            Ok(o) => self.fitter.fit(o),
            Err(reason) => {
                self.fitter.reset();
                FrameOutcome::Skipped(reason)
            }
        }
    }

    /// The observer and the fitter, to run apart: observe frame k + 1 while frame k is
    /// matched; give the fitter every observation in order and [`Fitter::reset`] it for every
    /// frame the observer refused. The outcomes are those of [`Tracker::frame`].
    pub fn parts(&mut self) -> (&mut Observer<'a>, &mut Fitter<'a>) {
        (&mut self.observer, &mut self.fitter)
    }

    /// Tracks `frames` (indices into `source`, in the order given) on two threads — this one
    /// reads and observes frame k + 1 while another matches frame k ([`Tracker::parts`]) — and
    /// hands every finished frame to `sink`, on this thread, in the order of `frames`. The
    /// outcomes are those of [`Tracker::frame`] one after the other; a frame the source cannot
    /// read is skipped with the reason and resets the tracker. The threads of the pool `run`
    /// is called from are shared between the two: the observer's parallel work runs on half of
    /// them, the fitter's on the other half while the observer's frames take about as long as
    /// its own, and on all of them while the observer's take less than
    /// [`WIDE_FITTER_BELOW`] of its own (the observer then leaves its half idle; back to half
    /// above [`NARROW_FITTER_ABOVE`]). The outcomes do not depend on the threads.
    ///
    /// `stop` is checked before each frame is read: once it is set no further frame is
    /// read, and the frames in flight (at most two) are finished and handed to `sink`. An error
    /// from `sink` stops the run the same way and is returned once those frames are done (they
    /// are not handed over). Returns the number of frames handed to `sink`.
    ///
    /// ```no_run
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use std::sync::atomic::AtomicBool;
    /// use symcorr::track::{FrameOutcome, TrackOptions, Tracker};
    /// use symcorr_kinect::{DepthSource, JointTrack};
    /// # let (pipeline, template): (symcorr::Pipeline, symcorr::PreparedMesh) = unimplemented!();
    /// let mut source = DepthSource::open("session")?;
    /// let joints = JointTrack::new(symcorr_kinect::read_joints("session/joints.json")?, 0.0)?;
    /// let mut tracker =
    ///     Tracker::new(&pipeline, &template, *source.intrinsics(), joints, TrackOptions::default());
    /// let frames: Vec<usize> = (0..source.len()).collect();
    /// tracker.run(&mut source, &frames, &AtomicBool::new(false), |f| {
    ///     if let FrameOutcome::Matched(m) = &f.outcome {
    ///         println!("frame {}: coverage {:.2}", f.index, m.coverage);
    ///     }
    ///     Ok::<(), std::io::Error>(())
    /// })?;
    /// # Ok(()) }
    /// ```
    pub fn run<E>(
        &mut self,
        source: &mut DepthSource,
        frames: &[usize],
        stop: &AtomicBool,
        mut sink: impl FnMut(TrackedFrame) -> Result<(), E>,
    ) -> Result<usize, E> {
        let (observer, fitter) = self.parts();
        let mut observed_seconds = SmoothedSeconds::default();
        let mut handed = 0;
        let mut failed: Option<E> = None;
        let mut hand = |f: TrackedFrame, failed: &mut Option<E>| {
            if failed.is_none() {
                match sink(f) {
                    Ok(()) => handed += 1,
                    Err(e) => *failed = Some(e),
                }
            }
        };
        // The observer's parallel work runs on a pool of its own: in one shared pool the
        // fitter's parallel sections queued behind the observer's (bone heat, fit checks), and
        // the fitter sets the rate (7.7 → 8.4–8.9 frames/s measured:
        // docs/decisions/2026-12-04-track-throughput-5.md). Each half gets half the threads
        // (docs/decisions/2026-12-06-track-threads-split.md). Without a pool (the system
        // refuses a thread), a half shares the caller's pool.
        let threads = rayon::current_num_threads();
        let observer_pool = rayon::ThreadPoolBuilder::new()
            .num_threads((threads / 2).max(1))
            .thread_name(|i| format!("symcorr-observer-{i}"))
            .build()
            .ok();
        let mut fitter_pools = FitterPools::new(threads);
        // The observer's smoothed seconds per frame (`f64` bits; NaN before its first frame),
        // which the fitter's choice of pool reads.
        let observer_seconds = AtomicU64::new(f64::NAN.to_bits());
        std::thread::scope(|scope| {
            // A frame read and observed (or refused by the observer), on its way to the fitter.
            type Observed = (usize, f64, Instant, Result<Observation, String>);
            let (to_fit, observed) = sync_channel::<Observed>(1);
            let (to_hand, finished) = channel::<TrackedFrame>();
            let observer_seconds = &observer_seconds;
            scope.spawn(move || {
                for (index, time_s, started, observation) in observed {
                    let outcome = match observation {
                        Ok(o) => {
                            let seconds = f64::from_bits(observer_seconds.load(Ordering::Relaxed));
                            let t = Instant::now();
                            let outcome = match fitter_pools.pick(seconds) {
                                Some(pool) => pool.install(|| fitter.fit(o)),
                                None => fitter.fit(o),
                            };
                            fitter_pools.fitted(t.elapsed().as_secs_f64());
                            outcome
                        }
                        Err(reason) => {
                            fitter.reset();
                            FrameOutcome::Skipped(reason)
                        }
                    };
                    let f = TrackedFrame {
                        index,
                        time_s,
                        started,
                        outcome,
                    };
                    if to_hand.send(f).is_err() {
                        break;
                    }
                }
            });
            for &i in frames {
                if stop.load(Ordering::SeqCst) || failed.is_some() {
                    break;
                }
                let time_s = source.time(i).unwrap_or(f64::NAN);
                let started = Instant::now();
                let observation = match source.frame(i) {
                    Ok(depth) => match &observer_pool {
                        Some(pool) => pool.install(|| observer.observe(time_s, &depth)),
                        None => observer.observe(time_s, &depth),
                    },
                    Err(e) => {
                        observer.reset();
                        Err(e.to_string())
                    }
                };
                observed_seconds.add(started.elapsed().as_secs_f64());
                if let Some(s) = observed_seconds.get() {
                    observer_seconds.store(s.to_bits(), Ordering::Relaxed);
                }
                if to_fit.send((i, time_s, started, observation)).is_err() {
                    break;
                }
                while let Ok(f) = finished.try_recv() {
                    hand(f, &mut failed);
                }
            }
            // The frames in flight are finished and handed over, stopped or not.
            drop(to_fit);
            for f in finished {
                hand(f, &mut failed);
            }
        });
        match failed {
            Some(e) => Err(e),
            None => Ok(handed),
        }
    }
}

/// [`Tracker::run`]'s fitter spreads its parallel work over every thread while the observer's
/// frames take less than this share of its own (smoothed over about five frames): the
/// observer then leaves its half of the threads idle most of the time. Measured 2026-12-06
/// on 2 cores (one thread per half against two each, ten recordings): one thread each was
/// faster by 13–19 % where the observer's frames took 0.85–0.98 of the fitter's (640×480 and
/// 640×576 views of a body 2.6 m away), slower by 3–20 % where they took 0.04–0.61 (smaller
/// images, a body 3.8 m away, frames matched twice), either way at 0.70 (3.2 m away);
/// docs/decisions/2026-12-06-track-threads-split.md.
pub const WIDE_FITTER_BELOW: f64 = 0.6;

/// [`Tracker::run`]'s fitter, spread over every thread, goes back to its half once the
/// observer's frames take more than this share of its own. Above [`WIDE_FITTER_BELOW`], so
/// that a ratio near either does not switch every frame.
pub const NARROW_FITTER_ABOVE: f64 = 0.7;

/// Per-frame seconds, smoothed: an exponential average with weight 0.2 on the newest frame.
#[derive(Debug, Clone, Copy, Default)]
struct SmoothedSeconds(Option<f64>);

impl SmoothedSeconds {
    fn add(&mut self, seconds: f64) {
        if seconds.is_finite() {
            self.0 = Some(match self.0 {
                Some(m) => m + 0.2 * (seconds - m),
                None => seconds,
            });
        }
    }

    fn get(self) -> Option<f64> {
        self.0
    }
}

/// Is the fitter's next frame spread over every thread, given whether its last one was and
/// the observer's smoothed seconds per frame over the fitter's ([`WIDE_FITTER_BELOW`],
/// [`NARROW_FITTER_ABOVE`])? Without a ratio (NaN: no frame of either yet) it stays as it is.
fn fitter_spread_wide(wide: bool, observer_over_fitter: f64) -> bool {
    if observer_over_fitter.is_nan() {
        wide
    } else if wide {
        observer_over_fitter <= NARROW_FITTER_ABOVE
    } else {
        observer_over_fitter < WIDE_FITTER_BELOW
    }
}

/// The fitter's thread pools in [`Tracker::run`] and the choice between them, frame by frame.
struct FitterPools {
    /// The threads the observer's pool leaves (at least one).
    half: Option<rayon::ThreadPool>,
    /// Every thread (`None` when that is no more than `half`).
    all: Option<rayon::ThreadPool>,
    /// Whether the last frame ran on `all`. A run starts there: its first frames are fitted
    /// from the skeletons, the fitter's longest.
    wide: bool,
    /// The fitter's smoothed seconds per frame.
    seconds: SmoothedSeconds,
}

impl FitterPools {
    /// The pools for `threads` threads in all.
    fn new(threads: usize) -> FitterPools {
        let pool = |n: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .thread_name(|i| format!("symcorr-fitter-{i}"))
                .build()
                .ok()
        };
        let half = (threads - threads / 2).max(1);
        FitterPools {
            half: pool(half),
            all: (threads > half).then(|| pool(threads)).flatten(),
            wide: true,
            seconds: SmoothedSeconds::default(),
        }
    }

    /// The pool for the next frame, given the observer's smoothed seconds per frame (NaN
    /// before its first); `None`: the caller's pool.
    fn pick(&mut self, observer_seconds: f64) -> Option<&rayon::ThreadPool> {
        let ratio = self
            .seconds
            .get()
            .map_or(f64::NAN, |f| observer_seconds / f);
        self.wide = fitter_spread_wide(self.wide, ratio);
        if self.wide && self.all.is_some() {
            self.all.as_ref()
        } else {
            self.half.as_ref()
        }
    }

    /// Records a frame's fit taking `seconds`.
    fn fitted(&mut self, seconds: f64) {
        self.seconds.add(seconds);
    }
}

/// One frame of [`Tracker::run`]: its index in the recording, its time (depth stream clock,
/// NaN where the source has none), when it was read, and what happened to it.
#[derive(Debug, Clone)]
pub struct TrackedFrame {
    /// Index of the frame in the recording.
    pub index: usize,
    /// Its time, seconds.
    pub time_s: f64,
    /// When its reading began (the frame's wall time is `started.elapsed()` when handed over).
    pub started: Instant,
    /// Matched or skipped.
    pub outcome: FrameOutcome,
}

impl Observer<'_> {
    /// Forgets the previous frame: no continuity check, no smoothing history.
    pub fn reset(&mut self) {
        self.previous = None;
        if let Some(f) = &mut self.filter {
            f.reset();
        }
        if let Some(f) = &mut self.refinement {
            f.reset();
        }
    }

    /// The joints at `time_s` (depth stream clock), corrected and smoothed, and the scan of
    /// `depth` prepared with them. A frame that cannot be observed (no skeleton near its time,
    /// no body in the scan) gives the reason and resets the observer.
    pub fn observe(&mut self, time_s: f64, depth: &DepthFrame) -> Result<Observation, String> {
        let observed = self.observe_inner(time_s, depth);
        if observed.is_err() {
            self.reset();
        }
        observed
    }

    fn observe_inner(&mut self, time_s: f64, depth: &DepthFrame) -> Result<Observation, String> {
        let (corrections, skeleton, scan, t_scan) = self.joints_and_scan(time_s, depth)?;
        let t = Instant::now();
        let template = (self.template.0, &*self.template.1);
        let (mut target, tables) = prepare_scan(&self.pipeline, template, &scan, &skeleton)?;
        // The fit's anchors: the refinement's moves low-passed (its labels and bone heat keep
        // this frame's own refinement).
        if let Some(f) = &mut self.refinement {
            // The moves are measured from the joints as the attachment read them: a limb pair
            // or the whole skeleton it swapped back is swapped here too (else the move is the
            // distance between the two legs, low-passed into the next frames' anchors).
            let given = target.attachment.diagnostics.mirror.apply(&skeleton);
            target.attachment.joints = f.filter(time_s, &given, &target.attachment.joints);
        }
        let t_prepare = t.elapsed().as_secs_f64();
        let d = &target.attachment.diagnostics;
        let mut timings = vec![
            ("scan".to_string(), t_scan),
            ("prepare".to_string(), t_prepare),
        ];
        timings.extend(
            d.timings_s
                .iter()
                .map(|(stage, t)| (format!("prepare.attach.{stage}"), *t)),
        );
        timings.extend(tables.iter().flat_map(|t| {
            t.index_timings()
                .iter()
                .map(|(stage, t)| (format!("prepare.{stage}"), *t))
        }));
        Ok(Observation {
            corrections,
            scan,
            target,
            tables,
            timings,
        })
    }

    /// Steps 1–4 up to the attachment, without the search index: the frame's scan prepared
    /// with the joints at `time_s` ([`Observer::observe`]'s, and like it a frame that cannot
    /// be observed resets the observer). For the joint-log check ([`log_check`]), which asks
    /// only how the joints sit in the scan.
    fn prepared(&mut self, time_s: f64, depth: &DepthFrame) -> Result<PreparedMesh, String> {
        let prepared = self
            .joints_and_scan(time_s, depth)
            .and_then(|(_, skeleton, scan, _)| prepare_view(&self.pipeline, &scan, &skeleton));
        if prepared.is_err() {
            self.reset();
        }
        prepared
    }

    /// Steps 1–3 and the scan (4): the corrections, the joints as used (corrected and
    /// smoothed, and kept as the next frame's reference), the scan and its seconds.
    fn joints_and_scan(
        &mut self,
        time_s: f64,
        depth: &DepthFrame,
    ) -> Result<(Vec<Correction>, Skeleton, ScanMesh, f64), String> {
        let mut corrections = Vec::new();
        let timed = self
            .joints
            .at(time_s + self.options.joint_offset_s)
            .map_err(|e: SkipReason| e.to_string())?;
        if timed.interpolated {
            corrections.push(Correction::JointsInterpolated);
        }
        let mut skeleton = timed.skeleton;
        if let (true, Some(prev)) = (self.options.fix_swaps, &self.previous) {
            for pair in [LimbPair::Legs, LimbPair::Arms] {
                if limb_swap_evidence(prev, &skeleton, pair) > SWAP_EVIDENCE_THRESHOLD {
                    skeleton = skeleton.swap_limbs(pair);
                    corrections.push(Correction::limbs_swapped(pair));
                }
            }
        }
        if let Some(prev) = &self.previous {
            if borrow_lost_joints(prev, &mut skeleton) {
                corrections.push(Correction::JointsBorrowed);
            }
        }
        if let Some(f) = &mut self.filter {
            skeleton = f.filter(time_s, &skeleton);
        }
        let t = Instant::now();
        let scan = scan_mesh_with_rays(depth, &self.rays, Some(&skeleton), &self.options.scan)
            .map_err(|e| e.to_string())?;
        let t_scan = t.elapsed().as_secs_f64();
        // Continuity is judged against what was used, the corrected and smoothed joints.
        self.previous = Some(skeleton.clone());
        Ok((corrections, skeleton, scan, t_scan))
    }
}

impl Fitter<'_> {
    /// Forgets the previous fit: the next frame starts from the skeletons.
    pub fn reset(&mut self) {
        self.previous_fit = None;
        self.previous_sides = None;
        self.previous_offsets = None;
    }

    /// Matches the template onto an observed frame: warm-started from the previous fit unless
    /// there is none or a joint jumped more than [`TrackOptions::max_warm_jump_m`]. A match
    /// that fails skips the frame with its reason and resets the fitter (not the observer:
    /// the joints it follows are still good).
    pub fn fit(&mut self, observation: Observation) -> FrameOutcome {
        match self.fit_inner(observation) {
            Ok(m) => FrameOutcome::Matched(Box::new(m)),
            Err(reason) => {
                self.reset();
                FrameOutcome::Skipped(reason)
            }
        }
    }

    /// The match of `target`, warm-started from the previous fit unless there is none or a
    /// joint jumped more than [`TrackOptions::max_warm_jump_m`]; whether it was warm.
    fn run_match(
        &self,
        target: &PreparedMesh,
        tables: Option<&ArticulatedTables>,
    ) -> Result<(Correspondence, bool), String> {
        let warm = self.previous_fit.as_ref().filter(|(_, joints)| {
            self.options.warm_start
                && largest_joint_motion(joints, &target.attachment.joints)
                    <= self.options.max_warm_jump_m / target.metres_per_unit()
        });
        let start = match warm {
            Some((transforms, joints)) => ArticulatedStart::Warm { transforms, joints },
            None => ArticulatedStart::Skeletons,
        };
        let corr = self
            .pipeline
            .run_with(
                self.template,
                target,
                start,
                tables.map(|t| (&*self.template_tables, t)),
            )
            .map_err(|e: PipelineError| e.to_string())?;
        Ok((corr, warm.is_some()))
    }

    /// The frame's scan prepared anew with its joints turned half a turn about their spine
    /// ([`Pipeline::prepare_turned`]), and its match ([`Fitter::run_match`]): the prepared
    /// scan, the match and whether it was warm.
    fn turned_match(
        &self,
        target: &PreparedMesh,
    ) -> Result<(PreparedMesh, Correspondence, bool), String> {
        let turned = self
            .pipeline
            .prepare_turned(target)
            .ok_or("the turned skeleton does not attach")?;
        let (corr, warm) = self.match_reprepared(&turned)?;
        Ok((turned, corr, warm))
    }

    /// The match of a frame's scan prepared anew in the fitter ([`Fitter::run_match`], with the
    /// search index built here): the match and whether it was warm.
    fn match_reprepared(&self, target: &PreparedMesh) -> Result<(Correspondence, bool), String> {
        let tables = scan_tables(
            &self.pipeline,
            (self.template, &self.template_tables),
            target,
        )?;
        self.run_match(target, tables.as_ref())
    }

    fn fit_inner(&mut self, observation: Observation) -> Result<MatchedFrame, String> {
        let Observation {
            mut corrections,
            scan,
            mut target,
            tables,
            mut timings,
        } = observation;
        let t = Instant::now();
        let (mut corr, mut was_warm) = self.run_match(&target, tables.as_ref())?;
        // A fit that leaves most of what it shows the camera without a counterpart may stand on
        // a skeleton turned away from the camera: the template then shows the scan its back.
        // The joints turned half a turn get their own fit, kept when it clearly holds more of
        // its view or lays clearly more surface on the scan (`turn_verdict`; a turned fit that
        // cannot be made leaves the frame to the first). When neither holds clearly more, the
        // scan cannot tell front from back, but time can: a body does not turn half a turn
        // between two frames, so the fit that continues the previous frame's (warm-started:
        // its joints moved little from those the previous fit posed) is kept. Without such a
        // fit the frame is skipped: a guess would map left onto right over the whole view.
        let mut turned_back = false;
        if corr.view_held().is_some_and(|h| h < TURN_RETRY_BELOW) {
            if let Ok((turned, turned_corr, turned_warm)) = self.turned_match(&target) {
                let verdict = match turn_verdict(corr.view_hold(), turned_corr.view_hold()) {
                    TurnVerdict::Undetermined if was_warm && !turned_warm => TurnVerdict::Given,
                    TurnVerdict::Undetermined if turned_warm && !was_warm => TurnVerdict::Turned,
                    verdict => verdict,
                };
                match verdict {
                    TurnVerdict::Turned => {
                        (target, corr, was_warm) = (turned, turned_corr, turned_warm);
                        turned_back = true;
                    }
                    TurnVerdict::Given => {}
                    TurnVerdict::Undetermined => {
                        return Err(PipelineError::FacingUndetermined {
                            given: corr.view_held().unwrap_or(0.0),
                            turned: turned_corr.view_held().unwrap_or(0.0),
                        }
                        .to_string())
                    }
                }
            }
        }
        // The sides, from this frame's evidence and the previous frames'
        // (`TrackOptions::sides_memory`).
        let own = sides_evidence(&target);
        let memory = match (
            &self.previous_sides,
            &self.previous_fit,
            self.options.sides_memory,
        ) {
            (Some(sides), Some((_, joints)), Some(m)) if sides.turned_back == turned_back => {
                sides_exchanged(joints, &target.attachment.joints)
                    .map(|exchanged| (exchanged, m.share() * sides.fused))
            }
            _ => None,
        };
        let (continued, fused) = match memory {
            // This frame's sides are the previous frames' exchanged, with less evidence for
            // them than the previous frames hold against: exchanged back, its evidence with them.
            Some((true, memory)) if own < memory => (true, memory - own),
            Some((true, memory)) => (false, own - memory),
            Some((false, memory)) => (false, own + memory),
            None => (false, own),
        };
        // What the attachment corrected is the kept skeleton's.
        if continued {
            let exchanged = self.pipeline.prepare_sides_exchanged(&target).ok_or(
                "the skeleton with its sides continued from the previous frames does not attach",
            )?;
            let (c, w) = self.match_reprepared(&exchanged)?;
            // The sides kept are the log's exchanged unless the attachment had exchanged them.
            if !target.attachment.diagnostics.mirror.swapped {
                corrections.push(Correction::SidesSwapped);
            }
            corrections.push(Correction::SidesContinued);
            corrections.extend(
                target
                    .attachment
                    .diagnostics
                    .mirror
                    .swapped_limbs
                    .map(Correction::limbs_swapped),
            );
            (target, corr, was_warm) = (exchanged, c, w);
            if target.attachment.diagnostics.fit.accepted_poor_fit {
                corrections.push(Correction::PoorFitAccepted);
            }
        } else {
            corrections.extend(attachment_corrections(&target));
        }
        if turned_back {
            corrections.push(Correction::SkeletonTurned);
        }
        if let Some(held) = corr.view_held().filter(|&h| h < MIN_VIEW_HELD) {
            return Err(PipelineError::ViewNotHeld { held }.to_string());
        }
        let t_match = t.elapsed().as_secs_f64();
        let posed = match &corr.report {
            MethodReport::Articulated {
                posed, transforms, ..
            } => {
                self.previous_fit = Some((**transforms, target.attachment.joints.clone()));
                self.previous_sides = Some(SidesEvidence { fused, turned_back });
                let rest = &self.template.input_mesh().positions;
                let mut out: Vec<[f32; 3]> = rest.iter().map(|p| p.map(|x| x as f32)).collect();
                for (v, p) in posed.iter().enumerate() {
                    out[self.template.input_id(v as u32) as usize] = p.map(|x| x as f32);
                }
                Some(out)
            }
            _ => None,
        };
        // `scan`, `prepare`, then `match`, then the sub-stages.
        timings.insert(2, ("match".to_string(), t_match));
        timings.extend(
            corr.timings
                .iter()
                .map(|(stage, t)| (format!("match.{stage}"), *t)),
        );
        let n = self.template.input_mesh().num_vertices();
        let mut target_of = vec![-1i32; n];
        let mut confidence = vec![0f32; n];
        let shown = corr.has_counterpart();
        for (i, p) in corr.pairs.iter().enumerate() {
            if shown.is_some_and(|h| !h[i]) {
                continue;
            }
            let v = self.template.input_id(p.template) as usize;
            target_of[v] = target.input_id(p.target) as i32;
            confidence[v] = p.confidence as f32;
        }
        if let Some(posed) = &posed {
            let offsets = match_offsets(&target_of, posed, &scan.mesh.positions);
            if let (Some(max), Some(previous), true) = (
                self.options.max_match_shift_m,
                &self.previous_offsets,
                was_warm,
            ) {
                refuse_shifted(&mut target_of, &mut confidence, &offsets, previous, max);
            }
            // The reference is every match of this frame, refused or not: a match that stays
            // where it moved to is followed again from the next frame on.
            self.previous_offsets = Some(offsets);
        }
        let matched = target_of.iter().filter(|&&x| x >= 0).count();
        let mean_confidence = if matched > 0 {
            confidence.iter().map(|&c| f64::from(c)).sum::<f64>() / matched as f64
        } else {
            0.0
        };
        let labels: Vec<Option<usize>> = target.labels().iter().map(|s| Some(s.index())).collect();
        let scan_labels = target.to_input(&labels, None);
        Ok(MatchedFrame {
            coverage: matched as f64 / n.max(1) as f64,
            mean_confidence,
            fit_score: target.attachment.diagnostics.fit.score,
            view_held: corr.view_held(),
            target_of,
            confidence,
            corrections,
            scan,
            scan_labels,
            posed,
            warm: was_warm,
            timings,
        })
    }
}

/// The fused evidence for a kept fit's sides ([`TrackOptions::sides_memory`]).
#[derive(Debug, Clone, Copy)]
struct SidesEvidence {
    /// This frame's facing evidence for its skeleton's sides plus the memory's share of the
    /// previous frame's.
    fused: f64,
    /// Whether its skeleton was turned back ([`Correction::SkeletonTurned`]): the sides of a
    /// turned and an unturned skeleton are not compared.
    turned_back: bool,
}

/// The handedness check's facing evidence for the sides of `target`'s skeleton as attached
/// ([`symcorr_attach::MirrorCheck::evidence`] is that of the skeleton before the attachment's
/// side swap: reversed when it swapped). 0 when the check was not made (or gave no finite
/// number: the fused evidence stays finite).
fn sides_evidence(target: &PreparedMesh) -> f64 {
    let m = &target.attachment.diagnostics.mirror;
    let e = if m.swapped {
        -m.evidence()
    } else {
        m.evidence()
    };
    if e.is_finite() {
        e
    } else {
        0.0
    }
}

/// Whether `current` has its sides exchanged against `previous` (the previous fit's joints):
/// `Some(true)` when both limb pairs fit `previous` clearly better with left and right
/// exchanged ([`limb_swap_evidence`] above [`SWAP_EVIDENCE_THRESHOLD`]), `Some(false)` when
/// both fit it clearly better as named, `None` otherwise (limbs passing each other, or a pair
/// whose joints were lost).
fn sides_exchanged(previous: &Skeleton, current: &Skeleton) -> Option<bool> {
    let evidence =
        [LimbPair::Legs, LimbPair::Arms].map(|p| limb_swap_evidence(previous, current, p));
    if evidence.iter().all(|&e| e > SWAP_EVIDENCE_THRESHOLD) {
        Some(true)
    } else if evidence.iter().all(|&e| e < -SWAP_EVIDENCE_THRESHOLD) {
        Some(false)
    } else {
        None
    }
}

/// A frame's scan prepared with `skeleton` by `pipeline`, seen from the origin (the scan is in
/// camera space: its camera sits there), and its articulated tables (`None` for the other
/// methods).
fn prepare_scan(
    pipeline: &Pipeline,
    template: (&PreparedMesh, &ArticulatedTables),
    scan: &ScanMesh,
    skeleton: &Skeleton,
) -> Result<(PreparedMesh, Option<ArticulatedTables>), String> {
    let target = prepare_view(pipeline, scan, skeleton)?;
    let tables = scan_tables(pipeline, template, &target)?;
    Ok((target, tables))
}

/// A frame's scan prepared with its joints, seen from the camera at the origin (its
/// viewpoint, for the occlusion test).
fn prepare_view(
    pipeline: &Pipeline,
    scan: &ScanMesh,
    skeleton: &Skeleton,
) -> Result<PreparedMesh, String> {
    Ok(pipeline
        .prepare(scan.mesh.clone(), skeleton)
        .map_err(|e| e.to_string())?
        .seen_from(nalgebra::Point3::origin()))
}

/// A prepared scan's articulated tables against `template`, with its search index (`None`
/// for the other methods).
fn scan_tables(
    pipeline: &Pipeline,
    template: (&PreparedMesh, &ArticulatedTables),
    target: &PreparedMesh,
) -> Result<Option<ArticulatedTables>, String> {
    if pipeline.options.method != Method::Articulated {
        return Ok(None);
    }
    ArticulatedTables::target_against(template, target, &pipeline.options.articulated)
        .map(Some)
        .map_err(|e| e.to_string())
}

/// What the attachment of a frame's scan corrected: the skeleton's sides swapped to fit the
/// scan, a poor fit accepted.
fn attachment_corrections(target: &PreparedMesh) -> Vec<Correction> {
    let d = &target.attachment.diagnostics;
    let mut out = Vec::new();
    if d.mirror.swapped {
        out.push(Correction::SidesSwapped);
    }
    out.extend(d.mirror.swapped_limbs.map(Correction::limbs_swapped));
    if d.fit.accepted_poor_fit {
        out.push(Correction::PoorFitAccepted);
    }
    out
}

/// Per template input vertex, its match's position minus its posed position (`None` where it
/// has no match).
fn match_offsets(
    target_of: &[i32],
    posed: &[[f32; 3]],
    scan: &[[f64; 3]],
) -> Vec<Option<[f64; 3]>> {
    target_of
        .iter()
        .zip(posed)
        .map(|(&t, x)| {
            let y = scan.get(usize::try_from(t).ok()?)?;
            Some([
                y[0] - f64::from(x[0]),
                y[1] - f64::from(x[1]),
                y[2] - f64::from(x[2]),
            ])
        })
        .collect()
}

/// The temporal check: every match whose offset from its posed vertex moved more than `max`
/// since `previous` loses it (target −1, confidence 0). Returns how many were refused.
fn refuse_shifted(
    target_of: &mut [i32],
    confidence: &mut [f32],
    offsets: &[Option<[f64; 3]>],
    previous: &[Option<[f64; 3]>],
    max: f64,
) -> usize {
    let mut refused = 0;
    for (v, (now, before)) in offsets.iter().zip(previous).enumerate() {
        if let (Some(a), Some(b)) = (now, before) {
            let d2 = (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2);
            if d2 > max * max {
                target_of[v] = -1;
                confidence[v] = 0.0;
                refused += 1;
            }
        }
    }
    refused
}

/// Confidence given to a joint borrowed from the previous frame: usable, below a tracked one.
const BORROWED_CONFIDENCE: f64 = 0.5;

/// Fills the joints `current` has lost (confidence 0) but `previous` tracked with `previous`'s
/// positions moved by the mean motion of the joints tracked in both — a tracker that drops a
/// torso joint for a frame does not make the frame unusable. Borrowed joints get confidence
/// [`BORROWED_CONFIDENCE`] and the `interpolated` flag. Nothing is borrowed when no joint is
/// tracked in both frames. Returns whether a joint was borrowed.
fn borrow_lost_joints(previous: &Skeleton, current: &mut Skeleton) -> bool {
    let both: Vec<usize> = (0..current.positions.len())
        .filter(|&j| previous.confidence[j] > 0.0 && current.confidence[j] > 0.0)
        .collect();
    if both.is_empty() {
        return false;
    }
    let motion = both
        .iter()
        .map(|&j| current.positions[j] - previous.positions[j])
        .sum::<nalgebra::Vector3<f64>>()
        / both.len() as f64;
    let mut borrowed = false;
    for j in 0..current.positions.len() {
        if current.confidence[j] <= 0.0 && previous.confidence[j] > 0.0 {
            current.positions[j] = previous.positions[j] + motion;
            current.confidence[j] = BORROWED_CONFIDENCE;
            current.interpolated[j] = true;
            borrowed = true;
        }
    }
    borrowed
}

/// The largest distance a joint moved from `a` to `b` (joints tracked in both).
fn largest_joint_motion(a: &Skeleton, b: &Skeleton) -> f64 {
    (0..a.positions.len())
        .filter(|&j| a.confidence[j] > 0.0 && b.confidence[j] > 0.0)
        .map(|j| (a.positions[j] - b.positions[j]).norm())
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use symcorr_skeleton::Joint;

    /// The fixture recording's frames 10–15 (each tracked with sides as logged, `ok`), frame 15
    /// observed with its handedness check made to exchange the skeleton's sides on evidence as
    /// strong as the true sides have (a frame's misleading feet cue): the tracker continues the
    /// previous frames' sides, and the frame is posed where it is posed unforged; each frame's
    /// check deciding alone poses it with every limb on its twin's side.
    #[test]
    fn a_frame_whose_handedness_check_exchanges_the_sides_continues_the_previous_frames() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/synth");
        let rec = symcorr_kinect::Recording::open(root.join("recording")).unwrap();
        let log = symcorr_kinect::read_joints(root.join("recording/joints.json")).unwrap();
        let pipeline = Pipeline::new(crate::PipelineOptions {
            mode: crate::Mode::Dense,
            ..crate::PipelineOptions::default()
        });
        let body = |dir: &str, ext: &str| root.join(format!("bodies/{dir}/s0_rest.{ext}"));
        let mesh = symcorr_mesh::io::read(body("meshes", "ply")).unwrap().mesh;
        let joints = crate::io::read_skeleton(&body("joints", "json"), None).unwrap();
        let template = pipeline.prepare(mesh, &joints).unwrap();
        // (frame 15's corrections, its posed template)
        let run = |forge: bool, sides_memory: Option<SidesMemory>| {
            let options = TrackOptions {
                joint_offset_s: 0.04,
                sides_memory,
                ..TrackOptions::default()
            };
            let track = JointTrack::new(log.clone(), 0.0).unwrap();
            let mut tracker = Tracker::new(&pipeline, &template, *rec.intrinsics(), track, options);
            let mut last = None;
            for k in 10..=15 {
                let depth = rec.frame(k).unwrap();
                let (observer, fitter) = tracker.parts();
                let mut o = observer.observe(rec.time(k).unwrap(), &depth).unwrap();
                if forge && k == 15 {
                    let true_sides = o.target.attachment.diagnostics.mirror.clone();
                    assert!(!true_sides.swapped && true_sides.evidence() > 0.45);
                    let mut forged = pipeline.prepare_sides_exchanged(&o.target).unwrap();
                    let negate = |e: Option<f64>| e.map(|e| -e);
                    forged.attachment.diagnostics.mirror = symcorr_attach::MirrorCheck {
                        skeleton_evidence: negate(true_sides.skeleton_evidence),
                        mesh_evidence: negate(true_sides.mesh_evidence),
                        knee_evidence: negate(true_sides.knee_evidence),
                        swapped: true,
                        ..true_sides
                    };
                    o.tables =
                        scan_tables(&pipeline, (&template, &observer.template.1), &forged).unwrap();
                    o.target = forged;
                }
                match fitter.fit(o) {
                    FrameOutcome::Matched(m) => last = Some((m.corrections, m.posed.unwrap())),
                    FrameOutcome::Skipped(r) => panic!("frame {k} skipped: {r}"),
                }
            }
            last.unwrap()
        };
        let mean_distance = |a: &[[f32; 3]], b: &[[f32; 3]]| {
            let d = a.iter().zip(b).map(|(p, q)| {
                (0..3)
                    .map(|c| f64::from(p[c] - q[c]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            });
            d.sum::<f64>() / a.len() as f64
        };
        let (corrections, truth) = run(false, Some(SIDES_MEMORY));
        assert!(
            !corrections.contains(&Correction::SidesContinued),
            "{corrections:?}"
        );
        let (corrections, continued) = run(true, Some(SIDES_MEMORY));
        assert!(
            corrections.contains(&Correction::SidesContinued),
            "{corrections:?}"
        );
        assert!(
            !corrections.contains(&Correction::SidesSwapped),
            "{corrections:?}"
        );
        let (corrections, alone) = run(true, None);
        assert!(
            corrections.contains(&Correction::SidesSwapped),
            "{corrections:?}"
        );
        let (kept, mirrored) = (
            mean_distance(&continued, &truth),
            mean_distance(&alone, &truth),
        );
        assert!(
            kept < 0.02 && mirrored > 0.05,
            "{kept} m, each frame alone {mirrored} m"
        );
    }

    #[test]
    fn the_fitter_spreads_wide_while_the_observer_is_light_with_a_dead_band() {
        // No ratio yet: stays as it is.
        assert!(fitter_spread_wide(true, f64::NAN));
        assert!(!fitter_spread_wide(false, f64::NAN));
        // Wide stays wide up to the upper threshold, then goes back to its half.
        assert!(fitter_spread_wide(true, 0.3));
        assert!(fitter_spread_wide(true, NARROW_FITTER_ABOVE));
        assert!(!fitter_spread_wide(true, 0.95));
        // Half stays half down to the lower threshold: between the two nothing switches.
        assert!(!fitter_spread_wide(false, 0.65));
        assert!(!fitter_spread_wide(false, WIDE_FITTER_BELOW));
        assert!(fitter_spread_wide(false, 0.2));
        // An observer with no time at all (every frame refused at once) leaves the cores free.
        assert!(fitter_spread_wide(false, 0.0));
    }

    #[test]
    fn fitter_pools_follow_the_observer_to_frame_times() {
        // Two threads: the observer's pool takes one, the fitter one or both.
        let mut pools = FitterPools::new(2);
        let size = |p: Option<&rayon::ThreadPool>| p.map(|p| p.current_num_threads());
        // Before any frame: all of them (the first frames are fitted from the skeletons).
        assert_eq!(size(pools.pick(f64::NAN)), Some(2));
        pools.fitted(0.060);
        // The observer's frames take as long as the fitter's: half.
        assert_eq!(size(pools.pick(0.058)), Some(1));
        // 0.039 s against 0.06 (0.65) lies between the thresholds: still half.
        assert_eq!(size(pools.pick(0.039)), Some(1));
        // A light observer (0.02 s against 0.06): all again.
        assert_eq!(size(pools.pick(0.020)), Some(2));
        // The fitter's own frames grow shorter (its average falls towards 0.025 s) while the
        // observer's stay at 0.02: past 0.7 of its own, back to half.
        let picked: Vec<_> = (0..20)
            .map(|_| {
                pools.fitted(0.025);
                size(pools.pick(0.020))
            })
            .collect();
        assert_eq!(picked.first(), Some(&Some(2)));
        assert_eq!(picked.last(), Some(&Some(1)));
        // One thread in all: one pool of one thread for both choices.
        let mut one = FitterPools::new(1);
        assert_eq!(size(one.pick(f64::NAN)), Some(1));
        one.fitted(0.05);
        assert_eq!(size(one.pick(0.01)), Some(1));
    }

    #[test]
    fn smoothed_seconds_start_at_the_first_frame_and_skip_non_finite_ones() {
        let mut s = SmoothedSeconds::default();
        assert_eq!(s.get(), None);
        s.add(f64::NAN);
        assert_eq!(s.get(), None);
        s.add(1.0);
        assert_eq!(s.get(), Some(1.0));
        s.add(2.0);
        approx::assert_relative_eq!(s.get().unwrap(), 1.2, epsilon = 1e-12);
        s.add(f64::INFINITY);
        approx::assert_relative_eq!(s.get().unwrap(), 1.2, epsilon = 1e-12);
    }

    #[test]
    fn a_lost_joint_is_borrowed_from_the_previous_frame_moved_with_the_body() {
        let prev = symcorr_attach::testbody::t_pose(1.0);
        let mut cur = prev.clone();
        let step = nalgebra::Vector3::new(0.05, 0.0, -0.02);
        for p in cur.positions.iter_mut() {
            *p += step;
        }
        let spine = Joint::Spine.index();
        cur.confidence[spine] = 0.0;
        cur.positions[spine] = nalgebra::Point3::origin();
        assert!(borrow_lost_joints(&prev, &mut cur));
        approx::assert_relative_eq!(
            cur.positions[spine],
            prev.positions[spine] + step,
            epsilon = 1e-12
        );
        assert_eq!(cur.confidence[spine], BORROWED_CONFIDENCE);
        assert!(cur.interpolated[spine]);
        // Nothing lost, nothing borrowed; a previous frame without the joint lends nothing.
        let mut again = cur.clone();
        assert!(!borrow_lost_joints(&prev, &mut again));
        let mut lost_both = prev.clone();
        lost_both.confidence[spine] = 0.0;
        let mut cur2 = lost_both.clone();
        assert!(!borrow_lost_joints(&lost_both, &mut cur2));
        assert_eq!(cur2.confidence[spine], 0.0);
    }

    #[test]
    fn a_match_that_moved_against_its_posed_vertex_is_refused() {
        // Vertex 0 moved with its posed vertex, vertex 1 slid 4 cm along the surface, vertex 2
        // had no match before, vertex 3 has none now.
        let posed = [
            [0.0f32, 0.0, 1.0],
            [0.1, 0.0, 1.0],
            [0.2, 0.0, 1.0],
            [0.3, 0.0, 1.0],
        ];
        let scan = [[0.005, 0.0, 1.0], [0.14, 0.0, 1.0], [0.2, 0.1, 1.0]];
        let mut target_of = vec![0, 1, 2, -1];
        let mut confidence = vec![0.9f32, 0.8, 0.7, 0.0];
        let offsets = match_offsets(&target_of, &posed, &scan);
        assert_eq!(offsets[3], None);
        approx::assert_relative_eq!(offsets[1].unwrap()[0], 0.04, epsilon = 1e-6);
        let previous = vec![Some([0.0, 0.0, 0.0]), Some([0.0, 0.0, 0.0]), None, None];
        let refused = refuse_shifted(&mut target_of, &mut confidence, &offsets, &previous, 0.03);
        assert_eq!(refused, 1);
        assert_eq!(target_of, vec![0, -1, 2, -1]);
        assert_eq!(confidence, vec![0.9, 0.0, 0.7, 0.0]);
        // A looser bound keeps it.
        let mut target_of = vec![0, 1, 2, -1];
        assert_eq!(
            refuse_shifted(&mut target_of, &mut confidence, &offsets, &previous, 0.05),
            0
        );
    }

    #[test]
    fn swapping_a_limb_pair_exchanges_only_its_joints_and_twice_is_identity() {
        let sk = symcorr_attach::testbody::t_pose(1.0);
        let s = sk.swap_limbs(LimbPair::Legs);
        assert_eq!(s.position(Joint::KneeLeft), sk.position(Joint::KneeRight));
        assert_eq!(s.position(Joint::FootRight), sk.position(Joint::FootLeft));
        assert_eq!(s.position(Joint::HandLeft), sk.position(Joint::HandLeft));
        assert_eq!(s.swap_limbs(LimbPair::Legs).positions, sk.positions);
    }

    #[test]
    fn sides_are_exchanged_only_when_both_limb_pairs_say_so() {
        let sk = symcorr_attach::testbody::t_pose(1.0);
        assert_eq!(sides_exchanged(&sk, &sk), Some(false));
        assert_eq!(sides_exchanged(&sk, &sk.swap_sides()), Some(true));
        // One pair alone is the tracker's limb swap, not the sides.
        assert_eq!(sides_exchanged(&sk, &sk.swap_limbs(LimbPair::Legs)), None);
        // Legs lost: no verdict.
        let mut lost = sk.swap_sides();
        for j in LimbPair::Legs.left_joints() {
            lost.confidence[j.index()] = 0.0;
            lost.confidence[j.mirror().index()] = 0.0;
        }
        assert_eq!(sides_exchanged(&sk, &lost), None);
    }
}
