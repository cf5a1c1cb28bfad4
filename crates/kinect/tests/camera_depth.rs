//! Intrinsics conventions and PNG-16 depth frames.

use approx::assert_abs_diff_eq;
use nalgebra::Point3;
use symcorr_kinect::depth::{decode_depth_png16, encode_depth_png16};
use symcorr_kinect::{read_depth_png16, write_depth_png16, DepthFrame, Intrinsics, KinectError};

#[test]
fn intrinsics_json_form_is_exact_and_round_trips() {
    let k = Intrinsics {
        width: 640,
        height: 480,
        fx: 580.0,
        fy: 580.0,
        cx: 319.5,
        cy: 239.5,
        mirroring: symcorr_kinect::Mirroring::Mirrored,
    };
    let text = serde_json::to_string(&k).unwrap();
    assert_eq!(
        text,
        r#"{"format":"symcorr.intrinsics/1","width":640,"height":480,"fx":580.0,"fy":580.0,"cx":319.5,"cy":239.5}"#
    );
    let back: Intrinsics = serde_json::from_str(&text).unwrap();
    assert_eq!(back, k);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("k.json");
    k.write(&p).unwrap();
    assert_eq!(Intrinsics::read(&p).unwrap(), k);
    // Wrong tag, bad focal length, unknown field → errors.
    assert!(
        serde_json::from_str::<Intrinsics>(&text.replace("intrinsics/1", "intrinsics/2")).is_err()
    );
    assert!(
        serde_json::from_str::<Intrinsics>(&text.replace("\"fx\":580.0", "\"fx\":-1.0")).is_err()
    );
    assert!(serde_json::from_str::<Intrinsics>(&text.replace("\"cy\"", "\"cz\"")).is_err());
    // "mirrored": a boolean, false for a direct image; true is the default and is not written.
    let with = |v: &str| text.replace('}', &format!(",\"mirrored\":{v}}}"));
    let direct: Intrinsics = serde_json::from_str(&with("false")).unwrap();
    assert_eq!(direct.mirroring, symcorr_kinect::Mirroring::Direct);
    assert_eq!(serde_json::to_string(&direct).unwrap(), with("false"));
    assert_eq!(
        serde_json::from_str::<Intrinsics>(&with("true")).unwrap(),
        k
    );
    for bad in ["null", "0", "\"false\""] {
        assert!(
            serde_json::from_str::<Intrinsics>(&with(bad)).is_err(),
            "{bad}"
        );
    }
    std::fs::write(&p, "{").unwrap();
    assert!(matches!(
        Intrinsics::read(&p),
        Err(KinectError::Json { .. })
    ));
}

#[test]
fn kinect_v1_intrinsics_match_the_sdk_field_of_view() {
    let k = Intrinsics::kinect_v1();
    assert_eq!((k.width, k.height), (640, 480));
    // Nominal horizontal FOV 58.5° (NUI_CAMERA_DEPTH_NOMINAL_HORIZONTAL_FOV): 2·atan(320/fx).
    let hfov = 2.0 * (320.0 / k.fx).atan().to_degrees();
    assert!((hfov - 58.5).abs() < 0.1, "{hfov}");
    // Vertical 45.6°.
    let vfov = 2.0 * (240.0 / k.fy).atan().to_degrees();
    assert!((vfov - 45.6).abs() < 0.3, "{vfov}");
}

#[test]
fn projection_directions_follow_the_documented_convention() {
    let k = Intrinsics::kinect_v1();
    // The optical axis lands on the principal point.
    assert_eq!(k.project(&Point3::new(0.0, 0.0, 2.0)), [k.cx, k.cy]);
    // +y (up) → smaller v (rows grow downward).
    assert!(k.project(&Point3::new(0.0, 0.5, 2.0))[1] < k.cy);
    // +x (sensor's left) → larger u (SDK v1's mirrored depth image).
    assert!(k.project(&Point3::new(0.5, 0.0, 2.0))[0] > k.cx);
    // SDK formula at 320×240: x_pixel = 160 + x·285.63/z.
    let u = k.project(&Point3::new(0.3, 0.0, 1.5))[0];
    assert_abs_diff_eq!(u / 2.0, 160.0 + 0.3 * 285.63 / 1.5, epsilon = 1e-9);
    // Farther → closer to the centre.
    assert!(k.project(&Point3::new(0.5, 0.0, 4.0))[0] < k.project(&Point3::new(0.5, 0.0, 2.0))[0]);
}

#[test]
fn unproject_inverts_project() {
    let k = Intrinsics {
        width: 512,
        height: 424,
        fx: 365.1,
        fy: 364.9,
        cx: 257.3,
        cy: 208.2,
        mirroring: symcorr_kinect::Mirroring::Mirrored,
    };
    for i in 0..50 {
        let t = i as f64;
        let p = Point3::new(t.sin(), (1.3 * t).cos(), 0.5 + 0.1 * t);
        let [u, v] = k.project(&p);
        let q = k.unproject(u, v, p.z);
        assert_abs_diff_eq!(q, p, epsilon = 1e-12);
    }
}

