//! Recording folders, joints at depth frames' times, one-euro smoothing and left/right swap
//! evidence. Every recording is written here, in a temporary folder.

use nalgebra::{Point3, Rotation3, Vector3};
use std::path::Path;
use symcorr_kinect::{
    arms_swapped, legs_swapped, limb_swap_evidence, swap_evidence, write_depth_png16,
    write_joints_json, DepthFrame, Intrinsics, JointFrame, JointLog, JointTrack, KinectError,
    LimbPair, OneEuroFilter, Recording, SkeletonFilter, SkipReason,
};
use symcorr_skeleton::{Joint, Skeleton};

// ---------------------------------------------------------------------------------------------
// Recording folders

const W: u32 = 8;
const H: u32 = 6;

fn intrinsics() -> Intrinsics {
    Intrinsics {
        width: W,
        height: H,
        fx: 7.0,
        fy: 7.0,
        cx: 3.5,
        cy: 2.5,
        mirroring: symcorr_kinect::Mirroring::Mirrored,
        distortion: None,
    }
}

/// Frame `i` of the test recordings: every pixel `1000 + i` mm except pixel (0, 0), no reading.
fn depth(i: u16) -> DepthFrame {
    let mut data = vec![1000 + i; (W * H) as usize];
    data[0] = 0;
    DepthFrame::new(W, H, data).unwrap()
}

/// A recording folder with frames `numbers` and the given times file text.
fn write_recording(dir: &Path, numbers: &[usize], times: &str) {
    intrinsics().write(dir.join("intrinsics.json")).unwrap();
    std::fs::create_dir_all(dir.join("depth")).unwrap();
    for &n in numbers {
        write_depth_png16(dir.join(format!("depth/{n:06}.png")), &depth(n as u16)).unwrap();
    }
    std::fs::write(dir.join("depth_times.txt"), times).unwrap();
}

fn open_err(dir: &Path) -> KinectError {
    match Recording::open(dir) {
        Ok(r) => panic!("opened a bad recording: {r:?}"),
        Err(e) => e,
    }
}

/// Times written in milliseconds or microseconds, in the depth times or in the joint log, are
/// refused naming the unit they look like, not read as a 33-second or 9-hour frame interval.
#[test]
fn times_in_another_unit_than_seconds_are_refused_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    for (i, (times, unit)) in [
        ("0\n33.4\n66.7\n", Some("milliseconds")),
        ("0\n33367\n66700\n", Some("microseconds")),
        // 2000 s apart: 0.5 Hz in milliseconds or 500 Hz in microseconds.
        ("0\n2000\n4000\n", Some("milliseconds or microseconds")),
        ("0\n3.3e-5\n6.7e-5\n", None),
        ("0\n0.0334\n0.0667\n", None),
    ]
    .into_iter()
    .enumerate()
    {
        let dir = tmp.path().join(i.to_string());
        std::fs::create_dir(&dir).unwrap();
        write_recording(&dir, &[0, 1, 2], times);
        let seconds = times.contains("0.0334");
        match (Recording::open(&dir), seconds) {
            (Ok(_), true) => {}
            (Err(e @ KinectError::Recording { .. }), false) => {
                let msg = e.to_string();
                assert!(msg.contains("times must be in seconds"), "{msg}");
                match unit {
                    Some(u) => assert!(msg.contains(&format!("look like {u})")), "{msg}"),
                    None => assert!(!msg.contains("look like"), "{msg}"),
                }
                assert!(msg.contains("depth_times.txt"), "{msg}");
            }
            (r, _) => panic!("{times:?}: {r:?}"),
        }
    }
    let skeleton = Skeleton::from_arrays([[0.0, 1.0, 2.0]; 20]);
    for (fps, ok) in [(30.0, true), (0.03, false), (500.0, true), (3e4, false)] {
        let log = JointLog::from_skeletons(vec![skeleton.clone(); 4], fps);
        match JointTrack::new(log, 0.0) {
            Ok(_) => assert!(ok, "{fps} frames per second"),
            Err(KinectError::Track(msg)) => {
                assert!(!ok && msg.contains("times must be in seconds"), "{msg}");
                assert!(fps > 1.0 || msg.contains("milliseconds"), "{msg}");
            }
            Err(e) => panic!("{e}"),
        }
    }
}

#[test]
fn valid_recording_opens_and_reads_frames_on_demand() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    write_recording(dir, &[0, 1, 2], "10.0\n10.0333\r\n  10.0667 \n");
    // Extra files anywhere are ignored, also in depth/ (names that are not frame numbers).
    std::fs::write(dir.join("notes.txt"), "kinect, living room").unwrap();
    std::fs::write(dir.join("depth/README"), "frames").unwrap();
    write_depth_png16(dir.join("depth/preview.png"), &depth(9)).unwrap();
    std::fs::create_dir(dir.join("color")).unwrap();
    let mut log =
        JointLog::from_skeletons(vec![Skeleton::from_arrays([[0.0, 1.0, 2.0]; 20])], 30.0);
    log.frames[0].time_s = 10.0;
    write_joints_json(dir.join("joints.json"), &log).unwrap();

    let rec = Recording::open(dir).unwrap();
    assert_eq!(rec.len(), 3);
    assert!(!rec.is_empty());
    assert_eq!(rec.intrinsics(), &intrinsics());
    assert_eq!(rec.times(), &[10.0, 10.0333, 10.0667]);
    assert_eq!(rec.time(2), Some(10.0667));
    assert_eq!(rec.time(3), None);
    assert_eq!(rec.dir(), dir);
    assert_eq!(rec.frame_path(1), dir.join("depth").join("000001.png"));
    for i in 0..3 {
        assert_eq!(rec.frame(i).unwrap(), depth(i as u16));
    }
    let e = rec.frame(3).unwrap_err();
    assert!(matches!(e, KinectError::Recording { .. }));
    assert!(e
        .to_string()
        .ends_with("depth: frame 3 requested, but the recording has 3 frames (0..=2)"));
}

