//! `symcorr track`'s per-frame accuracy on a synthetic recording with ground truth
//! (`symcorr-synth recording`: truth/NNNNNN.png holds, per pixel, the body vertex id + 1).
//!
//! ```text
//! cargo run --release -p symcorr-experiments --bin track_eval -- fixtures/synth/recording
//! ```
//!
//! For every frame, the template (fixtures/synth/bodies s0_rest, the recording body's topology)
//! is matched by `symcorr::track::Tracker` exactly as `symcorr track` does; each matched template
//! vertex `v` lands on a scan vertex, whose pixel's truth names the body vertex `b` seen there.
//! The error is the geodesic distance from `v` to `b` on the template over its √area (the body
//! vertex ids are the template's), a flip is `b` nearer `v`'s mirror twin (symcorr-eval's
//! `evaluate`). One line per frame (status, corrections, coverage, mean error, flips, matches on
//! pixels with no body vertex, seconds, and the share of scan vertices whose segment label is
//! the template's label of the body vertex they show, and the matches that jumped: template
//! vertices matched in this frame and the previous one whose matched body vertex moved more
//! than 5 cm on the body at rest — the same material point stays the same body vertex however
//! the body moves, so any such move is beyond the true motion), then the totals, with flips and
//! jumps per template segment. `--breakdown` adds, under each frame's line, one line per segment
//! with flips or jumps: their counts and how far the posed segment sits from the scan points
//! showing its vertices (median, and the rigid motion between the two: a turned or a shifted
//! fit). `--projective` scores each match at the pixel its posed template vertex projects to
//! instead of at its scan vertex: the fit's own accuracy and jumps, without the final map's
//! choice among the scan's noisy points.

use clap::Parser;
use std::path::PathBuf;
use std::time::Instant;
use symcorr::track::{FrameOutcome, TrackOptions, Tracker};
use symcorr::{Pipeline, PipelineOptions};
use symcorr_eval::{evaluate, read_mirror, EvalGraph};
use symcorr_kinect::{read_depth_png16, JointTrack, Recording};

