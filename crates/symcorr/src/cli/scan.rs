//! `symcorr scan (--oni FILE | --depth PNG16 --intrinsics K.json | --device [--uri URI]) --joints J --out scan.ply`
//!
//! Turns one depth frame (or the per-pixel median of `--fuse N` consecutive frames) into a scan
//! mesh: floor and background removed using the skeleton from `--joints`, the components near the bones kept
//! (symcorr-kinect's `scan` module). The skeleton is the robust average of the whole joint log
//! unless `--joints-frame N` picks one frame.

use super::CliError;
use clap::Args;
use std::path::PathBuf;
use symcorr_kinect::{
    read_depth_png16, read_joints, read_joints_with_format, scan_mesh, DepthFrame, FrameSelect,
    Intrinsics, ScanOptions,
};

/// Arguments of `symcorr scan`.
#[derive(Debug, Args)]
pub struct ScanArgs {
    /// OpenNI2 recording (.oni) to take the depth frame from (needs the `openni2` feature).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["depth", "device"])]
    pub oni: Option<PathBuf>,
    /// 16-bit greyscale PNG depth frame (millimetres); needs --intrinsics.
    #[arg(
        long,
        value_name = "PNG16",
        requires = "intrinsics",
        conflicts_with = "device"
    )]
    pub depth: Option<PathBuf>,
    /// Read live from an OpenNI2 device (needs the `openni2` feature).
    #[arg(long)]
    pub device: bool,
    /// Device URI for --device (default: the first device OpenNI2 lists).
    #[arg(long, value_name = "URI", requires = "device")]
    pub uri: Option<String>,
    /// Camera intrinsics (symcorr.intrinsics/1 JSON). Required with --depth; for recordings and
    /// devices it overrides the stream's field of view.
    #[arg(long, value_name = "K.json")]
    pub intrinsics: Option<PathBuf>,
    /// Joint file (symcorr.joints/1, Kinect SDK text, NTU .skeleton), same camera space.
    #[arg(long, value_name = "J")]
    pub joints: PathBuf,
    /// Force the joint file format: json, kinect-text, ntu or k4abt (default: detected from
    /// content).
    #[arg(long, value_name = "FORMAT")]
    pub joints_format: Option<String>,
    /// Use this frame of the joint log (0-based) instead of the robust average of all frames.
    #[arg(long, value_name = "N")]
    pub joints_frame: Option<usize>,
    /// Output mesh (.ply, .off, .obj, .glb, .gltf).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Depth frame of the recording/device stream to use (0-based count of delivered frames).
    #[arg(long, value_name = "N", conflicts_with = "time")]
    pub frame: Option<usize>,
    /// Time in the recording (seconds from its first frame, finite, >= 0) of the depth frame to
    /// use.
    #[arg(long, value_name = "S")]
    pub time: Option<f64>,
    /// Fuse this many consecutive frames (per-pixel median) into one before meshing (1..=300).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub fuse: usize,
    /// Largest depth jump along a triangle edge, metres (finite, > 0).
    #[arg(long, default_value_t = 0.05)]
    pub discontinuity: f64,
    /// Keep the floor (no RANSAC floor removal).
    #[arg(long)]
    pub keep_floor: bool,
    /// Also write the per-vertex pixel ids (`v·width + u`) as JSON.
    #[arg(long, value_name = "FILE")]
    pub pixel_map: Option<PathBuf>,
}

/// Most frames `--fuse` takes (10 s of a 30 Hz stream).
pub const MAX_FUSE: usize = 300;

/// Checks every numeric option before any file is read: `--fuse` in `1..=`[`MAX_FUSE`],
/// `--discontinuity` finite and > 0, `--time` finite and >= 0. The error names the option.
fn check_numbers(a: &ScanArgs) -> Result<(), CliError> {
    if !(1..=MAX_FUSE).contains(&a.fuse) {
        return Err(CliError(format!(
            "--fuse {}: expected 1..={MAX_FUSE} frames",
            a.fuse
        )));
    }
    if !(a.discontinuity.is_finite() && a.discontinuity > 0.0) {
        return Err(CliError(format!(
            "--discontinuity {:?}: expected a finite length > 0 (metres)",
            a.discontinuity
        )));
    }
    if let Some(t) = a.time {
        if !(t.is_finite() && t >= 0.0) {
            return Err(CliError(format!(
                "--time {t:?}: expected a finite time >= 0 (seconds)"
            )));
        }
    }
    Ok(())
}