#[test]
fn frames_must_be_contiguous_from_zero() {
    // A gap: 000002.png is missing.
    let tmp = tempfile::tempdir().unwrap();
    write_recording(tmp.path(), &[0, 1, 3], "0\n1\n2\n");
    let e = open_err(tmp.path());
    assert!(matches!(e, KinectError::Recording { .. }), "{e}");
    let msg = e.to_string();
    assert!(msg.contains("000002.png: missing"), "{msg}");
    assert!(
        msg.ends_with("(found 000000.png to 000001.png, then 000003.png)"),
        "{msg}"
    );
    assert!(!msg.contains('\n'));

    // Not starting at 000000.
    let tmp = tempfile::tempdir().unwrap();
    write_recording(tmp.path(), &[1, 2], "0\n1\n");
    let msg = open_err(tmp.path()).to_string();
    assert!(msg.contains("000000.png: missing"), "{msg}");
    assert!(
        msg.ends_with("(no frame before it, then 000001.png)"),
        "{msg}"
    );

    // A frame number with the wrong number of digits.
    let tmp = tempfile::tempdir().unwrap();
    write_recording(tmp.path(), &[0, 1], "0\n1\n");
    write_depth_png16(tmp.path().join("depth/0002.png"), &depth(2)).unwrap();
    let msg = open_err(tmp.path()).to_string();
    assert!(
        msg.contains("0002.png: frame file names have 6 digits"),
        "{msg}"
    );

    // No frames at all; no depth folder.
    let tmp = tempfile::tempdir().unwrap();
    write_recording(tmp.path(), &[], "");
    let msg = open_err(tmp.path()).to_string();
    assert!(
        msg.ends_with("depth: no depth frames (expected 000000.png, 000001.png, …)"),
        "{msg}"
    );
    std::fs::remove_dir(tmp.path().join("depth")).unwrap();
    let e = open_err(tmp.path());
    assert!(
        matches!(e, KinectError::Io { ref file, .. } if file.ends_with("depth")),
        "{e}"
    );
}

#[test]
fn times_file_errors_name_the_file_and_line() {
    let cases: [(&str, usize, &str); 6] = [
        (
            "0\nabc\n0.2\n",
            2,
            "`abc` is not a number; expected the time of depth frame 1 in seconds",
        ),
        ("0\n0.1\nNaN\n", 3, "time `NaN` is not finite"),
        ("0\n1e400\n0.2\n", 2, "time `1e400` is not finite"),
        (
            "0\n0.1\n0.1\n",
            3,
            "time 0.1 s is not after the previous frame's 0.1 s (times must increase strictly)",
        ),
        (
            "0.5\n0.1\n0.7\n",
            2,
            "time 0.1 s is not after the previous frame's 0.5 s (times must increase strictly)",
        ),
        (
            "0\n\n0.2\n",
            2,
            "empty line; expected the time of depth frame 1 in seconds",
        ),
    ];
    for (text, line, message) in cases {
        let tmp = tempfile::tempdir().unwrap();
        write_recording(tmp.path(), &[0, 1, 2], text);
        let e = open_err(tmp.path());
        let file = tmp.path().join("depth_times.txt").display().to_string();
        assert_eq!(
            e.to_string(),
            format!("{file}:{line}: {message}"),
            "{text:?}"
        );
        assert!(matches!(e, KinectError::Parse { line: l, .. } if l == line));
    }
    // Fewer or more times than frames.
    for (text, n) in [("0\n", 1), ("0\n0.1\n", 2), ("0\n0.1\n0.2\n0.3\n", 4)] {
        let tmp = tempfile::tempdir().unwrap();
        write_recording(tmp.path(), &[0, 1, 2], text);
        let e = open_err(tmp.path());
        let file = tmp.path().join("depth_times.txt").display().to_string();
        assert_eq!(
            e.to_string(),
            format!(
                "{file}: {n} time{} for 3 depth frames (one line per frame)",
                if n == 1 { "" } else { "s" }
            )
        );
    }
    // Missing times file.
    let tmp = tempfile::tempdir().unwrap();
    write_recording(tmp.path(), &[0], "0\n");
    std::fs::remove_file(tmp.path().join("depth_times.txt")).unwrap();
    let e = open_err(tmp.path());
    assert!(
        matches!(e, KinectError::Io { ref file, .. } if file.ends_with("depth_times.txt")),
        "{e}"
    );
}