/// Per-frame accuracy of `symcorr track` on a recording with ground truth.
#[derive(Parser, Debug)]
struct Args {
    /// Recording folder with truth/ (symcorr-synth recording).
    recording: PathBuf,
    /// Joint log (default: RECORDING/joints.json).
    #[arg(long)]
    joints: Option<PathBuf>,
    /// Track every Nth frame only (as `symcorr track --every N`).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    every: u64,
    /// Template body folder (meshes/, joints/, mirror.txt), the recording body's topology.
    #[arg(long, default_value = "fixtures/synth/bodies")]
    bodies: PathBuf,
    /// Template name in the body folder.
    #[arg(long, default_value = "s0_rest")]
    template: String,
    /// Seconds added to every depth frame's time before the joint log is read.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    joint_offset: f64,
    /// Turn the limb-swap fix off.
    #[arg(long)]
    no_swap_fix: bool,
    /// Turn the joint smoothing off.
    #[arg(long)]
    no_smoothing: bool,
    /// Start every frame's fit from the skeletons (no warm start from the previous frame).
    #[arg(long)]
    cold: bool,
    /// Also print, for this frame, the mean error and match count per template segment.
    #[arg(long, value_name = "FRAME")]
    detail: Option<usize>,
    /// Template points driving the ICP fits (default: the method's).
    #[arg(long)]
    icp_points: Option<usize>,
    /// ICP rounds from a warm start (default: the method's).
    #[arg(long)]
    warm_iterations: Option<usize>,
    /// Rounds of the non-rigid step (default: the method's).
    #[arg(long)]
    nonrigid_rounds: Option<usize>,
    /// Rounds of the non-rigid step from a warm start (default: the method's).
    #[arg(long)]
    warm_nonrigid_rounds: Option<usize>,
    /// Radius of the reciprocal check, in the template's √area (default: the tracker's; 0
    /// turns it off).
    #[arg(long)]
    reciprocal_radius: Option<f64>,
    /// Temporal check: largest move of a match against its posed vertex between frames,
    /// metres (default: the tracker's; 0 turns it off).
    #[arg(long)]
    max_match_shift: Option<f64>,
    /// Weight of the joint anchors in a bone's fit (default: the method's).
    #[arg(long)]
    joint_anchor: Option<f64>,
    /// Weight of the head bone's anchor at the neck's base, relative to the other joint
    /// anchors (default: the method's).
    #[arg(long)]
    head_neck_anchor: Option<f64>,
    /// Weight of the head twist prior (default: the method's; 0 turns it off).
    #[arg(long)]
    head_twist_prior: Option<f64>,
    /// Largest share of the unturned head's score a turned start of the warm twist search may
    /// keep (default: the method's; 0 turns the search off).
    #[arg(long)]
    head_warm_twist: Option<f64>,
    /// Weight of the prior that holds the head at the turn the joint log reports (default: the
    /// method's; 0 turns it off).
    #[arg(long)]
    head_turn_prior: Option<f64>,
    /// Weight of the target → template pairs in the ICP rounds against the template → target
    /// pairs (default: the method's; 0 turns them off).
    #[arg(long)]
    target_to_template: Option<f64>,
    /// Over-relaxation of the ICP rounds from a warm start: each bone's step taken this many
    /// times (default: the method's; 1: as fitted).
    #[arg(long)]
    warm_relaxation: Option<f64>,
    /// One-euro filter of the joints: minimum cutoff (Hz), beta (per m/s) and derivative
    /// cutoff (Hz), `MIN,BETA,D` (default: the tracker's).
    #[arg(long, value_delimiter = ',')]
    euro: Option<Vec<f64>>,
    /// Score each matched template vertex at the pixel its posed position projects to (the
    /// fit's own accuracy, without the final map's choice of scan vertex).
    #[arg(long)]
    projective: bool,
    /// Cutoff (Hz) of the low-pass of the attachment's joint refinement over time (default: the
    /// tracker's; 0 turns it off: each frame's own refinement)
    #[arg(long)]
    refinement_cutoff: Option<f64>,
    /// Share of the fused sides evidence carried to the next frame (default: the tracker's; 0
    /// turns it off: each frame's handedness check decides alone).
    #[arg(long)]
    sides_memory: Option<f64>,
    /// Per frame, also print the flips and jumps per template segment and how far that
    /// segment's posed template sits from where the frame shows it (median, metres).
    #[arg(long)]
    breakdown: bool,
    /// Solve each frame's bone heat on clusters of this radius (skeleton heights; 0: on the
    /// scan itself). Default: the tracker's.
    #[arg(long)]
    heat_radius: Option<f64>,
}

