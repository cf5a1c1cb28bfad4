//! `symcorr-synth`: synthetic bodies with ground truth and a virtual Kinect (see README.md).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use symcorr_synth::dataset::resolve_pose;
use symcorr_synth::dataset::{write_dataset, DatasetSpec, MeshFormat, ScanSpec};
use symcorr_synth::fixtures::WALK_PERIOD_S;
use symcorr_synth::kinect::{write_scan, write_sequence, CameraSampling};
use symcorr_synth::mapping::{kinect_joints, reference_labels, SelfIntersectionCheck};
use symcorr_synth::noise::JointNoise;
use symcorr_synth::poses::{interpolate, walk_pose};
use symcorr_synth::recording::{kinect_v1_intrinsics, write_recording, RecordingSpec};
use symcorr_synth::render::{Camera, Realism};
use symcorr_synth::tracker::TrackerNoise;
use symcorr_synth::{fixtures, Assets, Model, Pose, Result, Shape, SynthError};

#[derive(Parser)]
#[command(
    name = "symcorr-synth",
    version,
    about = "Synthetic human bodies with exact ground truth and a virtual Kinect"
)]
struct Cli {
    /// Folder of the MPFB2 assets (default: the project's fixtures/mpfb2).
    #[arg(long, global = true)]
    assets: Option<PathBuf>,
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Args, Clone)]
struct NoiseArgs {
    /// Gaussian joint noise, σ in centimetres per coordinate.
    #[arg(long, default_value_t = 0.0)]
    noise_sigma_cm: f64,
    /// Fraction of joints moved onto the surface (nearest vertex) before the Gaussian noise.
    #[arg(long, default_value_t = 0.0)]
    surface_fraction: f64,
    /// Fraction of joints reported with confidence 0.
    #[arg(long, default_value_t = 0.0)]
    drop_fraction: f64,
    /// Seed of the joint-noise stream.
    #[arg(long, default_value_t = 1)]
    noise_seed: u64,
}

impl NoiseArgs {
    fn noise(&self) -> Result<Option<JointNoise>> {
        let n = JointNoise {
            sigma_cm: self.noise_sigma_cm,
            surface_fraction: self.surface_fraction,
            drop_fraction: self.drop_fraction,
            seed: self.noise_seed,
        };
        let frac_ok = |x: f64| (0.0..=1.0).contains(&x);
        if !(n.sigma_cm.is_finite()
            && n.sigma_cm >= 0.0
            && frac_ok(n.surface_fraction)
            && frac_ok(n.drop_fraction))
        {
            return Err(SynthError::Invalid(
                "noise: σ must be ≥ 0 and fractions in [0, 1]".into(),
            ));
        }
        Ok((!n.is_none()).then_some(n))
    }
}