#[test]
fn intrinsics_are_checked_on_open() {
    let tmp = tempfile::tempdir().unwrap();
    write_recording(tmp.path(), &[0], "0\n");
    std::fs::write(
        tmp.path().join("intrinsics.json"),
        r#"{"format":"symcorr.intrinsics/1","width":8,"height":6,"fx":0.0,"fy":7.0,"cx":3.5,"cy":2.5}"#,
    )
    .unwrap();
    let e = open_err(tmp.path());
    assert!(
        matches!(e, KinectError::Json { ref file, .. } if file.ends_with("intrinsics.json")),
        "{e}"
    );
    std::fs::remove_file(tmp.path().join("intrinsics.json")).unwrap();
    let e = open_err(tmp.path());
    assert!(
        matches!(e, KinectError::Io { ref file, .. } if file.ends_with("intrinsics.json")),
        "{e}"
    );
}

#[test]
fn open_refuses_intrinsics_of_another_size_than_the_first_frame() {
    // Intrinsics of another depth mode (8x6 against frames of 4x3) would skip every frame.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    write_recording(dir, &[0, 1], "0\n1\n");
    for i in 0..2 {
        write_depth_png16(
            dir.join(format!("depth/{i:06}.png")),
            &DepthFrame::new(4, 3, vec![1; 12]).unwrap(),
        )
        .unwrap();
    }
    let e = open_err(dir);
    let file = dir.join("depth/000000.png").display().to_string();
    assert!(matches!(e, KinectError::Recording { .. }), "{e}");
    assert!(
        e.to_string().starts_with(&format!(
            "{file}: depth frame is 4x3, but intrinsics.json says 8x6: the intrinsics are another"
        )),
        "{e}"
    );
    // A first frame that is no PNG at all is that frame's problem, not the recording's.
    std::fs::write(dir.join("depth/000000.png"), b"not a png").unwrap();
    let rec = Recording::open(dir).unwrap();
    assert!(rec.frame(0).is_err() && rec.frame(1).is_err());
}

#[test]
fn open_decodes_no_frame_and_frame_checks_each_one() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    write_recording(dir, &[0, 1, 2], "0\n1\n2\n");
    // Frame 1 of another size, frame 2 not a PNG: the layout is still valid.
    write_depth_png16(
        dir.join("depth/000001.png"),
        &DepthFrame::new(4, 3, vec![1; 12]).unwrap(),
    )
    .unwrap();
    std::fs::write(dir.join("depth/000002.png"), b"not a png").unwrap();
    let rec = Recording::open(dir).unwrap();
    assert!(rec.frame(0).is_ok());
    let e = rec.frame(1).unwrap_err();
    let file = dir.join("depth/000001.png").display().to_string();
    assert_eq!(
        e.to_string(),
        format!("{file}: depth frame is 4x3, but intrinsics.json says 8x6")
    );
    let e = rec.frame(2).unwrap_err();
    assert!(
        matches!(e, KinectError::Png { ref file, .. } if file.ends_with("000002.png")),
        "{e}"
    );
}

// ---------------------------------------------------------------------------------------------
// Joints at a depth frame's time

/// A skeleton with every joint at `[x + 0.01·j, 1, 2]`.
fn line_skeleton(x: f64) -> Skeleton {
    let mut p = [[0.0; 3]; 20];
    for (j, q) in p.iter_mut().enumerate() {
        *q = [x + 0.01 * j as f64, 1.0, 2.0];
    }
    Skeleton::from_arrays(p)
}

fn log_at(times: &[f64], skeletons: Vec<Skeleton>) -> JointLog {
    JointLog {
        frames: times
            .iter()
            .zip(skeletons)
            .map(|(&time_s, skeleton)| JointFrame { time_s, skeleton })
            .collect(),
        ..JointLog::from_skeletons(vec![], 30.0)
    }
}

const P: f64 = 1.0 / 30.0;

#[test]
fn track_interpolates_linearly_between_the_nearest_frames() {
    let xs = [0.0, 0.3, 0.9, 1.2];
    let log = JointLog::from_skeletons(xs.iter().map(|&x| line_skeleton(x)).collect(), 30.0);
    let track = JointTrack::new(log, 0.0).unwrap();
    assert!((track.period_s() - P).abs() < 1e-12);

    // Exactly at a frame: that frame, not interpolated.
    let s = track.at(2.0 * P).unwrap();
    assert_eq!((s.before, s.after, s.interpolated), (2, 2, false));
    assert_eq!(s.skeleton, line_skeleton(0.9));

    // A quarter of the way from frame 1 to frame 2.
    let s = track.at(1.25 * P).unwrap();
    assert_eq!((s.before, s.after, s.interpolated), (1, 2, true));
    assert!((s.weight_after - 0.25).abs() < 1e-9);
    for j in 0..20 {
        let want = 0.3 + 0.25 * 0.6 + 0.01 * j as f64;
        assert!((s.skeleton.positions[j].x - want).abs() < 1e-9);
    }

    // With an offset: the log's clock runs 2 periods ahead of the depth clock.
    let shifted = JointTrack::new(track.log().clone(), 2.0 * P).unwrap();
    let s = shifted.at(-0.75 * P).unwrap();
    assert_eq!((s.before, s.after), (1, 2));
    assert!((s.log_time_s - 1.25 * P).abs() < 1e-12);
    assert_eq!(shifted.offset_s(), 2.0 * P);
}

