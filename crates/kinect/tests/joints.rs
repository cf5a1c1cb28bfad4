//! Joint importers against the hand-made fixtures in fixtures/kinect (see make_fixtures.py there).

use approx::assert_abs_diff_eq;
use std::path::PathBuf;
use symcorr_kinect::joints::{
    parse_joints, parse_joints_as, parse_joints_json, read_ntu_skeleton, to_json_string,
    BodySelect, JointFormat,
};
use symcorr_kinect::sdk_text::{parse_kinect_text, to_kinect_text};
use symcorr_kinect::{
    read_joints, read_joints_with_format, write_joints_json, JointFrame, JointLog, KinectError,
    SkeletonKind,
};
use symcorr_skeleton::{Joint, Skeleton};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/kinect")
        .join(name)
}

fn close(a: impl Into<[f64; 3]>, b: impl Into<[f64; 3]>) -> bool {
    let (a, b) = (a.into(), b.into());
    (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9)
}

#[test]
fn kinect_v1_json_fixture_reads_all_frames() {
    let log = read_joints(fixture("standing_v1.json")).unwrap();
    assert_eq!(log.skeleton_kind, SkeletonKind::KinectV1);
    assert_eq!(log.frames.len(), 3);
    let f1 = &log.frames[1];
    assert_abs_diff_eq!(f1.time_s, 1.0 / 30.0, epsilon = 1e-12);
    assert!(close(
        f1.skeleton.position(Joint::HipCenter),
        [0.01, 0.0, 2.5]
    ));
    assert!(close(
        f1.skeleton.position(Joint::ShoulderRight),
        [0.19, 0.45, 2.5]
    ));
    assert_eq!(f1.skeleton.confidence[Joint::Head.index()], 0.5);
    assert_eq!(f1.skeleton.confidence[Joint::Spine.index()], 1.0);
    assert!(f1.skeleton.interpolated.iter().all(|b| !b));
}

#[test]
fn nite_json_maps_fifteen_joints_and_flags_interpolated_ones() {
    let v1 = read_joints(fixture("standing_v1.json")).unwrap().frames[0]
        .skeleton
        .clone();
    let log = read_joints(fixture("standing_nite.json")).unwrap();
    assert_eq!(log.skeleton_kind, SkeletonKind::Nite);
    let s = &log.frames[0].skeleton;
    // Measured joints (millimetres converted to metres), including the `left_elbow` alias.
    for j in [
        Joint::Head,
        Joint::ShoulderCenter,
        Joint::Spine,
        Joint::ElbowLeft,
        Joint::HandRight,
        Joint::KneeLeft,
        Joint::AnkleRight,
    ] {
        assert!(close(s.position(j), v1.position(j)), "{j:?}");
        assert!(!s.interpolated[j.index()], "{j:?}");
    }
    let flagged: Vec<Joint> = Joint::ALL
        .into_iter()
        .filter(|j| s.interpolated[j.index()])
        .collect();
    assert_eq!(
        flagged,
        vec![
            Joint::HipCenter,
            Joint::WristLeft,
            Joint::WristRight,
            Joint::FootLeft,
            Joint::FootRight
        ]
    );
    assert!(close(
        s.position(Joint::HipCenter),
        nalgebra::center(&v1.position(Joint::HipLeft), &v1.position(Joint::HipRight))
    ));
    // Feet are extrapolated in front of (the subject faces the sensor: −z) and below the ankle,
    // 0.3 and 0.18 shin lengths; the standing fixture's up is +y.
    for (k, a, f) in [
        (Joint::KneeLeft, Joint::AnkleLeft, Joint::FootLeft),
        (Joint::KneeRight, Joint::AnkleRight, Joint::FootRight),
    ] {
        let shin = nalgebra::distance(&s.position(k), &s.position(a));
        let d = [0, 1, 2].map(|c| (s.position(f)[c] - s.position(a)[c]) / shin);
        assert!(
            (d[2] + 0.3).abs() < 0.03,
            "foot not in front of ankle: {d:?}"
        );
        assert!(
            (d[1] + 0.18).abs() < 0.03,
            "foot not below the ankle: {d:?}"
        );
        assert!(d[0].abs() < 0.05, "{d:?}");
        assert!(s.confidence[f.index()] <= 0.5);
    }
    // Wrist at 80 % elbow → hand.
    let (e, h) = (s.position(Joint::ElbowLeft), s.position(Joint::HandLeft));
    let w = s.position(Joint::WristLeft);
    assert!(close(w, [0, 1, 2].map(|k| e[k] + 0.8 * (h[k] - e[k]))));
}

#[test]
fn kinect_text_fixture_interpolates_untracked_joint() {
    let log = read_joints(fixture("standing_v1.txt")).unwrap();
    assert_eq!(log.frames.len(), 2);
    assert_abs_diff_eq!(log.frames[0].time_s, 10.0 / 30.0, epsilon = 1e-12);
    assert_abs_diff_eq!(log.frames[1].time_s, 11.0 / 30.0, epsilon = 1e-12);
    let s0 = &log.frames[0].skeleton;
    assert!(s0.interpolated.iter().all(|b| !b));
    assert!(close(s0.position(Joint::WristRight), [0.24, -0.06, 2.48]));
    let s1 = &log.frames[1].skeleton;
    let wr = Joint::WristRight.index();
    assert!(s1.interpolated[wr]);
    assert!(s1.confidence[wr] < 1.0);
    let (e, h) = (
        s1.position(Joint::ElbowRight),
        s1.position(Joint::HandRight),
    );
    assert!(close(
        s1.position(Joint::WristRight),
        [0, 1, 2].map(|k| e[k] + 0.8 * (h[k] - e[k]))
    ));
}