#[derive(Subcommand)]
enum Cmd {
    /// Fit symcorr-attach's MakeHuman boundary convention and write it as Rust source
    /// (tools/synth/src/convention.rs says on which bodies).
    Convention {
        /// Output file.
        #[arg(long, default_value = "crates/attach/src/convention_makehuman.rs")]
        out: PathBuf,
    },
    /// Write a benchmark dataset folder (meshes/, joints/, labels/, mirror.txt, pairs.txt).
    Dataset {
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// A shape as `NAME:target=w,target=w` (repeat; `NAME:` alone is the base shape).
        #[arg(long = "shape", required = true)]
        shapes: Vec<String>,
        /// Comma-separated poses: rest, t-pose, arms-down, arms-tight, walk-PP, random-SEED, file:PATH.
        #[arg(long, value_delimiter = ',', required = true)]
        poses: Vec<String>,
        /// Mesh format: ply (binary) or off.
        #[arg(long, default_value = "ply")]
        format: String,
        #[command(flatten)]
        noise: NoiseArgs,
        /// Make each pair's target a single-view virtual-Kinect scan (meshes/NAME_scan,
        /// joints in camera space, truth/NAME_scan.txt = body vertex per scan vertex), seen
        /// from the default camera (0, 0, 2.6) looking at (0, -0.05, 0) unless
        /// --scan-cameras draws one per body.
        #[arg(long)]
        scans: bool,
        /// Sensor realism of the scans: `ideal`, `kinect` or `kinect-v1`.
        #[arg(long, default_value = "kinect")]
        scan_realism: String,
        /// Seed of the scans' sensor noise.
        #[arg(long, default_value_t = 1)]
        scan_seed: u64,
        /// Draw each scan's camera (seeded per body by --scan-seed; written to cameras/):
        /// `frontal` (2.5–3.2 m, azimuth ±35°, 0.6–1.6 m high) or `profile` (|azimuth| 60–90°).
        /// Scan meshes then keep every component near the bones, as `symcorr` does.
        #[arg(long)]
        scan_cameras: Option<String>,
        /// Joints of the scans: `exact` (the rig's) or `tracker` (σ 2.5 cm, 4.5 cm at hands and
        /// feet, unseen joints inferred; seeded by --scan-seed).
        #[arg(long, default_value = "exact")]
        scan_joints: String,
        /// Loop-subdivide every mesh this many times (13,380 → 53,258 → 212,… vertices; the
        /// mirror map and labels are extended, the vertex order stays shared).
        #[arg(long, default_value_t = 0)]
        subdivide: u32,
        /// Make each pair's target this many Loop subdivisions finer than its template
        /// (meshes/NAME_fine, truth/NAME_fine.txt): a different triangulation per pair.
        #[arg(long, default_value_t = 0)]
        finer_targets: u32,
    },
    /// Pose one body and write its mesh, joints and labels.
    Pose {
        /// Shape as `target=w,target=w` (empty: base shape).
        #[arg(long, default_value = "")]
        shape: String,
        /// Pose: rest, t-pose, arms-down, arms-tight, walk-PP, random-SEED, file:PATH.
        #[arg(long, default_value = "rest")]
        pose: String,
        /// Output mesh (.ply or .off).
        #[arg(long)]
        out: PathBuf,
        /// Output joints (symcorr.joints/1).
        #[arg(long)]
        joints: Option<PathBuf>,
        /// Output reference labels (one per line).
        #[arg(long)]
        labels: Option<PathBuf>,
        #[command(flatten)]
        noise: NoiseArgs,
    },
    /// Render one virtual-Kinect view of a posed body (depth, per-pixel vertex ids, joints).
    Scan {
        #[command(flatten)]
        view: ViewArgs,
        /// Pose: rest, t-pose, arms-down, arms-tight, walk-PP, random-SEED, file:PATH.
        #[arg(long, default_value = "rest")]
        pose: String,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
    },
    /// Render a sequence: the walk cycle, or an interpolation between two poses.
    Sequence {
        #[command(flatten)]
        view: ViewArgs,
        /// Number of frames.
        #[arg(long, default_value_t = 30)]
        frames: usize,
        /// Frame rate (frames per second).
        #[arg(long, default_value_t = 30.0)]
        fps: f64,
        /// Interpolate Euler angles linearly from this pose … (default: walk cycle).
        #[arg(long, requires = "to")]
        from: Option<String>,
        /// … to this pose over the sequence.
        #[arg(long)]
        to: Option<String>,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
    },
    /// Write a synthetic Kinect recording (symcorr.recording/1): the body walks in place
    /// and turns to profile and back; corrupted joint log, ground truth (tools/synth/README.md).
    Recording {
        #[command(flatten)]
        view: ViewArgs,
        /// Number of frames.
        #[arg(long, default_value_t = 300)]
        frames: usize,
        /// Frame rate of the depth and joint streams (frames per second).
        #[arg(long, default_value_t = 30.0)]
        fps: f64,
        /// Depth image width in pixels (Kinect v1 field of view).
        #[arg(long, default_value_t = 640)]
        width: u32,
        /// Depth image height in pixels.
        #[arg(long, default_value_t = 480)]
        height: u32,
        /// Largest turn about the vertical axis, reached halfway (degrees; 90 = profile).
        #[arg(long, default_value_t = 90.0, allow_negative_numbers = true)]
        max_turn_deg: f64,
        /// Largest turn of the head against the chest (degrees, a look left and right every
        /// 3 s; 0: the head turns with the chest).
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        head_turn_deg: f64,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Also write the depth frames as an OpenNI2 recording (.oni) at this path.
        #[arg(long, value_name = "FILE")]
        oni: Option<PathBuf>,
        /// Write the depth images as the lens forms them (`"mirrored": false` in
        /// intrinsics.json), as the Azure Kinect and Orbbec SDKs and RealSense deliver them,
        /// instead of mirrored as the Kinect SDK's.
        #[arg(long)]
        unmirrored: bool,
        /// A lens distortion (OpenCV's `distCoeffs`: k1,k2,p1,p2[,k3[,k4,k5,k6]]), applied by
        /// the virtual camera and written to intrinsics.json.
        #[arg(
            long,
            value_name = "K1,K2,P1,P2[,K3[,K4,K5,K6]]",
            value_delimiter = ',',
            allow_negative_numbers = true,
            conflicts_with = "oni"
        )]
        distortion: Option<Vec<f64>>,
        /// Another camera's intrinsics (`symcorr.intrinsics/1`: an Azure Kinect depth mode, a
        /// Kinect v2, a RealSense), rendered through and written to intrinsics.json; they
        /// replace `--width`, `--height`, `--unmirrored` and `--distortion`.
        #[arg(
            long,
            value_name = "K.json",
            conflicts_with_all = ["width", "height", "unmirrored", "distortion"]
        )]
        intrinsics: Option<PathBuf>,
    },
    /// Write a recording folder's depth frames, times and intrinsics as an OpenNI2 recording
    /// (.oni) that OpenNI2's file player plays (`symcorr track` reads either).
    Oni {
        /// The recording folder (intrinsics.json, depth/, depth_times.txt).
        recording: PathBuf,
        /// The .oni file to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Regenerate the committed fixture set (fixtures/synth) bit for bit.
    Fixtures {
        /// Output folder (the committed set lives in fixtures/synth).
        #[arg(long)]
        out: PathBuf,
    },
}