/// A match that moves farther than this on the body between consecutive frames jumped (metres,
/// on the body at rest).
const JUMP_M: f64 = 0.05;

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let rec = Recording::open(&args.recording)?;
    let joints = args
        .joints
        .clone()
        .unwrap_or_else(|| args.recording.join("joints.json"));
    let track = JointTrack::new(symcorr_kinect::read_joints(&joints)?, 0.0)?;
    let mesh_path = args
        .bodies
        .join("meshes")
        .join(format!("{}.ply", args.template));
    let mesh = symcorr_mesh::io::read(&mesh_path)?.mesh;
    let sk = symcorr::io::read_skeleton(
        &args
            .bodies
            .join("joints")
            .join(format!("{}.json", args.template)),
        None,
    )?;
    let mirror = read_mirror(&args.bodies.join("mirror.txt"))?;
    let graph = EvalGraph::new(&mesh);
    let area = mesh.total_area();
    let mut options = PipelineOptions {
        mode: symcorr::Mode::Dense,
        ..PipelineOptions::default()
    };
    let a = &mut options.articulated;
    a.icp_points = args.icp_points.unwrap_or(a.icp_points);
    a.warm_iterations = args.warm_iterations.unwrap_or(a.warm_iterations);
    a.nonrigid_rounds = args.nonrigid_rounds.unwrap_or(a.nonrigid_rounds);
    a.warm_nonrigid_rounds = args.warm_nonrigid_rounds.unwrap_or(a.warm_nonrigid_rounds);
    a.joint_anchor = args.joint_anchor.unwrap_or(a.joint_anchor);
    a.head_neck_anchor = args.head_neck_anchor.unwrap_or(a.head_neck_anchor);
    if let Some(w) = args.head_twist_prior {
        a.head_twist_prior = (w > 0.0).then_some(w);
    }
    if let Some(w) = args.head_turn_prior {
        a.head_turn_prior = (w > 0.0).then_some(w);
    }
    if let Some(g) = args.head_warm_twist {
        a.head_warm_twist = (g > 0.0).then_some(g);
    }
    if let Some(w) = args.target_to_template {
        a.target_to_template = (w > 0.0).then_some(symcorr_correspond::TargetPairs {
            weight: w,
            ..symcorr_correspond::TargetPairs::default()
        });
    }
    if let Some(r) = args.warm_relaxation {
        a.warm_relaxation = r;
    }
    let pipeline = Pipeline::new(options);
    let template = pipeline.prepare(mesh, &sk)?;
    let index: Vec<usize> = template.labels().iter().map(|l| l.index()).collect();
    let template_labels: Vec<usize> = template.to_input(&index, usize::MAX);
    let options = TrackOptions {
        joint_offset_s: args.joint_offset,
        fix_swaps: !args.no_swap_fix,
        warm_start: !args.cold,
        smoothing: match (&args.euro, args.no_smoothing) {
            (_, true) => None,
            (Some(e), false) => match e.as_slice() {
                &[min, beta, d] => Some(symcorr_kinect::OneEuroFilter::new(min, beta, d)?),
                _ => return Err("--euro takes three numbers: MIN,BETA,D".into()),
            },
            (None, false) => Some(symcorr_kinect::OneEuroFilter::default()),
        },
        reciprocal_radius: args
            .reciprocal_radius
            .map_or(Some(symcorr::track::RECIPROCAL_RADIUS), |r| {
                (r > 0.0).then_some(r)
            }),
        max_match_shift_m: args
            .max_match_shift
            .map_or(Some(symcorr::track::MAX_MATCH_SHIFT_M), |d| {
                (d > 0.0).then_some(d)
            }),
        scan_heat_mesh: args
            .heat_radius
            .map_or(symcorr::track::SCAN_HEAT_MESH, |r| {
                if r > 0.0 {
                    symcorr_attach::HeatMesh::Clustered { radius: r }
                } else {
                    symcorr_attach::HeatMesh::Input
                }
            }),
        refinement_smoothing: match args.refinement_cutoff {
            None => TrackOptions::default().refinement_smoothing,
            Some(c) if c > 0.0 => Some(symcorr_kinect::JointMoveFilter::new(c)?),
            Some(_) => None,
        },
        sides_memory: match args.sides_memory {
            None => Some(symcorr::track::SIDES_MEMORY),
            Some(m) if m > 0.0 => Some(symcorr::track::SidesMemory::new(m)?),
            Some(_) => None,
        },
        ..TrackOptions::default()
    };
    let mut tracker = Tracker::new(&pipeline, &template, *rec.intrinsics(), track, options);
    let (mut all_errors, mut flips, mut counted, mut off_body, mut matched_frames) =
        (Vec::new(), 0usize, 0usize, 0usize, 0usize);
    let mut seconds = 0.0;
    // Temporal stability: per template vertex, the body vertex its match showed in the previous
    // frame; a match that moves more than JUMP_M on the body between consecutive frames jumped
    // (the same material point stays the same body vertex however the body moves).
    let rest = template.input_mesh().positions.clone();
    let mut previous: Option<Vec<Option<u32>>> = None;
    let (mut jumps, mut followed) = (0usize, 0usize);
    let mut jumps_per_segment = vec![0usize; symcorr_attach::Segment::ALL.len()];
    let mut flips_per_segment = vec![0usize; symcorr_attach::Segment::ALL.len()];
    // Jumps whose match in the later frame is the wrong one (more than half a jump from its
    // truth); the others left a wrong match of the earlier frame.
    let mut jumps_wrong_now = 0usize;
    println!(
        "frame status corrections coverage mean_error flips off_body seconds labels_agreement jumps"
    );
    let frames: Vec<usize> = (0..rec.len()).step_by(args.every as usize).collect();
    for &i in &frames {
        let time = rec.time(i).unwrap_or(f64::NAN);
        let depth = rec.frame(i)?;
        let truth = read_depth_png16(args.recording.join(format!("truth/{i:06}.png")))?;
        let t = Instant::now();
        let outcome = tracker.frame(time, &depth);
        let dt = t.elapsed().as_secs_f64();
        seconds += dt;
        match outcome {
            FrameOutcome::Skipped(reason) => {
                previous = None;
                println!("{i} skipped: {reason}")
            }
            FrameOutcome::Matched(m) => {
                matched_frames += 1;
                let mut pairs = Vec::new();
                let mut off = 0;
                let k = rec.intrinsics();
                for (v, &s) in m.target_of.iter().enumerate() {
                    if s < 0 {
                        continue;
                    }
                    // The body vertex seen at the scan vertex's pixel, or with `--projective`
                    // at the pixel the posed template vertex projects to.
                    let shown = match (args.projective, &m.posed) {
                        (true, Some(posed)) => {
                            let [u, w] =
                                k.project(&nalgebra::Point3::from(posed[v].map(f64::from)));
                            let (u, w) = (u.round(), w.round());
                            // NaN fails the test; `as` saturates what lies beyond the image.
                            (u >= 0.0 && w >= 0.0)
                                .then(|| truth.at(u as u32, w as u32))
                                .flatten()
                        }
                        _ => truth
                            .data_mm
                            .get(m.scan.pixel_ids[s as usize] as usize)
                            .copied(),
                    };
                    match shown.unwrap_or(0) {
                        0 => off += 1,
                        b => pairs.push((v as u32, u32::from(b) - 1)),
                    }
                }
                // The scan's segment labels against the template's at the body vertex each scan
                // vertex shows: how well the frame's attachment went.
                let (mut agree, mut seen) = (0usize, 0usize);
                for (sv, l) in m.scan_labels.iter().enumerate() {
                    let pixel = m.scan.pixel_ids[sv] as usize;
                    let b = truth.data_mm.get(pixel).copied().unwrap_or(0);
                    if let (Some(l), true) = (l, b > 0) {
                        seen += 1;
                        agree += usize::from(*l == template_labels[usize::from(b) - 1]);
                    }
                }
                let e = evaluate(&graph, area, &pairs, |p| p, Some(&mirror));
                let mut shows = vec![None; m.target_of.len()];
                let mut error_of = vec![f64::NAN; m.target_of.len()];
                for (&(v, b), err) in pairs.iter().zip(&e.errors) {
                    shows[v as usize] = Some(b);
                    error_of[v as usize] = err * area.sqrt();
                }
                let nseg = symcorr_attach::Segment::ALL.len();
                let mut frame_seg_jumps = vec![0usize; nseg];
                let mut frame_seg_flips = vec![0usize; nseg];
                for (&(v, _), flip) in pairs.iter().zip(&e.flips) {
                    if *flip == Some(true) {
                        frame_seg_flips[template_labels[v as usize]] += 1;
                    }
                }
                let (mut frame_jumps, mut frame_followed) = (0usize, 0usize);
                if let Some(prev) = &previous {
                    for (v, (a, b)) in prev.iter().zip(&shows).enumerate() {
                        if let (Some(a), Some(b)) = (a, b) {
                            frame_followed += 1;
                            let (p, q) = (rest[*a as usize], rest[*b as usize]);
                            let d = ((p[0] - q[0]).powi(2)
                                + (p[1] - q[1]).powi(2)
                                + (p[2] - q[2]).powi(2))
                            .sqrt();
                            if d > JUMP_M {
                                frame_jumps += 1;
                                frame_seg_jumps[template_labels[v]] += 1;
                                // Which end of the jump is wrong: a match within half the
                                // jump of its truth now was the wrong one before.
                                if error_of[v] > JUMP_M / 2.0 {
                                    jumps_wrong_now += 1;
                                }
                            }
                        }
                    }
                }
                jumps += frame_jumps;
                followed += frame_followed;
                previous = Some(shows);
                for (total, k) in jumps_per_segment.iter_mut().zip(&frame_seg_jumps) {
                    *total += k;
                }
                for (total, k) in flips_per_segment.iter_mut().zip(&frame_seg_flips) {
                    *total += k;
                }
                if args.detail == Some(i) {
                    let segs = symcorr_attach::Segment::ALL;
                    let mut conf = vec![vec![0usize; segs.len()]; segs.len()];
                    for (sv, l) in m.scan_labels.iter().enumerate() {
                        let pixel = m.scan.pixel_ids[sv] as usize;
                        let b = truth.data_mm.get(pixel).copied().unwrap_or(0);
                        if let (Some(l), true) = (l, b > 0) {
                            conf[template_labels[usize::from(b) - 1]][*l] += 1;
                        }
                    }
                    for (seg, row) in segs.iter().zip(conf) {
                        let on: Vec<String> = segs
                            .iter()
                            .zip(row)
                            .filter(|(_, k)| *k > 0)
                            .map(|(s, k)| format!("{s:?} {k}"))
                            .collect();
                        if !on.is_empty() {
                            println!("  scan showing {seg:?} labelled {}", on.join(", "));
                        }
                    }
                    let segs = symcorr_attach::Segment::ALL;
                    let mut per =
                        vec![(0.0f64, 0usize, vec![0usize; segs.len()], 0usize); segs.len()];
                    for ((&(v, b), err), flip) in pairs.iter().zip(&e.errors).zip(&e.flips) {
                        let s = &mut per[template_labels[v as usize]];
                        s.0 += err;
                        s.1 += 1;
                        s.2[template_labels[b as usize]] += 1;
                        s.3 += usize::from(*flip == Some(true));
                    }
                    let rest = &template.input_mesh().positions;
                    for ((&(v, b), flip), err) in pairs.iter().zip(&e.flips).zip(&e.errors) {
                        if *flip == Some(true) {
                            let (pv, pb) = (rest[v as usize], rest[b as usize]);
                            println!(
                                "  flip {v} ({:.3} {:.3} {:.3}) on {b} ({:.3} {:.3} {:.3}) error {err:.3} confidence {:.2}",
                                pv[0], pv[1], pv[2], pb[0], pb[1], pb[2], m.confidence[v as usize]
                            );
                        }
                    }
                    for (seg, (sum, n, on, flips)) in segs.iter().zip(per) {
                        if n > 0 {
                            let on: Vec<String> = segs
                                .iter()
                                .zip(on)
                                .filter(|(_, k)| *k > 0)
                                .map(|(s, k)| format!("{s:?} {k}"))
                                .collect();
                            println!(
                                "  {seg:?}: {n} matches, {flips} flips, mean error {:.4}, on {}",
                                sum / n as f64,
                                on.join(", ")
                            );
                        }
                    }
                }
                let (c, f) = e.flip_counts();
                let names: Vec<&str> = m.corrections.iter().map(|c| c.name()).collect();
                println!(
                    "{i} ok {} {:.3} {:.4} {f}/{c} {off} {dt:.2} {:.3} {frame_jumps}/{frame_followed}",
                    if names.is_empty() {
                        "-".to_string()
                    } else {
                        names.join(",")
                    },
                    m.coverage,
                    e.mean_error(),
                    agree as f64 / seen.max(1) as f64
                );
                if args.breakdown {
                    print_breakdown(
                        &m,
                        &truth.data_mm,
                        &template_labels,
                        &frame_seg_flips,
                        &frame_seg_jumps,
                    );
                }
                all_errors.extend(e.errors);
                flips += f;
                counted += c;
                off_body += off;
            }
        }
    }
    let mean = all_errors.iter().sum::<f64>() / all_errors.len().max(1) as f64;
    println!(
        "ALL frames {} matched {matched_frames} mean_error {mean:.4} flips {flips}/{counted} off_body {off_body} jumps {jumps}/{followed} ({:.3} %) frames/s {:.2}",
        frames.len(),
        100.0 * jumps as f64 / followed.max(1) as f64,
        frames.len() as f64 / seconds.max(f64::MIN_POSITIVE)
    );
    let per: Vec<String> = symcorr_attach::Segment::ALL
        .iter()
        .zip(&jumps_per_segment)
        .filter(|(_, &k)| k > 0)
        .map(|(s, k)| format!("{s:?} {k}"))
        .collect();
    println!(
        "jumps per template segment: {} (wrong in the later frame: {jumps_wrong_now})",
        per.join(", ")
    );
    let per: Vec<String> = symcorr_attach::Segment::ALL
        .iter()
        .zip(&flips_per_segment)
        .filter(|(_, &k)| k > 0)
        .map(|(s, k)| format!("{s:?} {k}"))
        .collect();
    println!("flips per template segment: {}", per.join(", "));
    Ok(())
}