#[test]
fn ntu_skeleton_picks_the_most_tracked_body_or_a_given_id() {
    let log = read_joints(fixture("two_bodies.skeleton")).unwrap();
    assert_eq!(log.skeleton_kind, SkeletonKind::KinectV2);
    // Body A is only in frame 1 (frame 0 has no body, frame 2 only body B).
    assert_eq!(log.frames.len(), 1);
    assert_abs_diff_eq!(log.frames[0].time_s, 1.0 / 30.0, epsilon = 1e-12);
    let v1 = read_joints(fixture("standing_v1.json")).unwrap().frames[0]
        .skeleton
        .clone();
    for j in Joint::ALL {
        // spine_shoulder → shoulder_center, spine_base → hip_center, spine_mid → spine.
        assert!(
            (0..3)
                .all(|k| (log.frames[0].skeleton.position(j)[k] - v1.position(j)[k]).abs() < 1e-6),
            "{j:?}"
        );
        assert_eq!(log.frames[0].skeleton.confidence[j.index()], 1.0);
    }
    let b = read_ntu_skeleton(
        fixture("two_bodies.skeleton"),
        BodySelect::Id(72057594037931102),
    )
    .unwrap();
    assert_eq!(b.frames.len(), 2);
    // Frame 1: body B tracks only Kinect v2 joints 0..3 (state 2), others state 0; frame 2: all
    // inferred (state 1).
    assert_eq!(b.frames[0].skeleton.confidence[Joint::Spine.index()], 1.0);
    assert_eq!(b.frames[0].skeleton.confidence[Joint::Head.index()], 0.0);
    assert_eq!(
        b.frames[0].skeleton.confidence[Joint::ElbowLeft.index()],
        0.0
    );
    assert_eq!(b.frames[1].skeleton.confidence[Joint::Head.index()], 0.5);
    assert!(close(
        b.frames[1].skeleton.position(Joint::HipCenter),
        [1.0, 0.0, 3.5]
    ));
    let none = read_ntu_skeleton(fixture("two_bodies.skeleton"), BodySelect::Id(7));
    assert!(matches!(none, Err(KinectError::NoBody { .. })), "{none:?}");
}

#[test]
fn format_is_detected_from_content() {
    for (name, f) in [
        ("standing_v1.json", JointFormat::Json),
        ("standing_nite.json", JointFormat::Json),
        ("standing_v1.txt", JointFormat::KinectText),
        ("two_bodies.skeleton", JointFormat::NtuSkeleton),
    ] {
        let text = std::fs::read_to_string(fixture(name)).unwrap();
        assert_eq!(JointFormat::detect(&text), Some(f), "{name}");
        assert_eq!(parse_joints(&text, name).unwrap().1, f);
    }
    assert!(matches!(
        parse_joints("hello world\n", "x.txt"),
        Err(KinectError::UnknownFormat { .. })
    ));
    assert_eq!(JointFormat::detect("  \u{feff}\n"), None);
    // Forcing the wrong format is a parse error, not a panic.
    let e =
        read_joints_with_format(fixture("standing_v1.txt"), JointFormat::NtuSkeleton).unwrap_err();
    assert!(matches!(e, KinectError::Parse { line: 1, .. }), "{e}");
    assert_eq!(
        JointFormat::from_name("kinect_text"),
        Some(JointFormat::KinectText)
    );
    assert_eq!(
        JointFormat::from_name("ntu"),
        Some(JointFormat::NtuSkeleton)
    );
    assert_eq!(JointFormat::from_name("nope"), None);
}

#[test]
fn json_write_then_read_is_identity_and_keeps_interpolation_flags() {
    let mut log = read_joints(fixture("standing_nite.json")).unwrap();
    log.skeleton_kind = SkeletonKind::KinectV1; // the writer writes the canonical skeleton
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.json");
    write_joints_json(&path, &log).unwrap();
    let back = read_joints(&path).unwrap();
    assert_eq!(back, log);
    // No temporary file left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // Writing into a missing directory is an Io error naming the file.
    let e = write_joints_json(dir.path().join("no/such/dir/x.json"), &log).unwrap_err();
    assert!(e.to_string().contains("x.json"), "{e}");
}

fn v1_json(frame_joints: &str) -> String {
    format!(
        r#"{{"format":"symcorr.joints/1","skeleton":"kinect_v1","units":"m","frames":[{frame_joints}]}}"#
    )
}

fn full_joints_except(skip: &str) -> String {
    Joint::ALL
        .iter()
        .filter(|j| j.name() != skip)
        .map(|j| format!("\"{}\":[0.1,0.2,2.0]", j.name()))
        .collect::<Vec<_>>()
        .join(",")
}