/// Between a log frame and the next, where the tracker exchanged the legs, the legs are not
/// blended (halfway between the left and the right leg is neither): each leg joint is the
/// nearer frame's, the rest interpolated as usual.
#[test]
fn a_limb_pair_swapped_between_two_log_frames_is_not_blended() {
    let mut xyz = [[0.0, 1.0, 2.0]; 20];
    for j in Joint::ALL {
        let side = match j.name() {
            n if n.ends_with("left") => 0.15,
            n if n.ends_with("right") => -0.15,
            _ => 0.0,
        };
        xyz[j.index()] = [side, 1.0 - 0.05 * j.index() as f64, 2.0];
    }
    let a = Skeleton::from_arrays(xyz);
    let mut b = a.clone();
    for l in LimbPair::Legs.left_joints() {
        b.positions.swap(l.index(), l.mirror().index());
    }
    // The head moves 10 cm between the frames: still interpolated.
    b.positions[Joint::Head.index()].x += 0.1;
    let log = JointLog::from_skeletons(vec![a.clone(), b.clone()], 30.0);
    let track = JointTrack::new(log, 0.0).unwrap();
    for (w, near) in [(0.3, &a), (0.7, &b)] {
        let s = track.at(w * P).unwrap().skeleton;
        for l in LimbPair::Legs.left_joints() {
            for j in [l, l.mirror()] {
                assert_eq!(
                    s.positions[j.index()],
                    near.positions[j.index()],
                    "{j:?} at {w}"
                );
            }
        }
        let head = s.positions[Joint::Head.index()].x;
        assert!((head - 0.1 * w).abs() < 1e-9, "{head}");
        // The arms did not swap: blended (here equal in both frames).
        let hand = Joint::HandLeft.index();
        assert_eq!(s.positions[hand], a.positions[hand]);
    }
}

#[test]
fn track_skips_times_without_a_log_frame_nearby() {
    // Frames dropped between 2P and 10P; the median period stays P.
    let times = [0.0, P, 2.0 * P, 10.0 * P, 11.0 * P];
    let log = log_at(&times, (0..5).map(|i| line_skeleton(i as f64)).collect());
    let track = JointTrack::new(log, 0.0).unwrap();
    assert!((track.period_s() - P).abs() < 1e-12);
    match track.at(6.0 * P) {
        Err(SkipReason::NoSkeleton { nearest_gap_s }) => {
            assert!((nearest_gap_s - 4.0 * P).abs() < 1e-12)
        }
        other => panic!("{other:?}"),
    }
    // 1.2 periods after frame 2: only frame 2 is near enough; used alone.
    let s = track.at(3.2 * P).unwrap();
    assert_eq!((s.before, s.after, s.interpolated), (2, 2, false));
    assert_eq!(s.skeleton, line_skeleton(2.0));
    // Before the start and after the end: the end frame within 1.5 periods, else nothing.
    assert_eq!(track.at(-1.4 * P).unwrap().before, 0);
    assert!(matches!(
        track.at(-1.6 * P),
        Err(SkipReason::NoSkeleton { .. })
    ));
    assert_eq!(track.at(12.4 * P).unwrap().after, 4);
    assert!(matches!(
        track.at(12.6 * P),
        Err(SkipReason::NoSkeleton { .. })
    ));
    assert!(matches!(
        track.at(f64::NAN),
        Err(SkipReason::NoSkeleton { nearest_gap_s }) if nearest_gap_s.is_infinite()
    ));
    assert!(track
        .at(6.0 * P)
        .unwrap_err()
        .to_string()
        .starts_with("no joint log frame"));
}

#[test]
fn untracked_joints_and_confidence_in_interpolation() {
    let mut a = line_skeleton(0.0);
    let mut b = line_skeleton(0.3);
    a.confidence[Joint::Head.index()] = 0.4;
    b.confidence[Joint::Head.index()] = 0.9;
    a.confidence[Joint::HandLeft.index()] = 0.0; // lost in the earlier frame
    b.confidence[Joint::FootRight.index()] = 0.0; // lost in the later frame
    a.interpolated[Joint::FootRight.index()] = true;
    let track = JointTrack::new(
        JointLog::from_skeletons(vec![a.clone(), b.clone()], 30.0),
        0.0,
    )
    .unwrap();

    // 0.3 periods after a: a is within half a period, b is not.
    let s = track.at(0.3 * P).unwrap().skeleton;
    let head = Joint::Head.index();
    assert_eq!(s.confidence[head], 0.4); // the smaller
    assert!((s.positions[head].x - (0.03 + 0.3 * 0.3)).abs() < 1e-9);
    // Foot: tracked only in a, a is near → a's position, confidence and flag.
    let foot = Joint::FootRight.index();
    assert_eq!(s.positions[foot], a.positions[foot]);
    assert_eq!(s.confidence[foot], 1.0);
    assert!(s.interpolated[foot]);
    // Hand: tracked only in b, b is 0.7 periods away → untracked.
    let hand = Joint::HandLeft.index();
    assert_eq!(s.confidence[hand], 0.0);
    assert!((s.positions[hand].x - (0.07 + 0.3 * 0.3)).abs() < 1e-9);

    // 0.8 periods after a: the other way round.
    let s = track.at(0.8 * P).unwrap().skeleton;
    assert_eq!(s.positions[hand], b.positions[hand]);
    assert_eq!(s.confidence[hand], 1.0);
    // Foot: tracked (and flagged interpolated) only in a, now 0.8 periods away: untracked, and
    // no longer flagged, so that nothing takes its blended position for an estimate.
    assert_eq!(s.confidence[foot], 0.0);
    assert!(!s.interpolated[foot] && !s.tracks(Joint::FootRight));
}