fn ramp(w: u32, h: u32) -> DepthFrame {
    let data = (0..w * h).map(|i| (i * 977 % 65536) as u16).collect();
    DepthFrame::new(w, h, data).unwrap()
}

#[test]
fn png16_round_trips_every_value() {
    let f = ramp(67, 41);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("d.png");
    write_depth_png16(&p, &f).unwrap();
    let back = read_depth_png16(&p).unwrap();
    assert_eq!(back, f);
    assert_eq!(back.at(66, 40), Some(f.data_mm[40 * 67 + 66]));
    assert_eq!(back.at(67, 0), None);
    // Full u16 range survives.
    let g = DepthFrame::new(2, 1, vec![0, 65535]).unwrap();
    assert_eq!(
        decode_depth_png16(&encode_depth_png16(&g).unwrap(), "m").unwrap(),
        g
    );
}

#[test]
fn bad_depth_pngs_are_typed_errors() {
    // 8-bit greyscale is refused.
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, 2, 2);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&[1, 2, 3, 4]).unwrap();
    }
    let e = decode_depth_png16(&out, "eight.png").unwrap_err();
    assert!(
        matches!(e, KinectError::Png { .. }) && e.to_string().contains("eight.png"),
        "{e}"
    );
    // Truncated PNG.
    let good = encode_depth_png16(&ramp(16, 16)).unwrap();
    let e = decode_depth_png16(&good[..good.len() / 2], "cut.png").unwrap_err();
    assert!(matches!(e, KinectError::Png { .. }), "{e}");
    // Not a PNG.
    assert!(matches!(
        decode_depth_png16(b"hello", "x.png"),
        Err(KinectError::Png { .. })
    ));
    // Wrong data size.
    assert!(matches!(
        DepthFrame::new(3, 3, vec![0; 8]),
        Err(KinectError::DepthSize { .. })
    ));
    assert!(matches!(
        read_depth_png16("/nonexistent/d.png"),
        Err(KinectError::Io { .. })
    ));
}

#[test]
fn implausible_intrinsics_are_refused_naming_the_value() {
    let ok = Intrinsics::kinect_v1();
    let cases: [(Intrinsics, &str); 9] = [
        (
            Intrinsics { fx: 1e308, ..ok },
            "fx = 1e308: expected a focal length in 1..=100000 px",
        ),
        (
            Intrinsics { fy: f64::NAN, ..ok },
            "fy = NaN: expected a focal length",
        ),
        (Intrinsics { fx: 0.5, ..ok }, "fx = 0.5: expected"),
        (Intrinsics { fy: -580.0, ..ok }, "fy = -580.0: expected"),
        (
            Intrinsics { width: 0, ..ok },
            "width = 0: expected 1..=16384 px",
        ),
        (
            Intrinsics {
                height: 100_000,
                ..ok
            },
            "height = 100000: expected 1..=16384 px",
        ),
        (
            Intrinsics { cx: 1e9, ..ok },
            "cx = 1000000000.0: expected a principal point in -320..=960 px",
        ),
        (
            Intrinsics {
                cy: f64::INFINITY,
                ..ok
            },
            "cy = inf: expected a principal point in -240..=720 px",
        ),
        (Intrinsics { cx: -321.0, ..ok }, "cx = -321.0: expected"),
    ];
    for (k, want) in cases {
        let e = k.validate().unwrap_err();
        assert!(matches!(e, KinectError::Intrinsics(_)), "{e}");
        let msg = e.to_string();
        assert!(
            msg.starts_with("invalid intrinsics: ") && msg.contains(want),
            "{msg}"
        );
        assert!(!msg.contains('\n'), "{msg}");
    }
    // Near the limits but plausible.
    for k in [
        Intrinsics {
            fx: 1.0,
            fy: 100_000.0,
            ..ok
        },
        Intrinsics {
            cx: -320.0,
            cy: 720.0,
            ..ok
        },
        Intrinsics {
            width: 16384,
            height: 1,
            cx: 0.0,
            cy: 0.0,
            ..ok
        },
    ] {
        k.validate().unwrap();
    }
    // The file reader names the file and the value.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("k.json");
    std::fs::write(
        &p,
        r#"{"format":"symcorr.intrinsics/1","width":640,"height":480,"fx":1e308,"fy":580.0,"cx":320.0,"cy":240.0}"#,
    )
    .unwrap();
    let e = Intrinsics::read(&p).unwrap_err();
    assert!(matches!(e, KinectError::Json { .. }), "{e}");
    let msg = e.to_string();
    assert!(
        msg.ends_with(
            "k.json: invalid intrinsics: fx = 1e308: expected a focal length in 1..=100000 px"
        ),
        "{msg}"
    );
}