/// One line per template segment with flips or jumps in this frame: their counts and the
/// median distance (metres) from the segment's posed template vertices to the scan points
/// whose truth names them — how far off the fit put that segment.
fn print_breakdown(
    m: &symcorr::track::MatchedFrame,
    truth: &[u16],
    template_labels: &[usize],
    flips: &[usize],
    jumps: &[usize],
) {
    let segs = symcorr_attach::Segment::ALL;
    let mut off: Vec<Vec<f64>> = vec![Vec::new(); segs.len()];
    // Per segment, (posed, shown) point pairs: the rigid motion taking the one onto the other
    // says whether the segment is turned or shifted.
    let mut both: Vec<Vec<(nalgebra::Point3<f64>, nalgebra::Point3<f64>)>> =
        vec![Vec::new(); segs.len()];
    if let Some(posed) = &m.posed {
        for (sv, &pixel) in m.scan.pixel_ids.iter().enumerate() {
            let b = truth.get(pixel as usize).copied().unwrap_or(0);
            if b == 0 {
                continue;
            }
            let v = usize::from(b) - 1;
            let (x, y) = (posed[v], m.scan.mesh.positions[sv]);
            let d = ((f64::from(x[0]) - y[0]).powi(2)
                + (f64::from(x[1]) - y[1]).powi(2)
                + (f64::from(x[2]) - y[2]).powi(2))
            .sqrt();
            off[template_labels[v]].push(d);
            both[template_labels[v]].push((
                nalgebra::Point3::from(x.map(f64::from)),
                nalgebra::Point3::from(y),
            ));
        }
    }
    for (k, seg) in segs.iter().enumerate() {
        if flips[k] == 0 && jumps[k] == 0 {
            continue;
        }
        let d = &mut off[k];
        d.sort_by(f64::total_cmp);
        let median = d.get(d.len() / 2).copied().unwrap_or(f64::NAN);
        let (angle, shift, axis) = rigid_offset(&both[k]);
        println!(
            "  {seg:?}: flips {} jumps {} posed off {median:.3} m (rigidly: turned {angle:.1}° about ({:.2} {:.2} {:.2}), shifted {shift:.3} m)",
            flips[k], jumps[k], axis[0], axis[1], axis[2]
        );
    }
}