#[test]
fn bad_json_gives_typed_errors_naming_file_and_frame() {
    let ok_frame = format!(r#"{{"joints":{{{}}}}}"#, full_joints_except(""));
    assert!(parse_joints_json_ok(&v1_json(&ok_frame)));

    let missing = format!(r#"{{"joints":{{{}}}}}"#, full_joints_except("knee_left"));
    let e = parse_joints(&v1_json(&format!("{ok_frame},{missing}")), "a.json").unwrap_err();
    assert!(matches!(e, KinectError::Frame { frame: 1, .. }), "{e}");
    assert!(
        e.to_string().contains("a.json") && e.to_string().contains("knee_left"),
        "{e}"
    );

    let e = parse_joints(
        &v1_json(&ok_frame).replace("kinect_v1", "kinect_v9"),
        "a.json",
    )
    .unwrap_err();
    assert!(
        matches!(e, KinectError::UnknownSkeleton { ref name, .. } if name == "kinect_v9"),
        "{e}"
    );

    let e = parse_joints(
        &v1_json(&ok_frame).replace("joints/1", "joints/2"),
        "a.json",
    )
    .unwrap_err();
    assert!(matches!(e, KinectError::Json { .. }), "{e}");

    let bad = ok_frame.replacen("[0.1,0.2,2.0]", "[0.1,null,2.0]", 1);
    let e = parse_joints(&v1_json(&bad), "a.json").unwrap_err();
    assert!(matches!(e, KinectError::Frame { frame: 0, .. }), "{e}");

    let bad = ok_frame.replacen("[0.1,0.2,2.0]", "[0.1,2.0]", 1);
    assert!(matches!(
        parse_joints(&v1_json(&bad), "a.json"),
        Err(KinectError::Frame { .. })
    ));

    let bad = ok_frame.replacen("\"hip_center\"", "\"tail\"", 1);
    let e = parse_joints(&v1_json(&bad), "a.json").unwrap_err();
    assert!(e.to_string().contains("tail"), "{e}");

    let bad = format!(
        r#"{{"joints":{{{}}},"confidence":{{"head":1.5}}}}"#,
        full_joints_except("")
    );
    assert!(matches!(
        parse_joints(&v1_json(&bad), "a.json"),
        Err(KinectError::Frame { .. })
    ));

    let e = parse_joints(&v1_json(""), "a.json").unwrap_err();
    assert!(matches!(e, KinectError::NoBody { .. }), "{e}");

    let truncated = &v1_json(&ok_frame)[..60];
    assert!(matches!(
        parse_joints(truncated, "a.json"),
        Err(KinectError::Json { .. })
    ));

    // A nite frame naming only its head: what nothing tracked can estimate is untracked.
    let nite =
        r#"{"format":"symcorr.joints/1","skeleton":"nite","frames":[{"joints":{"head":[0,1,2]}}]}"#;
    let (log, _) = parse_joints(nite, "n.json").unwrap();
    let s = &log.frames[0].skeleton;
    assert_eq!(s.confidence[Joint::Head.index()], 1.0);
    let untracked = Joint::ALL.into_iter().filter(|&j| j != Joint::Head);
    assert!(untracked
        .into_iter()
        .all(|j| s.confidence[j.index()] == 0.0));
    // A log in which no frame tracks a joint has no body.
    let nite = nite.replace("\"joints\"", "\"confidence\":{\"head\":0},\"joints\"");
    let e = parse_joints(&nite, "n.json").unwrap_err();
    assert!(matches!(e, KinectError::NoBody { .. }), "{e}");
}

fn parse_joints_json_ok(text: &str) -> bool {
    parse_joints(text, "a.json").is_ok()
}

#[test]
fn kinect_v2_json_uses_neck_when_spine_shoulder_is_missing() {
    let v2 = symcorr_kinect::mapping::KINECT_V2_NAMES;
    let joints: Vec<String> = v2
        .iter()
        .enumerate()
        .filter(|(_, n)| **n != "spine_shoulder")
        .map(|(i, n)| format!("\"{n}\":[{},{},2.0]", 0.01 * i as f64, 0.02 * i as f64))
        .collect();
    let text = format!(
        r#"{{"format":"symcorr.joints/1","skeleton":"kinect_v2","frames":[{{"joints":{{{}}}}}]}}"#,
        joints.join(",")
    );
    let log = parse_joints(&text, "v2.json").unwrap().0;
    let s = &log.frames[0].skeleton;
    assert!(close(s.position(Joint::ShoulderCenter), [0.02, 0.04, 2.0])); // neck = index 2
    assert!(close(s.position(Joint::Head), [0.03, 0.06, 2.0]));
    assert!(close(s.position(Joint::FootRight), [0.19, 0.38, 2.0]));
    assert!(s.interpolated.iter().all(|b| !b));
}

#[test]
fn bad_text_dumps_name_the_line() {
    let good = std::fs::read_to_string(fixture("standing_v1.txt")).unwrap();
    let lines: Vec<&str> = good.lines().collect();
    // NaN on line 3.
    let bad = format!(
        "{}\n{}\n{}\n",
        lines[0],
        lines[1],
        lines[2].replacen("2.500000", "nan", 1)
    );
    let e = parse_kinect_text(&bad, "k.txt").unwrap_err();
    assert!(matches!(e, KinectError::Parse { line: 3, .. }), "{e}");
    assert!(e.to_string().starts_with("k.txt:3:"), "{e}");
    // Wrong value count (a truncated last line).
    let bad = format!("{}\n{}\n{}\n", lines[0], lines[1], &lines[2][..100]);
    assert!(matches!(
        parse_kinect_text(&bad, "k.txt"),
        Err(KinectError::Parse { line: 3, .. })
    ));
    // Too many values.
    let bad = format!("{} 1.0\n", lines[1]);
    assert!(matches!(
        parse_kinect_text(&bad, "k.txt"),
        Err(KinectError::Parse { line: 1, .. })
    ));
    // Empty.
    assert!(matches!(
        parse_kinect_text("# nothing\n", "k.txt"),
        Err(KinectError::NoBody { .. })
    ));
    // All-zero joints: a frame without a body, and no other frame.
    let zeros = format!("0{}\n", " 0".repeat(60));
    assert!(matches!(
        parse_joints(&zeros, "k.txt"),
        Err(KinectError::NoBody { .. })
    ));
}

#[test]
fn bad_ntu_files_name_the_line() {
    let good = std::fs::read_to_string(fixture("two_bodies.skeleton")).unwrap();
    let lines: Vec<&str> = good.lines().collect();
    let parse = |t: &str| {
        parse_joints_as(
            t,
            "n.skeleton",
            JointFormat::NtuSkeleton,
            BodySelect::MostTracked,
        )
    };
    // Truncated in the middle of body A's joints (line 20).
    let e = parse(&lines[..20].join("\n")).unwrap_err();
    assert!(matches!(e, KinectError::Parse { line: 21, .. }), "{e}");
    // Wrong joint count.
    let mut l = lines.clone();
    assert_eq!(l[4], "25");
    l[4] = "20";
    let e = parse(&l.join("\n")).unwrap_err();
    assert!(matches!(e, KinectError::Parse { line: 5, .. }), "{e}");
    // Bad tracking state.
    let mut l: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    l[5] = l[5]
        .replacen(" 2", " 7", 1)
        .trim_end_matches('2')
        .to_string()
        + "7";
    let e = parse(&l.join("\n")).unwrap_err();
    assert!(matches!(e, KinectError::Parse { line: 6, .. }), "{e}");
    // Trailing data.
    let e = parse(&format!("{good}1\n")).unwrap_err();
    assert!(e.to_string().contains("trailing"), "{e}");
    // No body at all.
    assert!(matches!(
        parse("2\n0\n0\n"),
        Err(KinectError::NoBody { .. })
    ));
}

fn skeleton(seed: u64) -> Skeleton {
    let mut positions = [[0.0; 3]; 20];
    for (i, p) in positions.iter_mut().enumerate() {
        let t = (seed as f64) * 0.37 + i as f64;
        *p = [t.sin(), t.cos(), 2.0 + 0.1 * i as f64];
    }
    Skeleton::from_arrays(positions)
}

#[test]
fn text_writer_round_trips_positions() {
    let log = JointLog {
        skeleton_kind: SkeletonKind::KinectV1,
        frames: (0..3)
            .map(|i| JointFrame {
                time_s: i as f64 / 30.0,
                skeleton: skeleton(i),
            })
            .collect(),
    };
    let back = parse_kinect_text(&to_kinect_text(&log), "<memory>").unwrap();
    assert_eq!(back, log);
    let json = to_json_string(&log);
    assert!(json.starts_with(r#"{"format":"symcorr.joints/1","skeleton":"kinect_v1","units":"m""#));
}

mod props {
    use super::*;
    use proptest::prelude::*;

    fn arb_skeleton(text: bool) -> impl Strategy<Value = Skeleton> {
        let coord = if text { -5.0..5.0f64 } else { -1e6..1e6f64 };
        (
            proptest::array::uniform20(proptest::array::uniform3(coord)),
            proptest::array::uniform20(0.0..=1.0f64),
            proptest::array::uniform20(any::<bool>()),
        )
            .prop_map(move |(mut positions, confidence, interpolated)| {
                // The text format writes untracked joints as 0 0 0; keep z away from 0.
                for p in positions.iter_mut() {
                    p[2] = p[2].abs() + 0.5;
                }
                if text {
                    Skeleton::from_arrays(positions)
                } else {
                    Skeleton {
                        positions: positions.map(Into::into),
                        confidence,
                        interpolated,
                        head_turn: None,
                    }
                }
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn json_round_trip(frames in proptest::collection::vec((0.0..1e4f64, arb_skeleton(false)), 1..5)) {
            let log = JointLog {
                skeleton_kind: SkeletonKind::KinectV1,
                frames: frames.into_iter().map(|(time_s, skeleton)| JointFrame { time_s, skeleton }).collect(),
            };
            let (back, format) = parse_joints(&to_json_string(&log), "<memory>").unwrap();
            prop_assert_eq!(format, JointFormat::Json);
            prop_assert_eq!(back, log);
        }

        #[test]
        fn kinect_text_round_trip(frames in proptest::collection::vec((0u32..100_000, arb_skeleton(true)), 1..5)) {
            let log = JointLog {
                skeleton_kind: SkeletonKind::KinectV1,
                frames: frames.into_iter().map(|(f, skeleton)| JointFrame { time_s: f as f64 / 30.0, skeleton }).collect(),
            };
            let text = to_kinect_text(&log);
            let (back, format) = parse_joints(&text, "<memory>").unwrap();
            prop_assert_eq!(format, JointFormat::KinectText);
            prop_assert_eq!(back.frames.len(), log.frames.len());
            for (a, b) in back.frames.iter().zip(&log.frames) {
                prop_assert_eq!(a.skeleton.positions, b.skeleton.positions);
                prop_assert!((a.time_s - b.time_s).abs() < 1e-9);
            }
        }

        /// Written as the Azure Kinect SDK writes it and read back: every frame at its time (to
        /// the microsecond), its joints where they were (to a nanometre: the file holds
        /// millimetres), tracked; a frame without a body stays one.
        #[test]
        fn azure_kinect_round_trip(
            frames in proptest::collection::vec((0u64..10_000_000_000, arb_skeleton(true), any::<bool>()), 1..5)
        ) {
            let log = JointLog {
                skeleton_kind: SkeletonKind::KinectV1,
                frames: frames
                    .into_iter()
                    .map(|(us, mut skeleton, lost)| {
                        if lost {
                            skeleton.confidence = [0.0; 20];
                        }
                        JointFrame { time_s: us as f64 * 1e-6, skeleton }
                    })
                    .collect(),
            };
            let text = symcorr_kinect::k4abt::to_k4abt_json(&log);
            let result = parse_joints(&text, "<memory>");
            if !log.frames.iter().any(|f| f.skeleton.tracks_any()) {
                prop_assert!(matches!(result, Err(KinectError::NoBody { .. })), "{:?}", result);
                return Ok(());
            }
            let (back, format) = result.unwrap();
            prop_assert_eq!(format, JointFormat::AzureKinect);
            prop_assert_eq!(back.frames.len(), log.frames.len());
            for (a, b) in back.frames.iter().zip(&log.frames) {
                prop_assert!((a.time_s - b.time_s).abs() < 1e-9);
                prop_assert_eq!(a.skeleton.tracks_any(), b.skeleton.tracks_any());
                if b.skeleton.tracks_any() {
                    for j in Joint::ALL {
                        prop_assert!(close(a.skeleton.position(j), b.skeleton.position(j)));
                        prop_assert_eq!(a.skeleton.confidence[j.index()], 1.0);
                    }
                }
            }
        }
    }
}

/// A NiTE frame (15 joints) at time `t` of a subject standing 2 m from the sensor, facing it,
/// every joint tracked; `set` overrides joints by name (position, confidence).
fn nite_frame(t: f64, set: &[(&str, [f64; 3], f64)]) -> String {
    let standing = [
        ("head", [0.0, 0.6, 2.0]),
        ("neck", [0.0, 0.4, 2.0]),
        ("torso", [0.0, 0.1, 2.0]),
        ("shoulder_left", [-0.2, 0.4, 2.0]),
        ("shoulder_right", [0.2, 0.4, 2.0]),
        ("elbow_left", [-0.3, 0.1, 2.0]),
        ("elbow_right", [0.3, 0.1, 2.0]),
        ("hand_left", [-0.3, -0.2, 2.0]),
        ("hand_right", [0.3, -0.2, 2.0]),
        ("hip_left", [-0.1, -0.2, 2.0]),
        ("hip_right", [0.1, -0.2, 2.0]),
        ("knee_left", [-0.1, -0.6, 2.0]),
        ("knee_right", [0.1, -0.6, 2.0]),
        ("foot_left", [-0.1, -1.0, 2.0]),
        ("foot_right", [0.1, -1.0, 2.0]),
    ];
    let (mut joints, mut conf) = (Vec::new(), Vec::new());
    for (name, p) in standing {
        let (p, c) = set
            .iter()
            .find(|s| s.0 == name)
            .map_or((p, 1.0), |s| (s.1, s.2));
        joints.push(format!("\"{name}\":[{},{},{}]", p[0], p[1], p[2]));
        conf.push(format!("\"{name}\":{c}"));
    }
    format!(
        r#"{{"time_s":{t},"joints":{{{}}},"confidence":{{{}}}}}"#,
        joints.join(","),
        conf.join(",")
    )
}

#[test]
fn a_lost_body_or_an_untracked_hip_leaves_joints_untracked_not_the_log_unreadable() {
    let lost: Vec<_> = symcorr_kinect::mapping::NITE_NAMES
        .iter()
        .map(|&n| (n, [0.0; 3], 0.0))
        .collect();
    let frames = [
        nite_frame(0.0, &[]),
        // The tracker lost the body: every joint at the origin with confidence 0.
        nite_frame(1.0 / 30.0, &lost),
        // The left hip untracked: no hip centre, so no facing from the hips.
        nite_frame(2.0 / 30.0, &[("hip_left", [0.0; 3], 0.0)]),
    ];
    let text = format!(
        r#"{{"format":"symcorr.joints/1","skeleton":"nite","frames":[{}]}}"#,
        frames.join(",")
    );
    let (log, _) = parse_joints(&text, "lost.json").unwrap();
    assert_eq!(log.frames.len(), 3);
    let tracked = &log.frames[0].skeleton;
    assert!(tracked.confidence.iter().all(|&c| c > 0.0));
    let lost = &log.frames[1].skeleton;
    assert!(lost.confidence.iter().all(|&c| c == 0.0), "{lost:?}");
    assert!(lost.interpolated.iter().all(|&i| !i), "{lost:?}");
    let hip = &log.frames[2].skeleton;
    for j in [Joint::HipLeft, Joint::HipCenter] {
        assert_eq!(hip.confidence[j.index()], 0.0, "{j:?}");
        assert!(!hip.interpolated[j.index()], "{j:?}");
    }
    // Facing comes from the shoulders instead: the feet still point at the camera (−z).
    for (a, f) in [
        (Joint::AnkleLeft, Joint::FootLeft),
        (Joint::AnkleRight, Joint::FootRight),
    ] {
        assert!(hip.interpolated[f.index()] && hip.confidence[f.index()] > 0.0);
        assert!(hip.position(f).z < hip.position(a).z - 0.05, "{f:?}");
    }
    // The same in a Kinect SDK text dump: a line of zeros, and a line with one hip at zero.
    let line = |zero: &dyn Fn(Joint) -> bool, n: u32| {
        let mut l = n.to_string();
        for j in Joint::ALL {
            let p = if zero(j) {
                [0.0; 3]
            } else {
                tracked.position(j).into()
            };
            l += &format!(" {} {} {}", p[0], p[1], p[2]);
        }
        l
    };
    let dump = [
        line(&|_| false, 0),
        line(&|_| true, 1),
        line(&|j| j == Joint::HipRight, 2),
    ]
    .join("\n");
    let (log, _) = parse_joints(&dump, "lost.txt").unwrap();
    assert!(log.frames[0].skeleton.confidence.iter().all(|&c| c > 0.0));
    assert!(log.frames[1].skeleton.confidence.iter().all(|&c| c == 0.0));
    let s = &log.frames[2].skeleton;
    assert_eq!(s.confidence[Joint::HipRight.index()], 0.0);
    assert_eq!(
        s.confidence.iter().filter(|&&c| c == 0.0).count(),
        1,
        "{s:?}"
    );
}

/// A tracker that swapped the legs (a subject turned sideways) gives hips whose left is on the
/// right: feet estimated from them would point backwards. They come from the shoulders.
#[test]
fn estimated_feet_point_forward_when_the_tracker_swapped_the_legs() {
    let swapped = [
        ("hip_left", [0.1, -0.2, 2.0], 1.0),
        ("hip_right", [-0.1, -0.2, 2.0], 1.0),
        ("knee_left", [0.1, -0.6, 2.0], 1.0),
        ("knee_right", [-0.1, -0.6, 2.0], 1.0),
        ("foot_left", [0.1, -1.0, 2.0], 1.0),
        ("foot_right", [-0.1, -1.0, 2.0], 1.0),
    ];
    let text = format!(
        r#"{{"format":"symcorr.joints/1","skeleton":"nite","frames":[{}]}}"#,
        nite_frame(0.0, &swapped)
    );
    let (log, _) = parse_joints(&text, "swapped.json").unwrap();
    let s = &log.frames[0].skeleton;
    for (a, f) in [
        (Joint::AnkleLeft, Joint::FootLeft),
        (Joint::AnkleRight, Joint::FootRight),
    ] {
        // The subject faces the sensor: forward is −z.
        assert!(
            s.tracks(f) && s.interpolated[f.index()],
            "{f:?} not estimated"
        );
        assert!(
            s.position(f).z < s.position(a).z - 0.05,
            "{f:?} points backwards"
        );
    }
}

#[test]
fn interpolation_overflow_is_an_error_not_an_infinite_joint() {
    // NiTE hips at ±1e308: their midpoint (hip_center) overflows while interpolating.
    let nite = r#"{"format":"symcorr.joints/1","skeleton":"nite","frames":[{"joints":{
        "head":[0,1,2],"neck":[0,0.8,2],"torso":[0,0.5,2],
        "shoulder_left":[-0.2,0.8,2],"shoulder_right":[0.2,0.8,2],
        "elbow_left":[-0.3,0.5,2],"elbow_right":[0.3,0.5,2],
        "hand_left":[-0.3,0.2,2],"hand_right":[0.3,0.2,2],
        "hip_left":[-1e308,0,2],"hip_right":[1e308,0,2],
        "knee_left":[-0.1,-0.4,2],"knee_right":[0.1,-0.4,2],
        "foot_left":[-0.1,-0.8,2],"foot_right":[0.1,-0.8,2]}}]}"#;
    let e = parse_joints(nite, "n.json").unwrap_err();
    assert!(matches!(e, KinectError::Frame { frame: 0, .. }), "{e}");
}

/// Every `symcorr.joints/1` file under fixtures/ (recursively).
fn fixture_joint_files() -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut dirs = vec![PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures")];
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.extension().is_some_and(|x| x == "json")
                && std::fs::read_to_string(&p)
                    .unwrap()
                    .contains("symcorr.joints/1")
            {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The typed reader gives exactly the numbers written in the bundled files: every
/// `kinect_v1` file's coordinates (times the unit), times, confidences and interpolation flags,
/// read here independently as plain JSON values, match bit for bit.
#[test]
fn bundled_joint_files_parse_to_the_values_they_contain() {
    let files = fixture_joint_files();
    let mut v1_files = 0;
    for path in &files {
        let log = read_joints(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let text = std::fs::read_to_string(path).unwrap();
        let root: serde_json::Value = serde_json::from_str(&text).unwrap();
        let frames = root["frames"].as_array().unwrap();
        assert_eq!(log.frames.len(), frames.len(), "{}", path.display());
        if root["skeleton"] != "kinect_v1" {
            continue;
        }
        v1_files += 1;
        let unit = if root["units"] == "mm" { 0.001 } else { 1.0 };
        for (fi, (frame, parsed)) in frames.iter().zip(&log.frames).enumerate() {
            let expected_time = frame["time_s"].as_f64().unwrap_or(fi as f64 / 30.0);
            assert_eq!(parsed.time_s.to_bits(), expected_time.to_bits());
            let sk = &parsed.skeleton;
            for (name, xyz) in frame["joints"].as_object().unwrap() {
                let j = Joint::from_name(name).unwrap();
                for k in 0..3 {
                    let want = xyz[k].as_f64().unwrap() * unit;
                    let got = sk.positions[j.index()][k];
                    assert_eq!(got.to_bits(), want.to_bits(), "{} {name}", path.display());
                }
            }
            for j in Joint::ALL {
                let c = frame["confidence"][j.name()].as_f64().unwrap_or(1.0);
                assert_eq!(sk.confidence[j.index()].to_bits(), c.to_bits());
                let flagged = frame["interpolated"]
                    .as_array()
                    .is_some_and(|a| a.iter().any(|n| n == j.name()));
                assert_eq!(sk.interpolated[j.index()], flagged);
            }
        }
    }
    assert!(
        v1_files >= 20,
        "{v1_files} kinect_v1 files of {}",
        files.len()
    );
}

#[test]
fn an_unrecognised_joint_file_says_what_was_tried_and_why_each_failed() {
    let msg = |text: &str| {
        let e = parse_joints(text, "x.txt").unwrap_err();
        assert!(matches!(e, KinectError::UnknownFormat { .. }), "{e}");
        let m = e.to_string();
        assert!(!m.contains('\n') && !m.contains('\r'), "{m:?}");
        m
    };
    assert_eq!(
        msg("# comment\n\n0.5 1 2\n"),
        "x.txt: unrecognised joint file format: not JSON (starts with `#`, not `{`), not a \
         Kinect SDK text log (first line `0.5 1 2` has 3 fields, expected 61), not an NTU \
         .skeleton file (first line has 3 fields, expected the frame count alone)"
    );
    // A single field that is not a frame count.
    assert_eq!(
        msg("-3\n"),
        "x.txt: unrecognised joint file format: not JSON (starts with `-`, not `{`), not a \
         Kinect SDK text log (first line `-3` has 1 field, expected 61), not an NTU .skeleton \
         file (the first line is not a frame count, a non-negative integer)"
    );
    // A long first line is quoted to 40 characters; control characters are escaped.
    let long = format!("a\tb {}\n", "x ".repeat(100));
    let m = msg(&long);
    let quoted = format!("(first line `a\\tb {}x…` has 102 fields", "x ".repeat(17));
    assert!(m.contains(&quoted), "{m}");
    // Multi-byte characters are cut on a character boundary.
    let m = msg(&"é".repeat(50));
    assert!(m.contains(&format!("`{}…`", "é".repeat(40))), "{m}");
    assert_eq!(
        msg(""),
        "x.txt: unrecognised joint file format: the file is empty (or only white space)"
    );
    assert_eq!(
        msg("# only\n#comments\n"),
        "x.txt: unrecognised joint file format: the file has only blank lines and # comments"
    );
    // What detect recognises, detect_with_reason recognises too.
    assert_eq!(
        JointFormat::detect_with_reason(" {\"a\": 1}"),
        Ok(JointFormat::Json)
    );
}

/// Found by the `joints_detect` fuzz target: a first line of control characters, each quoted as
/// an 8-character escape, made the message hundreds of characters long.
#[test]
fn a_first_line_of_control_characters_is_quoted_briefly() {
    let mut bytes = vec![255u8, 35, 9, 0];
    bytes.extend([29u8; 92]);
    bytes.extend([0, 27, 255, 32, 255, 255, 102, 116, 116, 219, 126]);
    let text = String::from_utf8_lossy(&bytes);
    let e = parse_joints(&text, "fuzz").unwrap_err();
    assert!(matches!(e, KinectError::UnknownFormat { .. }), "{e}");
    let m = e.to_string();
    assert!(!m.contains('\n'), "{m:?}");
    let quoted = m.split('`').nth(5).unwrap();
    assert!(quoted.chars().count() <= 41, "{quoted:?}");
    assert!(
        quoted.starts_with("\u{fffd}#\\t\\0\\u{1d}") && quoted.ends_with('…'),
        "{quoted:?}"
    );
    assert!(m.chars().count() < 300, "{m}");
}

/// The frames are converted as they are parsed, after a first pass has read the header: a file
/// whose `frames` come before `skeleton` and `units` reads like one in the written order.
#[test]
fn frames_before_the_header_read_the_same() {
    let frame = format!(
        r#"{{"time_s":0.5,"joints":{{{}}}}}"#,
        full_joints_except("")
    );
    let written = format!(
        r#"{{"format":"symcorr.joints/1","skeleton":"kinect_v1","units":"mm","frames":[{frame},{frame}]}}"#
    );
    let reordered = format!(
        r#"{{"frames":[{frame},{frame}],"units":"mm","format":"symcorr.joints/1","skeleton":"kinect_v1"}}"#
    );
    let a = parse_joints_json(&written, "a.json").unwrap();
    let b = parse_joints_json(&reordered, "b.json").unwrap();
    assert_eq!(a, b);
    assert_eq!(a.frames.len(), 2);
    // Millimetres: 2.0 mm is 0.002 m.
    assert_abs_diff_eq!(a.frames[1].skeleton.position(Joint::Head).z, 0.002);
}

/// A body in the Azure Kinect SDK's own frame (millimetres, +x right, +y down): the 32 joints of
/// the canonical skeleton `s` as `to_k4abt_json` places them.
fn k4abt_body(id: u64, s: &Skeleton) -> String {
    let log = JointLog::from_skeletons(vec![s.clone()], 30.0);
    let text = symcorr_kinect::k4abt::to_k4abt_json(&log);
    let start = text.find("{\"body_id\"").unwrap();
    let end = text[start..].find("]]}").unwrap() + start + 3;
    text[start..end].replacen("\"body_id\": 1", &format!("\"body_id\": {id}"), 1)
}

fn k4abt_file(frames: &[(u64, Vec<String>)]) -> String {
    let frames: Vec<String> = frames
        .iter()
        .map(|(t, bodies)| {
            format!(
                "{{\"timestamp_usec\": {t}, \"num_bodies\": {}, \"bodies\": [{}]}}",
                bodies.len(),
                bodies.join(", ")
            )
        })
        .collect();
    format!(
        "{{\"k4abt_sdk_version\": \"1.1.2\", \"source_file\": \"take.mkv\", \"frames\": [{}]}}",
        frames.join(", ")
    )
}

#[test]
fn an_azure_kinect_log_reads_in_kinect_space_keeping_the_body_seen_most() {
    let a = read_joints(fixture("standing_v1.json")).unwrap().frames[0]
        .skeleton
        .clone();
    let b = skeleton(7);
    let text = k4abt_file(&[
        (1_000_000, vec![k4abt_body(3, &a), k4abt_body(5, &b)]),
        (1_033_333, vec![]),
        (1_066_667, vec![k4abt_body(3, &a)]),
    ]);
    let (log, format) = parse_joints(&text, "take.json").unwrap();
    assert_eq!(format, JointFormat::AzureKinect);
    assert_eq!(log.skeleton_kind, SkeletonKind::AzureKinect);
    let times: Vec<f64> = log.frames.iter().map(|f| f.time_s).collect();
    assert_eq!(times, vec![1.0, 1.033333, 1.066667]);
    // Body 3 is in two frames, body 5 in one. Its canonical joints come back where they were
    // (the file holds them as (−x, −y, z) in millimetres), every one tracked.
    for f in [&log.frames[0], &log.frames[2]] {
        for j in Joint::ALL {
            assert!(close(f.skeleton.position(j), a.position(j)), "{}", j.name());
            assert_eq!(f.skeleton.confidence[j.index()], 1.0);
            assert!(!f.skeleton.interpolated[j.index()]);
        }
    }
    // The subject's left stays their left: facing the camera, the left shoulder at −x.
    assert!(log.frames[0].skeleton.position(Joint::ShoulderLeft).x < 0.0);
    // The frame without the body is a frame in which the tracker lost it.
    assert!(!log.frames[1].skeleton.tracks_any());
    // Asked for by id.
    let other = parse_joints_as(
        &text,
        "take.json",
        JointFormat::AzureKinect,
        BodySelect::Id(5),
    )
    .unwrap();
    assert!(close(
        other.frames[0].skeleton.position(Joint::Head),
        b.position(Joint::Head)
    ));
    assert!(!other.frames[2].skeleton.tracks_any());
    let none = parse_joints_as(
        &text,
        "take.json",
        JointFormat::AzureKinect,
        BodySelect::Id(9),
    );
    assert!(matches!(none, Err(KinectError::NoBody { .. })), "{none:?}");
    // Without `joint_names`, the SDK's order; with them in another order, by name.
    let names: Vec<String> = symcorr_kinect::mapping::AZURE_KINECT_NAMES
        .iter()
        .map(|n| format!("\"{}\"", n.to_ascii_uppercase()))
        .collect();
    let mut reversed = names.clone();
    reversed.reverse();
    let body = k4abt_body(1, &a);
    let start = body.find("[[").unwrap() + 1;
    let mut joints: Vec<&str> = body[start..body.len() - 2].split("], [").collect();
    joints.reverse();
    let joints: Vec<String> = joints
        .iter()
        .map(|j| format!("[{}]", j.trim_matches(|c| c == '[' || c == ']')))
        .collect();
    let reordered = format!(
        "{{\"joint_names\": [{}], \"frames\": [{{\"timestamp_usec\": 0, \"bodies\": [{{\"body_id\": 1, \"joint_positions\": [{}]}}]}}]}}",
        reversed.join(", "),
        joints.join(", ")
    );
    let log = parse_joints(&reordered, "r.json").unwrap().0;
    for j in Joint::ALL {
        assert!(close(log.frames[0].skeleton.position(j), a.position(j)));
    }
    // `symcorr.joints/1` with skeleton `azure_kinect`: the SDK's names, Kinect space already.
    let kind = SkeletonKind::AzureKinect;
    let named: Vec<String> = kind
        .joint_names()
        .iter()
        .enumerate()
        .filter_map(|(i, n)| {
            let p = a.position(kind.canonical(i)?);
            Some(format!("\"{n}\": [{}, {}, {}]", p.x, p.y, p.z))
        })
        .collect();
    let text = format!(
        "{{\"format\": \"symcorr.joints/1\", \"skeleton\": \"azure_kinect\", \"frames\": [{{\"joints\": {{{}}}}}]}}",
        named.join(", ")
    );
    let (log, format) = parse_joints(&text, "n.json").unwrap();
    assert_eq!(format, JointFormat::Json);
    assert_eq!(log.skeleton_kind, SkeletonKind::AzureKinect);
    for j in Joint::ALL {
        assert!(close(log.frames[0].skeleton.position(j), a.position(j)));
    }
}

#[test]
fn bad_azure_kinect_logs_give_typed_errors_naming_the_file_and_frame() {
    let a = skeleton(3);
    let body = k4abt_body(1, &a);
    let one = |frame: &str| format!("{{\"k4abt_sdk_version\": \"1.1.2\", \"frames\": [{frame}]}}");
    let cases: Vec<(String, &str)> = vec![
        (
            "{\"k4abt_sdk_version\": \"1\"}".into(),
            "missing \"frames\"",
        ),
        (one(""), "has no frames"),
        (
            one(&format!("{{\"bodies\": [{body}]}}")),
            "frame 0: missing \"timestamp_usec\"",
        ),
        (
            one(&format!("{{\"timestamp_usec\": -5, \"bodies\": [{body}]}}")),
            "frame 0: timestamp_usec is -5",
        ),
        (
            one(&format!(
                "{{\"timestamp_usec\": 0, \"bodies\": [{}]}}",
                body.replacen(
                    "\"joint_positions\": [",
                    "\"joint_positions\": [[1, 2, 3], ",
                    1
                )
            )),
            "frame 0: body 0: 33 joint positions for 32 joints",
        ),
        (
            one("{\"timestamp_usec\": 0, \"bodies\": [{\"joint_positions\": []}]}"),
            "frame 0: body 0: missing \"body_id\"",
        ),
        (
            one("{\"timestamp_usec\": 0, \"bodies\": [{\"body_id\": 1}]}"),
            "frame 0: body 0: missing \"joint_positions\"",
        ),
        (
            one("{\"timestamp_usec\": 0, \"bodies\": []}"),
            "no frame of the 1 has a body",
        ),
        (
            "{\"joint_names\": [\"PELVIS\", \"TAIL\"], \"joint_positions\": 1, \"frames\": []}"
                .into(),
            "\"TAIL\" is not an Azure Kinect body tracking joint",
        ),
        (
            "{\"joint_names\": [\"PELVIS\", \"pelvis\"], \"joint_positions\": 1, \"frames\": []}"
                .into(),
            "\"pelvis\" is listed twice",
        ),
        (
            "{\"k4abt_sdk_version\": \"1\", \"frames\": [1, 2]}".into(),
            "not an Azure Kinect body tracking file",
        ),
        (
            "{\"k4abt_sdk_version\": \"1\", \"frames\": [".into(),
            "invalid JSON",
        ),
    ];
    for (text, expected) in cases {
        let e = parse_joints(&text, "take.json").unwrap_err();
        let m = e.to_string();
        assert!(
            m.starts_with("take.json: ") && m.contains(expected),
            "{text:.120} → {m}"
        );
    }
    // Forced on a file of another format.
    let e =
        read_joints_with_format(fixture("standing_v1.json"), JointFormat::AzureKinect).unwrap_err();
    assert!(
        e.to_string()
            .contains("frame 0: missing \"timestamp_usec\""),
        "{e}"
    );
}

/// A log that reports the head's turn against the chest: written as the Azure Kinect SDK writes
/// it (the turn as a face: nose and ears), read back to the same turn; in `symcorr.joints/1` as
/// `head_turn_rad`, exactly; a log without a face reports none. A turn outside ±π/2 is refused.
#[test]
fn a_reported_head_turn_survives_both_formats() {
    let mut s = read_joints(fixture("standing_v1.json")).unwrap().frames[0]
        .skeleton
        .clone();
    let plain = JointLog::from_skeletons(vec![s.clone()], 30.0);
    for turn in [-1.2, -0.3, 0.0, 0.5, 1.4] {
        s.head_turn = Some(turn);
        let log = JointLog::from_skeletons(vec![s.clone()], 30.0);
        let azure = parse_joints(&symcorr_kinect::k4abt::to_k4abt_json(&log), "a.json")
            .unwrap()
            .0;
        let back = azure.frames[0].skeleton.head_turn.unwrap();
        assert!((back - turn).abs() < 1e-6, "{turn} → {back}");
        let json = parse_joints(&to_json_string(&log), "j.json").unwrap().0;
        assert_eq!(json.frames[0].skeleton.head_turn, Some(turn));
    }
    // The face at the head (no turn reported): no turn read.
    let azure = parse_joints(&symcorr_kinect::k4abt::to_k4abt_json(&plain), "a.json").unwrap();
    assert_eq!(azure.0.frames[0].skeleton.head_turn, None);
    assert!(!to_json_string(&plain).contains("head_turn"));
    let text = to_json_string(&JointLog::from_skeletons(
        vec![Skeleton {
            head_turn: Some(0.125),
            ..s.clone()
        }],
        30.0,
    ))
    .replace("\"head_turn_rad\":0.125", "\"head_turn_rad\":2.5");
    let e = parse_joints(&text, "j.json").unwrap_err().to_string();
    assert!(
        e.contains("frame 0: head_turn_rad is 2.5, expected a number in [-π/2, π/2]"),
        "{e}"
    );
}
