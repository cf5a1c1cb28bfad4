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
        distortion: None,
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
        distortion: None,
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

// ---------------------------------------------------------------------------------------------
// Lens distortion against OpenCV (fixtures/kinect/distortion_reference.json, written by
// tools/reference/make_distortion_reference.py with cv2.projectPoints / cv2.undistortPoints).

/// The reference cases: OpenCV's camera (x right, y down, z forward) is Kinect camera space
/// with x and y negated, and OpenCV's image is the image as the lens forms it — a
/// [`Mirroring::Direct`](symcorr_kinect::Mirroring) image.
fn opencv_cases() -> Vec<(String, Intrinsics, serde_json::Value)> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/kinect/distortion_reference.json"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let f = |key: &str| c[key].as_f64().unwrap();
            let coefficients: Vec<f64> = c["distortion"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let k = Intrinsics {
                width: c["width"].as_u64().unwrap() as u32,
                height: c["height"].as_u64().unwrap() as u32,
                fx: f("fx"),
                fy: f("fy"),
                cx: f("cx"),
                cy: f("cy"),
                mirroring: symcorr_kinect::Mirroring::Direct,
                distortion: Some(symcorr_kinect::Distortion::from_opencv(&coefficients).unwrap()),
            };
            (c["name"].as_str().unwrap().to_string(), k, c.clone())
        })
        .collect()
}

fn pair(v: &serde_json::Value) -> [f64; 2] {
    [v[0].as_f64().unwrap(), v[1].as_f64().unwrap()]
}

#[test]
fn distorted_projection_matches_opencv() {
    let cases = opencv_cases();
    assert_eq!(cases.len(), 3);
    for (name, k, case) in cases {
        k.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        let entries = case["project"].as_array().unwrap();
        assert!(entries.len() >= 100, "{name}");
        let mut worst: f64 = 0.0;
        for e in entries {
            let p = &e["point"];
            let cv = [0, 1, 2].map(|i| p[i].as_f64().unwrap());
            let [u, v] = k.project(&Point3::new(-cv[0], -cv[1], cv[2]));
            let [ru, rv] = pair(&e["pixel"]);
            worst = worst.max((u - ru).abs()).max((v - rv).abs());
        }
        assert!(worst < 1e-9, "{name}: projection {worst} px from OpenCV's");
    }
}

#[test]
fn distorted_unprojection_matches_opencv_and_the_mirrored_image() {
    for (name, k, case) in opencv_cases() {
        let mirrored = k.columns_reversed();
        mirrored
            .validate()
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let rays = k.pixel_rays();
        let last = f64::from(k.width) - 1.0;
        let mut worst: f64 = 0.0;
        for e in case["unproject"].as_array().unwrap() {
            let [u, v] = pair(&e["pixel"]);
            let [rx, ry] = pair(&e["ray"]);
            let z = 2.5;
            let p = k.unproject(u, v, z);
            worst = worst.max((-p.x / z - rx).abs()).max((-p.y / z - ry).abs());
            assert_eq!(p.z, z);
            // The same pixel of the image with its columns reversed: the same ray.
            let q = mirrored.unproject(last - u, v, z);
            assert!((p - q).norm() < 1e-8, "{name} ({u}, {v}): {p} vs {q}");
            let [mu, mv] = mirrored.project(&p);
            assert!(
                (mu - (last - u)).abs() < 1e-6 && (mv - v).abs() < 1e-6,
                "{name}"
            );
            // The ray table gives the same point at a whole pixel.
            if (u.fract(), v.fract()) == (0.0, 0.0) {
                let t = rays.point(u as u32, v as u32, z).unwrap();
                assert!((t - p).norm() < 1e-6, "{name} ({u}, {v})");
            }
        }
        assert!(worst < 1e-9, "{name}: rays {worst} from OpenCV's");
    }
}

