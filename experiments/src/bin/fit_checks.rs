//! The measurements behind symcorr-attach's fit checks (`FitQuality`): on every body of a
//! dataset (meshes/, joints/, labels/ as in fixtures/synth/bodies), the checks' values and the
//! labels' agreement with the reference labels for the body's own joints (exact and with
//! Gaussian noise), its left and right exchanged, the joints turned about the vertical axis through
//! the hip centre, turned upside down, the joints of
//! another pose of the same subject and of another subject in the same pose.
//!
//! ```text
//! cargo run --release -p symcorr-experiments --bin fit_checks -- --bodies fixtures/synth/bodies
//! ```
//!
//! One line per (body, case): the checks (value, `*` when over its limit), whether the rotation
//! search moved the skeleton, the outcome (`ok`, `refused: check`) and, for accepted fits, the
//! share of vertices whose label equals the reference (`agree`) or its mirror twin (`mirror`).

use clap::Parser;
use nalgebra::{Point3, Rotation3, Vector3};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use symcorr_attach::{
    attach, AttachError, AttachOptions, FitCheckKind, Joint, PoorFitPolicy, Segment, Skeleton,
};
use symcorr_mesh::TriMesh;

/// Fit-check values on good and wrong joints.
#[derive(Parser, Debug)]
struct Args {
    /// A dataset folder: meshes/NAME.ply, joints/NAME.json, labels/NAME.txt (a scan NAME_scan:
    /// truth/NAME_scan.txt and its body's labels).
    #[arg(long)]
    bodies: PathBuf,
    /// Standard deviation of the joint noise case, in mesh units.
    #[arg(long, default_value_t = 0.03)]
    noise: f64,
    /// Seed of the noise.
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Only bodies whose name contains this.
    #[arg(long)]
    only: Option<String>,
    /// Turn angles about the vertical (y) axis through the skeleton's hip centre, in degrees.
    #[arg(long, value_delimiter = ',', default_values_t = vec![30.0, 90.0, 180.0])]
    turns: Vec<f64>,
}

struct Body {
    mesh: TriMesh,
    joints: Skeleton,
    /// Per vertex, the reference label (none: a scan pixel that shows no body vertex).
    labels: Vec<Option<Segment>>,
}

fn load(dir: &Path) -> Result<BTreeMap<String, Body>, String> {
    let mut out = BTreeMap::new();
    let meshes = std::fs::read_dir(dir.join("meshes")).map_err(|e| e.to_string())?;
    for e in meshes {
        let path = e.map_err(|e| e.to_string())?.path();
        let Some(name) = path.file_stem().and_then(|s| s.to_str()).map(String::from) else {
            continue;
        };
        let mesh = symcorr_mesh::io::read(&path)
            .map_err(|e| e.to_string())?
            .mesh;
        let joints =
            symcorr::io::read_skeleton(&dir.join("joints").join(format!("{name}.json")), None)
                .map_err(|e| e.to_string())?;
        // A scan (NAME_scan) has no labels of its own: its truth names the body vertex each
        // scan vertex shows, and that vertex's label is the scan vertex's.
        let body_name = name.strip_suffix("_scan").unwrap_or(&name);
        let read =
            |p: PathBuf| std::fs::read_to_string(&p).map_err(|e| format!("{}: {e}", p.display()));
        let mut text = read(dir.join("labels").join(format!("{body_name}.txt")))?;
        if body_name != name {
            let body_labels: Vec<&str> = text.split_whitespace().collect();
            let truth = read(dir.join("truth").join(format!("{name}.txt")))?;
            text = truth
                .split_whitespace()
                .map(|t| match t.parse::<i64>() {
                    // −1: a pixel that shows no body vertex (a flying pixel); never agrees.
                    Ok(-1) => Ok("-"),
                    Ok(i) => usize::try_from(i)
                        .ok()
                        .and_then(|i| body_labels.get(i).copied())
                        .ok_or_else(|| format!("{name}: bad truth {t}")),
                    Err(_) => Err(format!("{name}: bad truth {t}")),
                })
                .collect::<Result<Vec<_>, _>>()?
                .join(" ");
        }
        let labels = text
            .split_whitespace()
            .map(|t| match t {
                "-" => Ok(None),
                _ => t
                    .parse::<usize>()
                    .ok()
                    .and_then(|i| Segment::ALL.get(i).copied())
                    .map(Some)
                    .ok_or_else(|| format!("{name}: bad label {t}")),
            })
            .collect::<Result<Vec<_>, _>>()?;
        out.insert(
            name,
            Body {
                mesh,
                joints,
                labels,
            },
        );
    }
    Ok(out)
}