fn main() {
    let args = Args::parse();
    if let Err(e) = run(&args) {
        eprintln!("track_eval: {e}");
        std::process::exit(1);
    }
}

/// The rigid motion best taking the first points of `pairs` onto the second (Kabsch): its
/// rotation angle (degrees) and the shift of the first points' centroid (metres).
fn rigid_offset(pairs: &[(nalgebra::Point3<f64>, nalgebra::Point3<f64>)]) -> (f64, f64, [f64; 3]) {
    if pairs.len() < 3 {
        return (f64::NAN, f64::NAN, [f64::NAN; 3]);
    }
    let n = pairs.len() as f64;
    let ca = pairs
        .iter()
        .fold(nalgebra::Vector3::zeros(), |a, p| a + p.0.coords)
        / n;
    let cb = pairs
        .iter()
        .fold(nalgebra::Vector3::zeros(), |a, p| a + p.1.coords)
        / n;
    let h = pairs.iter().fold(nalgebra::Matrix3::zeros(), |h, (a, b)| {
        h + (a.coords - ca) * (b.coords - cb).transpose()
    });
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return (f64::NAN, (cb - ca).norm(), [f64::NAN; 3]);
    };
    let mut r = vt.transpose() * u.transpose();
    if r.determinant() < 0.0 {
        let mut v = vt.transpose();
        v.column_mut(2).neg_mut();
        r = v * u.transpose();
    }
    let cos = ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
    let axis = nalgebra::Rotation3::from_matrix_unchecked(r)
        .axis()
        .map_or([f64::NAN; 3], |a| [a.x, a.y, a.z]);
    (cos.acos().to_degrees(), (cb - ca).norm(), axis)
}