#[test]
fn no_body_when_no_joint_is_tracked() {
    let mut lost = line_skeleton(0.0);
    lost.confidence = [0.0; 20];
    let log = JointLog::from_skeletons(vec![line_skeleton(0.0), lost.clone(), lost], 30.0);
    let track = JointTrack::new(log, 0.0).unwrap();
    assert_eq!(track.at(1.5 * P), Err(SkipReason::NoBody));
    assert_eq!(track.at(2.0 * P), Err(SkipReason::NoBody));
    // Between a tracked and a lost frame, nearer the tracked one: its joints.
    assert!(track.at(0.2 * P).is_ok());
    // Nearer the lost one: nothing is tracked.
    assert_eq!(track.at(0.8 * P), Err(SkipReason::NoBody));
}

#[test]
fn track_refuses_unusable_logs() {
    let e = JointTrack::new(log_at(&[], vec![]), 0.0).unwrap_err();
    assert_eq!(e.to_string(), "joint track: the joint log has no frames");
    // A frame repeated exactly (a logger writing the latest skeleton at every depth frame) is
    // dropped; two different skeletons at one time, or a time going back, are refused, naming
    // the frames by their index in the file.
    let log = log_at(&[0.0, 0.1, 0.1, 0.2], vec![line_skeleton(0.0); 4]);
    assert_eq!(JointTrack::new(log, 0.0).unwrap().log().frames.len(), 3);
    let at = line_skeleton;
    let log = log_at(
        &[0.0, 0.0, 0.1, 0.1],
        vec![at(0.0), at(0.0), at(0.0), at(0.5)],
    );
    let e = JointTrack::new(log, 0.0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "joint track: joint log frame 3 at 0.1 s is not after frame 2 at 0.1 s \
         (a track needs strictly increasing times)"
    );
    let log = log_at(&[0.0, f64::NAN], vec![line_skeleton(0.0); 2]);
    let e = JointTrack::new(log, 0.0).unwrap_err();
    assert_eq!(
        e.to_string(),
        "joint track: joint log frame 1 has time NaN s, not a finite number"
    );
    let log = JointLog::from_skeletons(vec![line_skeleton(0.0)], 30.0);
    assert!(matches!(
        JointTrack::new(log.clone(), f64::INFINITY),
        Err(KinectError::Track(_))
    ));
    // One frame: the period is the Kinect's 1/30 s.
    let track = JointTrack::new(log, 0.0).unwrap();
    assert!((track.period_s() - P).abs() < 1e-15);
    assert!(track.at(1.4 * P).is_ok());
    assert!(track.at(1.6 * P).is_err());
}