/// Runs `symcorr scan`.
///
/// Errors: an invalid numeric option (named), an invalid intrinsics file (named, with the
/// value at fault), and any error reading the inputs or building the mesh.
pub fn run(a: ScanArgs) -> Result<(), CliError> {
    check_numbers(&a)?;
    // Every output is checked before any work (not a directory, not an input, its directory
    // exists).
    let inputs: Vec<&std::path::Path> = [
        a.oni.as_deref(),
        a.depth.as_deref(),
        a.intrinsics.as_deref(),
    ]
    .into_iter()
    .flatten()
    .chain([a.joints.as_path()])
    .collect();
    for out in [Some(&a.out), a.pixel_map.as_ref()].into_iter().flatten() {
        symcorr_mesh::io::check_output(out, &inputs).map_err(|e| CliError(e.to_string()))?;
    }
    let log = match super::joints_format(a.joints_format.as_deref())? {
        Some(f) => read_joints_with_format(&a.joints, f),
        None => read_joints(&a.joints),
    }
    .map_err(|e| CliError(e.to_string()))?;
    let select = match a.joints_frame {
        Some(i) => FrameSelect::Index(i),
        None => FrameSelect::Window {
            start_s: f64::NEG_INFINITY,
            end_s: f64::INFINITY,
        },
    };
    let skeleton = log
        .select(select)
        .map_err(|e| CliError::with(a.joints.display(), e))?;

    let explicit = match &a.intrinsics {
        Some(p) => Some(Intrinsics::read(p).map_err(|e| CliError(e.to_string()))?),
        None => None,
    };
    let (frames, k) = if let Some(png) = &a.depth {
        if a.fuse > 1 || a.frame.is_some() || a.time.is_some() {
            return Err(CliError(
                "--fuse, --frame and --time apply to recordings and devices, not to --depth".into(),
            ));
        }
        let f = read_depth_png16(png).map_err(|e| CliError(e.to_string()))?;
        let k = explicit.ok_or_else(|| CliError("--depth needs --intrinsics".into()))?;
        (vec![f], k)
    } else if a.oni.is_some() || a.device {
        openni_frames(&a, explicit)?
    } else {
        return Err(CliError(
            "give one depth source: --oni FILE, --depth PNG16 --intrinsics K.json, or --device"
                .into(),
        ));
    };
    let frame = if frames.len() == 1 {
        frames
            .into_iter()
            .next()
            .ok_or_else(|| CliError("no depth frame".into()))?
    } else {
        symcorr_kinect::fuse_depth_frames(&frames).map_err(|e| CliError(e.to_string()))?
    };
    // A depth image whose mirroring the intrinsics state wrongly shows the pose on the other
    // side; scanned as given, its match flipped three matches in four.
    symcorr_kinect::scan::check_mirroring(&frame, &k, &skeleton)
        .map_err(|e| CliError(e.to_string()))?;
    let opts = ScanOptions {
        discontinuity_m: a.discontinuity,
        remove_floor: !a.keep_floor,
        ..ScanOptions::default()
    };
    let scan =
        scan_mesh(&frame, &k, Some(&skeleton), &opts).map_err(|e| CliError(e.to_string()))?;
    symcorr_kinect::scan::check_scale(&scan.mesh, &skeleton, &k)
        .map_err(|e| CliError(e.to_string()))?;
    // Both outputs are staged, then committed together: an error leaves neither.
    let cli = |e: symcorr_mesh::MeshError| CliError(e.to_string());
    let mut batch = symcorr_mesh::io::OutputBatch::new();
    batch.add_mesh(&a.out, &scan.mesh, None).map_err(cli)?;
    if let Some(p) = &a.pixel_map {
        let json = serde_json::json!({
            "format": "symcorr.pixelmap/1",
            "width": frame.width,
            "height": frame.height,
            "pixel_ids": scan.pixel_ids,
        });
        batch.add(p, json.to_string().as_bytes()).map_err(cli)?;
    }
    batch.commit().map_err(cli)?;
    let r = &scan.report;
    println!(
        "scan: {} vertices, {} triangles ({} valid pixels; removed {} background, {} floor, {} in smaller components)",
        scan.mesh.num_vertices(),
        scan.mesh.num_triangles(),
        r.valid_pixels,
        r.background_removed,
        r.floor_removed,
        r.component_vertices_removed
    );
    let hand = symcorr_attach::handedness_verdict(&scan.mesh, &skeleton, 0.01);
    match hand.verdict {
        symcorr_attach::Handedness::Swapped => eprintln!(
            "symcorr: warning: the skeleton's left/right look swapped relative to the scan \
             (feet point {:.3} m backwards)",
            -hand.foot_offset_m
        ),
        symcorr_attach::Handedness::LimbsSwapped(pair) => eprintln!(
            "symcorr: warning: the skeleton's {}' left/right look swapped against the rest of it \
             (the shoulders and the hips point opposite ways across the spine); match and label \
             swap them back",
            pair.name()
        ),
        _ => {}
    }
    Ok(())
}