/// A small deterministic Gaussian source (xorshift + Box–Muller).
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    fn gauss(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

fn transformed(sk: &Skeleton, mut f: impl FnMut(Point3<f64>) -> Point3<f64>) -> Skeleton {
    let mut out = sk.clone();
    for p in out.positions.iter_mut() {
        *p = f(*p);
    }
    out
}

fn run_case(body: &Body, case: &str, joints: &Skeleton) {
    let options = AttachOptions {
        poor_fit: PoorFitPolicy::Accept,
        ..AttachOptions::default()
    };
    let a = match attach(&body.mesh, joints, &options) {
        Ok(a) => a,
        Err(AttachError::AlignmentFailed { .. }) => {
            println!("  {case:<14} refused: alignment failed");
            return;
        }
        Err(e) => {
            println!("  {case:<14} error: {e}");
            return;
        }
    };
    let fit = &a.diagnostics.fit;
    let mut line = format!("  {case:<14}");
    for k in FitCheckKind::ALL {
        match fit.check(k) {
            Some(c) => {
                line += &format!(
                    " {}={:.3}{}",
                    k.name(),
                    c.value,
                    if c.passed { " " } else { "*" }
                )
            }
            None => line += &format!(" {}=-    ", k.name()),
        }
    }
    let moved = !a.diagnostics.alignment.is_identity();
    let n = body.labels.len().min(a.labels.len()) as f64;
    let agree = a
        .labels
        .iter()
        .zip(&body.labels)
        .filter(|(x, y)| Some(**x) == **y)
        .count() as f64
        / n;
    let mirror = a
        .labels
        .iter()
        .zip(&body.labels)
        .filter(|(x, y)| y.is_some_and(|y| y != y.mirror() && **x == y.mirror()))
        .count() as f64
        / n;
    let outcome = match fit.worst() {
        None => "ok".to_string(),
        Some(c) => format!("refused: {}", c.kind.name()),
    };
    let m = &a.diagnostics.mirror;
    let cue = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.2}"));
    println!(
        "{line} score={:.2} moved={moved} swapped={} {outcome} agree={agree:.3} mirror={mirror:.3} cues(mesh {} feet {} knees {})",
        fit.score,
        m.swapped,
        cue(m.mesh_evidence),
        cue(m.skeleton_evidence),
        cue(m.knee_evidence)
    );
}

fn main() {
    let args = Args::parse();
    let bodies = match load(&args.bodies) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("fit_checks: {e}");
            std::process::exit(1);
        }
    };
    let mut noise = Noise(args.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let names: Vec<&String> = bodies.keys().collect();
    for (i, name) in names.iter().enumerate() {
        let body = &bodies[*name];
        if args
            .only
            .as_ref()
            .is_some_and(|o| !name.contains(o.as_str()))
        {
            continue;
        }
        println!("{name}");
        run_case(body, "exact", &body.joints);
        let noisy = transformed(&body.joints, |p| {
            p + Vector3::new(noise.gauss(), noise.gauss(), noise.gauss()) * args.noise
        });
        run_case(body, "noisy", &noisy);
        // Left and right exchanged, as a tracker that took the body's back for its front.
        run_case(body, "sides swapped", &body.joints.swap_sides());
        // Turned about the vertical through the skeleton's own hip centre, as a tracker that
        // misjudged the facing reports it (for a body at the origin, about the origin).
        let hip = body.joints.position(Joint::HipCenter);
        let pivot = Vector3::new(hip.x, 0.0, hip.z);
        for &deg in &args.turns {
            let r = Rotation3::from_axis_angle(&Vector3::y_axis(), deg.to_radians());
            run_case(
                body,
                &format!("turned {deg}"),
                &transformed(&body.joints, |p| r * (p - pivot) + pivot),
            );
        }
        let flip = Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI);
        run_case(
            body,
            "upside down",
            &transformed(&body.joints, |p| flip * p),
        );
        // Another pose of the same subject, and the same pose of another subject.
        let (subject, pose) = name.split_once('_').unwrap_or((name, ""));
        if let Some(other) = names
            .iter()
            .cycle()
            .skip(i + 1)
            .take(names.len())
            .find(|n| n.starts_with(subject) && **n != *name)
        {
            run_case(body, "other pose", &bodies[*other].joints);
        }
        if let Some(other) = names
            .iter()
            .find(|n| n.ends_with(&format!("_{pose}")) && !n.starts_with(subject))
        {
            run_case(body, "other subject", &bodies[*other].joints);
        }
    }
}