#[test]
fn binary_search_agrees_with_a_linear_scan() {
    // Irregular times (jittered 30 Hz with dropped frames), deterministic.
    let mut state = 0x1234_5678_u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut times = Vec::new();
    let mut t = 0.0;
    for _ in 0..300 {
        t += P * (0.8 + 0.4 * next()) * if next() < 0.1 { 3.0 } else { 1.0 };
        times.push(t);
    }
    let log = log_at(&times, times.iter().map(|&t| line_skeleton(t)).collect());
    let track = JointTrack::new(log, 0.0).unwrap();
    for _ in 0..2000 {
        let q = -0.1 + (t + 0.2) * next();
        let before = times.iter().rposition(|&x| x <= q);
        let after = times.iter().position(|&x| x > q);
        let near = |i: Option<usize>| i.filter(|&i| (times[i] - q).abs() <= 1.5 * track.period_s());
        match (track.at(q), near(before), near(after)) {
            (Err(SkipReason::NoSkeleton { .. }), None, None) => {}
            (Ok(s), b, a) => {
                let (want_b, want_a) = match (b, a) {
                    (Some(b), Some(_)) if times[b] == q => (b, b),
                    (Some(b), Some(a)) => (b, a),
                    (Some(i), None) | (None, Some(i)) => (i, i),
                    (None, None) => panic!("skeleton at {q} without a frame near"),
                };
                assert_eq!((s.before, s.after), (want_b, want_a), "at {q}");
                // Positions follow time linearly (x = frame time + 0.01 j).
                let x = s.skeleton.positions[0].x;
                let lo = times[want_b].min(q);
                let hi = times[want_a].max(q);
                assert!(x >= lo - 1e-12 && x <= hi + 1e-12);
            }
            (r, b, a) => panic!("at {q}: {r:?} with neighbours {b:?} {a:?}"),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// One-euro filter

/// The filter exactly as the paper's Algorithm 1 writes it: a low-pass filter object that keeps
/// its previous output, `alpha(rate, cutoff)`, and the derivative from the previous filtered
/// value; `rate` from the timestamps.
struct PaperLowPass {
    first: bool,
    hatxprev: f64,
}

impl PaperLowPass {
    fn new() -> Self {
        PaperLowPass {
            first: true,
            hatxprev: 0.0,
        }
    }
    fn filter(&mut self, x: f64, alpha: f64) -> f64 {
        let hatx = if self.first {
            self.first = false;
            x
        } else {
            alpha * x + (1.0 - alpha) * self.hatxprev
        };
        self.hatxprev = hatx;
        hatx
    }
}

struct PaperOneEuro {
    first: bool,
    mincutoff: f64,
    beta: f64,
    dcutoff: f64,
    xfilt: PaperLowPass,
    dxfilt: PaperLowPass,
    last_time: f64,
}

impl PaperOneEuro {
    fn alpha(rate: f64, cutoff: f64) -> f64 {
        let tau = 1.0 / (2.0 * std::f64::consts::PI * cutoff);
        let te = 1.0 / rate;
        1.0 / (1.0 + tau / te)
    }
    fn filter(&mut self, x: f64, timestamp: f64) -> f64 {
        let rate = if self.first {
            0.0
        } else {
            1.0 / (timestamp - self.last_time)
        };
        self.last_time = timestamp;
        let dx = if self.first {
            self.first = false;
            0.0
        } else {
            (x - self.xfilt.hatxprev) * rate
        };
        let edx = self.dxfilt.filter(dx, Self::alpha(rate, self.dcutoff));
        let cutoff = self.mincutoff + self.beta * edx.abs();
        self.xfilt.filter(x, Self::alpha(rate, cutoff))
    }
}

#[test]
fn one_euro_matches_the_papers_algorithm_step_by_step() {
    let xs = [
        0.0, 0.02, -0.01, 0.5, 0.52, 0.49, 0.9, 0.91, 0.3, 0.31, 0.305, 0.3,
    ];
    // Regular 30 Hz, then irregular times (a late frame, a dropped frame).
    let regular: Vec<f64> = (0..xs.len()).map(|i| i as f64 / 30.0).collect();
    let irregular = [
        0.0, 0.033, 0.07, 0.1, 0.167, 0.2, 0.233, 0.3, 0.31, 0.4, 0.433, 0.466,
    ];
    for (params, times) in [
        ((1.0, 5.0, 1.0), &regular[..]),
        ((1.0, 5.0, 1.0), &irregular[..]),
        ((0.3, 40.0, 2.5), &irregular[..]),
        ((2.0, 0.0, 1.0), &regular[..]),
    ] {
        let (mincutoff, beta, dcutoff) = params;
        let mut ours = OneEuroFilter::new(mincutoff, beta, dcutoff).unwrap();
        let mut paper = PaperOneEuro {
            first: true,
            mincutoff,
            beta,
            dcutoff,
            xfilt: PaperLowPass::new(),
            dxfilt: PaperLowPass::new(),
            last_time: 0.0,
        };
        for (&x, &t) in xs.iter().zip(times) {
            let (a, b) = (ours.filter(t, x), paper.filter(x, t));
            assert!((a - b).abs() < 1e-12, "{params:?} at {t}: {a} vs {b}");
        }
    }
}

#[test]
fn one_euro_keeps_a_constant_and_follows_a_step() {
    let mut f = OneEuroFilter::default();
    for i in 0..100 {
        assert_eq!(f.filter(i as f64 * P, 1.234), 1.234);
    }
    // A 30 cm jump (a hand moving fast): within 5 mm after 4 frames (measured 4.1 mm), never
    // overshooting.
    let mut f = OneEuroFilter::default();
    for i in 0..30 {
        f.filter(i as f64 * P, 0.0);
    }
    let out: Vec<f64> = (30..40).map(|i| f.filter(i as f64 * P, 0.3)).collect();
    assert!(out.windows(2).all(|w| w[1] >= w[0] && w[1] <= 0.3));
    assert!(0.3 - out[3] < 0.005, "{out:?}");
    // A fixed 1 Hz low-pass (beta = 0) lags far more (measured 11.6 cm short after 5 frames):
    // the speed term is what follows the step.
    let mut slow = OneEuroFilter::new(1.0, 0.0, 1.0).unwrap();
    for i in 0..30 {
        slow.filter(i as f64 * P, 0.0);
    }
    let y = (30..35)
        .map(|i| slow.filter(i as f64 * P, 0.3))
        .last()
        .unwrap();
    assert!(0.3 - y > 0.1, "{y}");
}

/// Standard normal samples, deterministic (Box–Muller on a 64-bit LCG).
fn gaussian(seed: u64, n: usize) -> Vec<f64> {
    let mut state = seed;
    let mut uniform = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let (u, v) = (uniform(), uniform());
            (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
        })
        .collect()
}

fn std_dev(v: &[f64]) -> f64 {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / v.len() as f64).sqrt()
}

#[test]
fn one_euro_reduces_jitter_at_rest() {
    // A joint standing still at 2 m with 1 cm white jitter, 100 s at 30 Hz.
    let noise = gaussian(7, 3000);
    let raw: Vec<f64> = noise.iter().map(|n| 2.0 + 0.01 * n).collect();
    let mut f = OneEuroFilter::default();
    let out: Vec<f64> = raw
        .iter()
        .enumerate()
        .map(|(i, &x)| f.filter(i as f64 * P, x))
        .collect();
    let factor = std_dev(&raw[30..]) / std_dev(&out[30..]);
    // Measured: 2.6 with the defaults (a fixed 1 Hz low-pass, beta = 0, gives 3.3).
    assert!(factor > 2.4, "jitter reduced only {factor:.2}×");
    let mut fixed = OneEuroFilter::new(1.0, 0.0, 1.0).unwrap();
    let out: Vec<f64> = raw
        .iter()
        .enumerate()
        .map(|(i, &x)| fixed.filter(i as f64 * P, x))
        .collect();
    let fixed_factor = std_dev(&raw[30..]) / std_dev(&out[30..]);
    assert!(
        fixed_factor >= factor && fixed_factor < 4.0,
        "{fixed_factor}"
    );
}

#[test]
fn one_euro_reset_restart_and_bad_parameters() {
    let mut f = OneEuroFilter::default();
    f.filter(0.0, 0.0);
    f.filter(P, 0.1);
    f.reset();
    assert_eq!(f.filter(2.0 * P, 5.0), 5.0);
    // A time not after the previous one restarts from the sample.
    assert_eq!(f.filter(2.0 * P, 7.0), 7.0);
    assert_eq!(f.filter(P, 8.0), 8.0);
    // A non-finite sample passes through and leaves the state alone.
    assert!(f.filter(3.0 * P, f64::NAN).is_nan());
    let y = f.filter(4.0 * P, 8.0);
    assert_eq!(y, 8.0);
    assert_eq!(OneEuroFilter::default(), OneEuroFilter::KINECT_30HZ);
    let d = OneEuroFilter::default();
    assert_eq!(
        (d.min_cutoff_hz(), d.beta(), d.d_cutoff_hz()),
        (1.0, 5.0, 1.0)
    );
    for (args, message) in [
        (
            (f64::NAN, 5.0, 1.0),
            "one-euro filter min_cutoff_hz = NaN: expected a finite number > 0",
        ),
        (
            (1.0, -1.0, 1.0),
            "one-euro filter beta = -1: expected a finite number ≥ 0",
        ),
        (
            (1.0, 5.0, f64::INFINITY),
            "one-euro filter d_cutoff_hz = inf: expected a finite number > 0",
        ),
    ] {
        let e = OneEuroFilter::new(args.0, args.1, args.2).unwrap_err();
        assert!(matches!(e, KinectError::FilterParameter { .. }));
        assert_eq!(e.to_string(), message);
    }
}

#[test]
fn skeleton_filter_filters_each_coordinate_alone() {
    let noise = gaussian(11, 60 * 20);
    let frames: Vec<Skeleton> = (0..20)
        .map(|i| {
            let mut s = line_skeleton(0.01 * i as f64);
            for (j, p) in s.positions.iter_mut().enumerate() {
                *p += Vector3::new(
                    noise[60 * i + 3 * j],
                    noise[60 * i + 3 * j + 1],
                    noise[60 * i + 3 * j + 2],
                ) * 0.01;
            }
            s.confidence[3] = 0.5;
            s
        })
        .collect();
    let mut sf = SkeletonFilter::new(OneEuroFilter::default());
    let mut scalar = vec![OneEuroFilter::default(); 60];
    for (i, s) in frames.iter().enumerate() {
        let t = i as f64 * P;
        let out = sf.filter(t, s);
        assert_eq!(out.confidence, s.confidence);
        for j in 0..20 {
            for c in 0..3 {
                assert_eq!(
                    out.positions[j][c],
                    scalar[3 * j + c].filter(t, s.positions[j][c])
                );
            }
        }
    }
    sf.reset();
    assert_eq!(sf.filter(100.0, &frames[0]), frames[0]);
}

// ---------------------------------------------------------------------------------------------
// Left/right swaps

/// A person facing the sensor (their left at −x, camera space), walking towards it at 1.2 m/s
/// with a 0.9 Hz stride: legs swing ±25° in opposition, arms ±20°, knees bend in the swing.
fn walker(t: f64) -> Skeleton {
    let phase = 2.0 * std::f64::consts::PI * 0.9 * t;
    let z = 3.5 - 1.2 * t;
    let mut p = [Point3::origin(); 20];
    let mut set = |j: Joint, q: Point3<f64>| p[j.index()] = q;
    set(Joint::HipCenter, Point3::new(0.0, 0.95, z));
    set(Joint::Spine, Point3::new(0.0, 1.15, z));
    set(Joint::ShoulderCenter, Point3::new(0.0, 1.42, z));
    set(Joint::Head, Point3::new(0.0, 1.62, z));
    // Swinging forward (towards the sensor) is −z; down is −y.
    let limb = |from: Point3<f64>, angle: f64, len: f64| {
        from + Vector3::new(0.0, -angle.cos(), -angle.sin()) * len
    };
    for (side, sign) in [(-1.0, 1.0), (1.0, -1.0)] {
        let left = side < 0.0;
        let pick = |l: Joint| if left { l } else { l.mirror() };
        let arm = 0.35 * -sign * phase.sin();
        let sh = Point3::new(0.19 * side, 1.40, z);
        let el = limb(sh, arm, 0.28);
        let wr = limb(el, arm + 0.2, 0.25);
        set(pick(Joint::ShoulderLeft), sh);
        set(pick(Joint::ElbowLeft), el);
        set(pick(Joint::WristLeft), wr);
        set(pick(Joint::HandLeft), limb(wr, arm + 0.2, 0.08));
        let leg = 0.44 * sign * phase.sin();
        let bend = 0.5 * (sign * phase.cos()).max(0.0);
        let hip = Point3::new(0.09 * side, 0.92, z);
        let knee = limb(hip, leg, 0.43);
        let ankle = limb(knee, leg - bend, 0.42);
        set(pick(Joint::HipLeft), hip);
        set(pick(Joint::KneeLeft), knee);
        set(pick(Joint::AnkleLeft), ankle);
        set(
            pick(Joint::FootLeft),
            ankle + Vector3::new(0.0, -0.05, -0.12),
        );
    }
    Skeleton::from_positions(p)
}

#[test]
fn a_swapped_frame_is_detected() {
    for i in 0..30 {
        let (prev, cur) = (walker(i as f64 * P), walker((i + 1) as f64 * P));
        let swapped = cur.swap_sides();
        let e = swap_evidence(&prev, &swapped);
        assert!(e > 0.9, "frame {i}: {e}");
        assert!(legs_swapped(&prev, &swapped) && arms_swapped(&prev, &swapped));
        // Only the legs exchanged.
        let legs = cur.swap_limbs(LimbPair::Legs);
        assert!(legs_swapped(&prev, &legs), "frame {i}");
        assert!(!arms_swapped(&prev, &legs), "frame {i}");
        assert!(limb_swap_evidence(&prev, &legs, LimbPair::Legs) > 0.7);
        // Back to normal after a swap: the next frame is swapped relative to the swapped one.
        assert!(legs_swapped(&legs, &walker((i + 2) as f64 * P)));
    }
}

#[test]
fn a_normal_walking_step_is_not_a_swap() {
    // A whole stride at 30 Hz, including the moments the legs and arms pass each other.
    let mut worst = f64::NEG_INFINITY;
    for i in 0..40 {
        let (prev, cur) = (walker(i as f64 * P), walker((i + 1) as f64 * P));
        let e = swap_evidence(&prev, &cur);
        worst = worst.max(e);
        assert!(
            !legs_swapped(&prev, &cur) && !arms_swapped(&prev, &cur),
            "frame {i}"
        );
        for pair in [LimbPair::Arms, LimbPair::Legs] {
            // Measured: legs at worst −0.78 (feet passing each other), arms −0.97.
            assert!(
                limb_swap_evidence(&prev, &cur, pair) < -0.7,
                "frame {i} {pair:?}"
            );
        }
    }
    // Measured: −0.93 over the whole limbs.
    assert!(worst < -0.9, "{worst}");
}

#[test]
fn a_body_turning_ten_degrees_is_not_a_swap() {
    let s = walker(0.3);
    let c = s.position(Joint::HipCenter);
    for angle in [10.0_f64, -10.0] {
        let r = Rotation3::from_axis_angle(&Vector3::y_axis(), angle.to_radians());
        let turned = s.map_positions(|p| c + r * (p - c));
        let e = swap_evidence(&s, &turned);
        assert!(e < -0.8, "{angle}°: {e}");
        assert!(!legs_swapped(&s, &turned) && !arms_swapped(&s, &turned));
    }
}

#[test]
fn swap_evidence_is_antisymmetric_and_ignores_untracked_joints() {
    let (a, b) = (walker(0.0), walker(P));
    let e = swap_evidence(&a, &b);
    assert!((swap_evidence(&a, &b.swap_sides()) + e).abs() < 1e-12);
    // Untracked limbs do not count; with none left there is no evidence.
    let mut lost = b.swap_sides();
    for l in LimbPair::Legs.left_joints() {
        lost.confidence[l.index()] = 0.0;
    }
    assert_eq!(limb_swap_evidence(&a, &lost, LimbPair::Legs), 0.0);
    assert!(!legs_swapped(&a, &lost));
    assert!(arms_swapped(&a, &lost));
}

/// The head's turn a log reports is read at a depth frame's time like a tracked joint: blended
/// between the two log frames around it, the near frame's alone when only one reports it (and
/// it is within half a period), none otherwise; the smoothing filters it and forgets it when a
/// frame reports none.
#[test]
fn a_reported_head_turn_is_blended_and_smoothed_like_a_joint() {
    let body = Skeleton::from_arrays(std::array::from_fn(|i| [0.01 * i as f64, 1.0, 2.5]));
    let with = |turn: Option<f64>| Skeleton {
        head_turn: turn,
        ..body.clone()
    };
    let log = JointLog::from_skeletons(vec![with(Some(0.2)), with(Some(0.4)), with(None)], 30.0);
    let track = JointTrack::new(log, 0.0).unwrap();
    let at = |t: f64| track.at(t).unwrap().skeleton.head_turn;
    assert!((at(1.0 / 60.0).unwrap() - 0.3).abs() < 1e-12);
    assert_eq!(at(1.0 / 30.0 + 0.01), Some(0.4));
    assert_eq!(at(1.0 / 30.0 + 0.02), None);
    let mut filter = SkeletonFilter::new(OneEuroFilter::default());
    for i in 0..5 {
        let out = filter.filter(i as f64 / 30.0, &with(Some(0.5)));
        assert!((out.head_turn.unwrap() - 0.5).abs() < 1e-12);
    }
    // A jump is followed part of the way, as a joint's is.
    let jumped = filter
        .filter(5.0 / 30.0, &with(Some(0.9)))
        .head_turn
        .unwrap();
    assert!(jumped > 0.5 && jumped < 0.9, "{jumped}");
    assert_eq!(filter.filter(6.0 / 30.0, &with(None)).head_turn, None);
    // Forgotten: the next reported turn passes through.
    let fresh = filter
        .filter(7.0 / 30.0, &with(Some(-0.2)))
        .head_turn
        .unwrap();
    assert!((fresh + 0.2).abs() < 1e-12, "{fresh}");
}