/// Intrinsics of an OpenNI2 stream: explicit ones, else from the stream's field of view
/// ([`Intrinsics::from_field_of_view`]: without one, the nominal Kinect v1 focal length scaled
/// to the frame width) and its mirroring property (not reported: mirrored, as a Kinect's).
#[cfg_attr(not(feature = "openni2"), allow(dead_code))]
fn stream_intrinsics(
    explicit: Option<Intrinsics>,
    frame: &DepthFrame,
    fov: Option<(f32, f32)>,
    mirrored: Option<bool>,
) -> Intrinsics {
    if let Some(k) = explicit {
        return k;
    }
    let fov = fov.map(|(h, v)| (f64::from(h), f64::from(v)));
    Intrinsics {
        mirroring: symcorr_kinect::Mirroring::from_openni(mirrored),
        ..Intrinsics::from_field_of_view(frame.width, frame.height, fov)
    }
}

#[cfg(not(feature = "openni2"))]
fn openni_frames(
    _a: &ScanArgs,
    _explicit: Option<Intrinsics>,
) -> Result<(Vec<DepthFrame>, Intrinsics), CliError> {
    Err(CliError(
        "this symcorr was built without OpenNI2: rebuild with `--features openni2` \
         (needs libopenni2-dev) to read .oni recordings or devices"
            .into(),
    ))
}