#[derive(Args, Clone)]
struct ViewArgs {
    /// Shape as `target=w,target=w` (empty: base shape).
    #[arg(long, default_value = "")]
    shape: String,
    /// Camera position `x,y,z` in the body frame (metres; the subject faces +z).
    #[arg(long, value_delimiter = ',', default_values_t = [0.0, 0.0, 2.6])]
    camera: Vec<f64>,
    /// Point the camera looks at, `x,y,z`.
    #[arg(long, value_delimiter = ',', default_values_t = [0.0, -0.05, 0.0])]
    look_at: Vec<f64>,
    /// Sensor realism: `ideal`, `kinect` (noise, quantisation, dropout, floor, wall) or
    /// `kinect-v1` (also IR shadow, flying pixels, random dropout; tools/synth/README.md).
    #[arg(long, default_value = "kinect")]
    realism: String,
    /// Seed of the sensor noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

impl ViewArgs {
    fn camera(&self) -> Result<Camera> {
        let v3 = |v: &[f64]| -> Result<[f64; 3]> {
            match v {
                [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
                _ => Err(SynthError::Invalid(
                    "camera and look-at need 3 finite numbers".into(),
                )),
            }
        };
        let (p, l) = (v3(&self.camera)?, v3(&self.look_at)?);
        if p == l {
            return Err(SynthError::Invalid(
                "camera position equals look-at point".into(),
            ));
        }
        Ok(Camera::kinect_v1(p, l))
    }
    fn realism(&self) -> Result<Realism> {
        Realism::preset(&self.realism, self.seed).ok_or_else(|| {
            SynthError::Invalid(format!(
                "--realism {}: expected ideal, kinect or kinect-v1",
                self.realism
            ))
        })
    }
}

fn parse_named_shape(s: &str) -> Result<(String, Shape)> {
    let (name, spec) = s
        .split_once(':')
        .ok_or_else(|| SynthError::Invalid(format!("--shape `{s}`: expected NAME:target=w,...")))?;
    if name.is_empty() {
        return Err(SynthError::Invalid(format!("--shape `{s}`: empty name")));
    }
    Ok((name.to_string(), Shape::parse(spec)?))
}

fn load_model(assets: &Option<PathBuf>) -> Result<Model> {
    let dir = assets.clone().unwrap_or_else(Assets::default_dir);
    Model::new(Assets::load(&dir)?)
}

fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

/// Writes recording folder `dir` as an `.oni` file at `out`, and says so.
fn write_oni(dir: &Path, out: &Path) -> Result<()> {
    let rec =
        symcorr_kinect::Recording::open(dir).map_err(|e| SynthError::Invalid(e.to_string()))?;
    let bytes = symcorr_kinect::oni_write::write_recording_oni(&rec, 0..rec.len(), out)?;
    eprintln!(
        "{}: {} depth frames of {}, {bytes} bytes",
        out.display(),
        rec.len(),
        dir.display()
    );
    Ok(())
}

/// The recording's camera from the Kinect-v1 options: its field of view at `width × height`,
/// mirrored unless `unmirrored`, through `distortion` (OpenCV's `distCoeffs`) when given.
fn recording_intrinsics(
    width: u32,
    height: u32,
    unmirrored: bool,
    distortion: Option<Vec<f64>>,
) -> Result<symcorr_kinect::Intrinsics> {
    let mut intrinsics = kinect_v1_intrinsics(width, height)?;
    if unmirrored {
        intrinsics.mirroring = symcorr_kinect::Mirroring::Direct;
    }
    if let Some(c) = distortion {
        intrinsics.distortion = Some(
            symcorr_kinect::Distortion::from_opencv(&c)
                .map_err(|e| SynthError::Invalid(format!("--distortion: {e}")))?,
        );
        intrinsics
            .validate()
            .map_err(|e| SynthError::Invalid(format!("--distortion: {e}")))?;
    }
    Ok(intrinsics)
}

fn run(cli: Cli) -> Result<()> {
    // Converting a recording needs no body model.
    let cmd = match cli.cmd {
        Cmd::Oni { recording, out } => return write_oni(&recording, &out),
        cmd => cmd,
    };
    let model = load_model(&cli.assets)?;
    match cmd {
        Cmd::Dataset {
            out,
            shapes,
            poses,
            format,
            noise,
            scans,
            scan_realism,
            scan_seed,
            scan_cameras,
            scan_joints,
            subdivide,
            finer_targets,
        } => {
            let scans = if scans {
                let realism = Realism::preset(&scan_realism, scan_seed).ok_or_else(|| {
                    SynthError::Invalid(format!(
                        "--scan-realism {scan_realism}: expected ideal, kinect or kinect-v1"
                    ))
                })?;
                let cameras = match scan_cameras.as_deref() {
                    None => None,
                    Some("frontal") => Some(CameraSampling::frontal(scan_seed)),
                    Some("profile") => Some(CameraSampling::profile(scan_seed)),
                    Some(c) => {
                        return Err(SynthError::Invalid(format!(
                            "--scan-cameras {c}: expected frontal or profile"
                        )))
                    }
                };
                let tracker = match scan_joints.as_str() {
                    "exact" => None,
                    "tracker" => Some(TrackerNoise::kinect_v1(scan_seed)),
                    j => {
                        return Err(SynthError::Invalid(format!(
                            "--scan-joints {j}: expected exact or tracker"
                        )))
                    }
                };
                Some(ScanSpec {
                    near_bones: cameras.is_some(),
                    cameras,
                    tracker,
                    ..ScanSpec::fixed(
                        Camera::kinect_v1([0.0, 0.0, 2.6], [0.0, -0.05, 0.0]),
                        realism,
                    )
                })
            } else {
                None
            };
            let format = match format.as_str() {
                "ply" => MeshFormat::Ply,
                "off" => MeshFormat::Off,
                f => {
                    return Err(SynthError::Invalid(format!(
                        "--format {f}: expected ply or off"
                    )))
                }
            };
            let spec = DatasetSpec {
                shapes: shapes
                    .iter()
                    .map(|s| parse_named_shape(s))
                    .collect::<Result<_>>()?,
                poses,
                format,
                noise: noise.noise()?,
                command: command_line(),
                share_meshes_with: None,
                scans,
                subdivide,
                finer_targets,
            };
            let s = write_dataset(&model, &spec, &out)?;
            eprintln!(
                "{}: {} bodies, {} pairs",
                out.display(),
                s.bodies.len(),
                s.pairs
            );
        }
        Cmd::Pose {
            shape,
            pose,
            out,
            joints,
            labels,
            noise,
        } => {
            fixtures::write_single(
                &model,
                &Shape::parse(&shape)?,
                &pose,
                &out,
                joints.as_deref(),
                labels.as_deref(),
                noise.noise()?,
            )?;
        }
        Cmd::Scan { view, pose, out } => {
            let base = model.body(&Shape::default())?;
            let labels = reference_labels(&base)?;
            let check = SelfIntersectionCheck::new(&base.rest.triangles, &labels);
            let body = model.body(&Shape::parse(&view.shape)?)?;
            let pose = resolve_pose(&model, &body, &check, &pose)?;
            let posed = body.pose(&pose)?;
            std::fs::create_dir_all(&out)
                .map_err(|e| SynthError::Invalid(format!("{}: {e}", out.display())))?;
            symcorr_mesh::io::write(out.join("body.ply"), &posed.mesh, None)?;
            let joints = kinect_joints(&body, &posed)?;
            write_scan(
                &out,
                &posed.mesh,
                &joints,
                &view.camera()?,
                &view.realism()?,
                "body.ply",
            )?;
        }
        Cmd::Sequence {
            view,
            frames,
            fps,
            from,
            to,
            out,
        } => {
            if frames == 0 || !(fps.is_finite() && fps > 0.0) {
                return Err(SynthError::Invalid(
                    "--frames must be ≥ 1 and --fps > 0".into(),
                ));
            }
            let base = model.body(&Shape::default())?;
            let labels = reference_labels(&base)?;
            let check = SelfIntersectionCheck::new(&base.rest.triangles, &labels);
            let body = model.body(&Shape::parse(&view.shape)?)?;
            let poses: Vec<Pose> = match (from, to) {
                (Some(a), Some(b)) => {
                    let a = resolve_pose(&model, &body, &check, &a)?;
                    let b = resolve_pose(&model, &body, &check, &b)?;
                    (0..frames)
                        .map(|f| {
                            interpolate(
                                &a,
                                &b,
                                if frames > 1 {
                                    f as f64 / (frames - 1) as f64
                                } else {
                                    0.0
                                },
                            )
                        })
                        .collect()
                }
                _ => (0..frames)
                    .map(|f| walk_pose(model.assets.walk.as_ref(), f as f64 / fps / WALK_PERIOD_S))
                    .collect(),
            };
            write_sequence(&out, &body, &poses, fps, &view.camera()?, &view.realism()?)?;
        }
        Cmd::Recording {
            view,
            frames,
            fps,
            width,
            height,
            max_turn_deg,
            head_turn_deg,
            out,
            oni,
            unmirrored,
            distortion,
            intrinsics,
        } => {
            let intrinsics = match intrinsics {
                Some(path) => symcorr_kinect::Intrinsics::read(&path)
                    .map_err(|e| SynthError::Invalid(format!("--intrinsics: {e}")))?,
                None => recording_intrinsics(width, height, unmirrored, distortion)?,
            };
            let camera = Camera {
                intrinsics,
                ..view.camera()?
            };
            let body = model.body(&Shape::parse(&view.shape)?)?;
            let spec = RecordingSpec {
                frames,
                fps,
                max_turn_deg,
                head_turn_deg,
                seed: view.seed,
                // Without the binary's path, so that the manifest does not depend on the build.
                command: std::iter::once("symcorr-synth".to_string())
                    .chain(std::env::args().skip(1))
                    .collect::<Vec<_>>()
                    .join(" "),
            };
            let s = write_recording(
                &out,
                &body,
                model.assets.walk.as_ref(),
                &spec,
                &camera,
                &view.realism()?,
            )?;
            eprintln!(
                "{}: {} frames, leg swaps {:?}, lost body {:?}",
                out.display(),
                s.frames,
                s.swaps,
                s.lost_body_frames
            );
            if let Some(oni) = oni {
                write_oni(&out, &oni)?;
            }
        }
        Cmd::Oni { recording, out } => write_oni(&recording, &out)?,
        Cmd::Fixtures { out } => fixtures::write_fixtures(&model, Path::new(&out))?,
        Cmd::Convention { out } => {
            let c = symcorr_synth::convention::fit_makehuman(&model)?;
            std::fs::write(&out, symcorr_synth::convention::rust_table(&c)).map_err(|e| {
                SynthError::Io {
                    path: out.clone(),
                    source: e,
                }
            })?;
            eprintln!(
                "{} boundary rules written to {}",
                c.rules.len(),
                out.display()
            );
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("symcorr-synth: {e}");
            ExitCode::from(1)
        }
    }
}