#[test]
fn a_lens_model_that_folds_inside_the_image_is_refused() {
    let pinhole = Intrinsics {
        width: 640,
        height: 480,
        fx: 400.0,
        fy: 400.0,
        cx: 320.0,
        cy: 240.0,
        mirroring: symcorr_kinect::Mirroring::Mirrored,
        distortion: None,
    };
    // r·(1 − 0.6 r²) stops growing at r = 0.745, where it shows 0.497: the image's corner,
    // at 1.0, is beyond what the lens shows.
    let fold = symcorr_kinect::Distortion::from_opencv(&[-0.6, 0.0, 0.0, 0.0]).unwrap();
    let k = Intrinsics {
        distortion: Some(fold),
        ..pinhole
    };
    let e = k.validate().unwrap_err().to_string();
    assert!(e.contains("folds") && e.contains("corner"), "{e}");
    // The same lens on a narrower camera (its corner at 0.4) describes the whole image.
    let narrow = Intrinsics {
        fx: 1000.0,
        fy: 1000.0,
        ..k
    };
    narrow.validate().unwrap();
    let p = narrow.unproject(0.0, 0.0, 2.0);
    let [u, v] = narrow.project(&p);
    assert!(u.abs() < 1e-9 && v.abs() < 1e-9, "{u} {v}");
    // A pinhole camera projects as it always has, bit for bit.
    let q = Point3::new(0.31, -0.17, 2.3);
    let [u, v] = pinhole.project(&q);
    assert_eq!(
        (u, v),
        (320.0 + 400.0 * 0.31 / 2.3, 240.0 - 400.0 * -0.17 / 2.3)
    );
}

#[test]
fn distortion_json_takes_opencvs_vectors() {
    let base = r#"{"format":"symcorr.intrinsics/1","width":512,"height":424,"fx":365.5,"fy":365.5,"cx":254.9,"cy":205.4"#;
    let read = |tail: &str| Intrinsics::from_json_str(&format!("{base}{tail}}}"), "k.json");
    let k5 = read(r#","distortion":[0.0905,-0.2701,0.0,0.0,0.0922]"#).unwrap();
    let d = k5.distortion.unwrap();
    assert_eq!(d.radial, [0.0905, -0.2701, 0.0922, 0.0, 0.0, 0.0]);
    assert_eq!(d.tangential, [0.0, 0.0]);
    assert!(k5
        .to_json()
        .ends_with(r#""distortion":[0.0905,-0.2701,0.0,0.0,0.0922]}"#));
    let k4 = read(r#","distortion":[0.01,-0.02,0.001,-0.002]"#).unwrap();
    assert_eq!(k4.distortion.unwrap().tangential, [0.001, -0.002]);
    assert!(k4
        .to_json()
        .ends_with(r#""distortion":[0.01,-0.02,0.001,-0.002]}"#));
    let k8 = read(r#","distortion":[0.5,-0.01,0.0,0.0,-0.006,0.83,0.12,-0.03],"mirrored":false"#)
        .unwrap();
    assert_eq!(k8.distortion.unwrap().radial[3], 0.83);
    assert_eq!(
        Intrinsics::from_json_str(&k8.to_json(), "k.json").unwrap(),
        k8
    );
    assert_eq!(read("").unwrap().distortion, None);
    for (tail, says) in [
        (
            r#","distortion":[0.1,0.2,0.0,0.0,0.1,0.0]"#,
            "6 coefficients",
        ),
        (r#","distortion":null"#, "invalid type: null"),
        (r#","distortion":[0.1,"x",0.0,0.0]"#, "invalid type"),
        (r#","distortion":[-0.9,0.0,0.0,0.0]"#, "folds"),
        // Decentring of 0.08 moves the corner by a fifth of its radius: another unit, not a lens.
        (r#","distortion":[0.09,-0.27,0.08,0.0,0.09]"#, "tangential"),
        // Found by fuzzing: coefficients of 10¹⁹ fold the model within a pixel of the centre.
        (
            r#","distortion":[2.0,0.0,0.001,-0.0003,6.7e19,6.7e19,6666.0,6.7e19]"#,
            "no lens",
        ),
    ] {
        let e = read(tail).unwrap_err();
        assert!(matches!(e, KinectError::Json { .. }), "{e}");
        assert!(e.to_string().contains(says), "{tail}: {e}");
    }
}