#[cfg(feature = "openni2")]
fn openni_frames(
    a: &ScanArgs,
    explicit: Option<Intrinsics>,
) -> Result<(Vec<DepthFrame>, Intrinsics), CliError> {
    use symcorr_kinect::openni2::OpenNi;
    let err = |e: symcorr_kinect::KinectError| CliError(e.to_string());
    let ni = OpenNi::init().map_err(err)?;
    let device = if let Some(path) = &a.oni {
        let d = ni.open_file(path).map_err(err)?;
        d.set_playback_speed(0.0).map_err(err)?;
        d.set_repeat(false).map_err(err)?;
        d
    } else {
        let uri = match &a.uri {
            Some(u) => u.clone(),
            None => ni
                .devices()
                .map_err(err)?
                .into_iter()
                .next()
                .map(|d| d.uri)
                .ok_or_else(|| CliError("no OpenNI2 device found (use --uri)".into()))?,
        };
        ni.open(&uri).map_err(err)?
    };
    let mut stream = device.depth_stream().map_err(err)?;
    let fov = stream.field_of_view();
    let mirroring = stream.mirroring();
    stream.start().map_err(err)?;
    let first = stream.read_frame(5000).map_err(err)?;
    let t0 = first.timestamp_us;
    let mut current = first;
    let mut count = 0usize;
    loop {
        let reached = match (a.frame, a.time) {
            (Some(n), _) => count >= n,
            (None, Some(s)) => (current.timestamp_us - t0) as f64 >= s * 1e6,
            (None, None) => true,
        };
        if reached {
            break;
        }
        current = stream.read_frame(5000).map_err(err)?;
        count += 1;
    }
    let mut frames = vec![current.depth];
    while frames.len() < a.fuse {
        frames.push(stream.read_frame(5000).map_err(err)?.depth);
    }
    let k = stream_intrinsics(explicit, &frames[0], fov, mirroring);
    Ok((frames, k))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;
    use symcorr_kinect::joints::JointLog;
    use symcorr_skeleton::Skeleton;

    /// A sphere of radius 0.3 m at 2.5 m in front of a wall at 4 m, seen by `k`.
    fn sphere_frame(k: &Intrinsics) -> DepthFrame {
        let mut data = Vec::new();
        for v in 0..k.height {
            for u in 0..k.width {
                let d = k.unproject(f64::from(u), f64::from(v), 1.0);
                let (a, b, c) = (d.coords.norm_squared(), -2.0 * 2.5, 2.5 * 2.5 - 0.09);
                let disc = b * b - 4.0 * a * c;
                let t = if disc >= 0.0 {
                    (-b - disc.sqrt()) / (2.0 * a)
                } else {
                    4.0
                };
                data.push((t * 1000.0).round() as u16);
            }
        }
        DepthFrame::new(k.width, k.height, data).unwrap()
    }

    /// A 160×120 Kinect v1 camera.
    fn small_intrinsics() -> Intrinsics {
        Intrinsics {
            width: 160,
            height: 120,
            fx: 142.8,
            fy: 142.8,
            cx: 80.0,
            cy: 60.0,
            mirroring: symcorr_kinect::Mirroring::Mirrored,
            distortion: None,
        }
    }

    #[test]
    fn scan_from_png_and_intrinsics_writes_the_subject_mesh() {
        let dir = tempfile::tempdir().unwrap();
        let k = small_intrinsics();
        let png = dir.path().join("d.png");
        symcorr_kinect::write_depth_png16(&png, &sphere_frame(&k)).unwrap();
        let kj = dir.path().join("k.json");
        k.write(&kj).unwrap();
        let mut p = [[0.0; 3]; 20];
        for (i, q) in p.iter_mut().enumerate() {
            let t = i as f64 / 19.0;
            *q = [0.2 * (2.0 * t - 1.0), 0.2 - 0.4 * t, 2.45 + 0.1 * t];
        }
        let joints = dir.path().join("j.json");
        symcorr_kinect::write_joints_json(
            &joints,
            &JointLog::from_skeletons(vec![Skeleton::from_arrays(p); 3], 30.0),
        )
        .unwrap();
        let out = dir.path().join("scan.ply");
        let map = dir.path().join("map.json");
        let args = ScanArgs {
            oni: None,
            depth: Some(png),
            device: false,
            uri: None,
            intrinsics: Some(kj),
            joints,
            joints_format: None,
            joints_frame: None,
            out: out.clone(),
            frame: None,
            time: None,
            fuse: 1,
            discontinuity: 0.05,
            keep_floor: false,
            pixel_map: Some(map.clone()),
        };
        run(args).unwrap();
        let mesh = symcorr_mesh::io::read(&out).unwrap().mesh;
        assert!(mesh.num_vertices() > 100);
        for q in &mesh.positions {
            let r = nalgebra::distance(&Point3::from(*q), &Point3::new(0.0, 0.0, 2.5));
            assert!((r - 0.3).abs() < 0.01, "{q:?}");
        }
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(map).unwrap()).unwrap();
        assert_eq!(
            m["pixel_ids"].as_array().unwrap().len(),
            mesh.num_vertices()
        );
    }

    /// `scan --depth d.png --intrinsics k.json --joints j.json --out scan.ply` in `dir` (the
    /// files need not exist).
    fn png_args(dir: &std::path::Path) -> ScanArgs {
        ScanArgs {
            oni: None,
            depth: Some(dir.join("d.png")),
            device: false,
            uri: None,
            intrinsics: Some(dir.join("k.json")),
            joints: dir.join("j.json"),
            joints_format: None,
            joints_frame: None,
            out: dir.join("scan.ply"),
            frame: None,
            time: None,
            fuse: 1,
            discontinuity: 0.05,
            keep_floor: false,
            pixel_map: None,
        }
    }

    #[test]
    fn invalid_numeric_options_are_refused_naming_the_option() {
        let dir = tempfile::tempdir().unwrap();
        type Edit = fn(&mut ScanArgs);
        let cases: [(Edit, &str); 8] = [
            (
                |a| a.discontinuity = f64::NAN,
                "--discontinuity NaN: expected a finite length > 0 (metres)",
            ),
            (
                |a| a.discontinuity = f64::INFINITY,
                "--discontinuity inf: expected a finite length > 0 (metres)",
            ),
            (
                |a| a.discontinuity = -0.05,
                "--discontinuity -0.05: expected a finite length > 0 (metres)",
            ),
            (
                |a| a.discontinuity = 0.0,
                "--discontinuity 0.0: expected a finite length > 0 (metres)",
            ),
            (
                |a| a.time = Some(f64::NAN),
                "--time NaN: expected a finite time >= 0 (seconds)",
            ),
            (
                |a| a.time = Some(-1.0),
                "--time -1.0: expected a finite time >= 0 (seconds)",
            ),
            (|a| a.fuse = 0, "--fuse 0: expected 1..=300 frames"),
            (|a| a.fuse = 301, "--fuse 301: expected 1..=300 frames"),
        ];
        for (set, want) in cases {
            let mut a = png_args(dir.path());
            set(&mut a);
            // Refused before any file is read (none of them exists).
            assert_eq!(run(a).unwrap_err().to_string(), want);
        }
        let mut a = png_args(dir.path());
        a.time = Some(0.0);
        a.fuse = MAX_FUSE;
        check_numbers(&a).unwrap();
    }

    #[test]
    fn implausible_intrinsics_files_are_refused_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let k = small_intrinsics();
        symcorr_kinect::write_depth_png16(dir.path().join("d.png"), &sphere_frame(&k)).unwrap();
        let mut p = [[0.0; 3]; 20];
        for (i, q) in p.iter_mut().enumerate() {
            let t = i as f64 / 19.0;
            *q = [0.2 * (2.0 * t - 1.0), 0.2 - 0.4 * t, 2.45 + 0.1 * t];
        }
        symcorr_kinect::write_joints_json(
            dir.path().join("j.json"),
            &JointLog::from_skeletons(vec![Skeleton::from_arrays(p)], 30.0),
        )
        .unwrap();
        for (field, value, want) in [
            (
                "fx",
                "1e308",
                "fx = 1e308: expected a focal length in 1..=100000 px",
            ),
            (
                "fy",
                "0.0",
                "fy = 0.0: expected a focal length in 1..=100000 px",
            ),
            (
                "cx",
                "5000.0",
                "cx = 5000.0: expected a principal point in -80..=240 px",
            ),
        ] {
            let text = serde_json::to_string(&k).unwrap().replace(
                &format!(
                    "\"{field}\":{}",
                    if field == "cx" { "80.0" } else { "142.8" }
                ),
                &format!("\"{field}\":{value}"),
            );
            std::fs::write(dir.path().join("k.json"), text).unwrap();
            let e = run(png_args(dir.path())).unwrap_err().to_string();
            assert!(
                e.contains("k.json: invalid intrinsics: ") && e.contains(want),
                "{e}"
            );
            assert!(!dir.path().join("scan.ply").exists());
        }
    }

    #[test]
    fn fov_gives_the_pinhole_focal_length() {
        let f = DepthFrame::new(640, 480, vec![0; 640 * 480]).unwrap();
        let k = stream_intrinsics(
            None,
            &f,
            Some((58.5f32.to_radians(), 45.6f32.to_radians())),
            None,
        );
        assert!((k.fx - 571.26).abs() < 1.0, "{}", k.fx);
        let nominal = stream_intrinsics(None, &f, None, None);
        assert_eq!(nominal, Intrinsics::kinect_v1());
        // A stream whose mirroring is off is read as the lens forms it.
        let direct = stream_intrinsics(None, &f, None, Some(false));
        assert_eq!(direct.mirroring, symcorr_kinect::Mirroring::Direct);
        assert_eq!(stream_intrinsics(None, &f, None, Some(true)), nominal);
    }
}
