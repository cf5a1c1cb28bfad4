//! The refined method's stages without the `symcorr` driver: landmark initial map, then
//! segment-constrained ZoomOut, on a dataset whose ground truth is the identity. See `--help`
//! and experiments/README.md.

use faer::Mat;
use nalgebra::{Point3, Vector3};
use std::collections::BTreeMap;
use std::error::Error;
use std::path::{Path, PathBuf};
use std::time::Instant;
use symcorr_attach::{attach, AttachOptions, BodySide, Segment, Skeleton};
use symcorr_correspond::*;
use symcorr_eval::{evaluate, EvalGraph};
use symcorr_mesh::TriMesh;
use symcorr_spectral::*;

/// The refined method's stages: landmark initial map, then segment-constrained ZoomOut.
///
/// Reads a dataset in DESIGN.md's layout whose ground truth is the identity (meshes/NAME.ply,
/// joints/NAME.json, pairs.txt, mirror.txt), prepares each mesh (eigenpairs, si-HKS over the
/// area-relative window τ = −8..3, attachment, heat-geodesic landmark coordinates, midline
/// halves) and, for each pair, prints the mean geodesic error (over the target's √area) and
/// the flip rate of the initial map (nearest landmark/si-HKS features within segment pools)
/// and of the ZoomOut map, the ZoomOut map's coverage of the target, and timings; the last
/// line (`ALL`) is over every pair.
#[derive(clap::Parser, Debug)]
#[command(name = "refine_eval", verbatim_doc_comment)]
struct Args {
    /// Dataset folder.
    dataset: PathBuf,
    /// Only the first MAX_PAIRS pairs of pairs.txt.
    max_pairs: Option<usize>,
    /// Laplace–Beltrami eigenpairs per mesh.
    #[arg(long, value_name = "K", default_value_t = 60)]
    eigenpairs: usize,
    /// ZoomOut: size of the first functional map.
    #[arg(long, value_name = "K", default_value_t = 20)]
    k_start: usize,
    /// ZoomOut: size of the last functional map.
    #[arg(long, value_name = "K", default_value_t = 60)]
    k_end: usize,
    /// ZoomOut: basis growth per iteration.
    #[arg(long, default_value_t = 4)]
    step: usize,
    /// ZoomOut: weight of the anchor (landmark/si-HKS) features in every point-map recovery
    /// (0 = plain ZoomOut).
    #[arg(long, value_name = "W", default_value_t = 0.0)]
    anchor_weight: f64,
    /// ZoomOut: at most this many template vertices in the iterations.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_ZOOMOUT_POINTS)]
    max_points: usize,
    /// Segment pools: a target vertex within BAND·√area (geodesic) of a segment also serves it.
    #[arg(long, default_value_t = 0.02)]
    band: f64,
    /// Weight of the si-HKS columns (each scaled by its standard deviation over all meshes)
    /// next to the landmark coordinates in the initial map's features.
    #[arg(long, value_name = "W", default_value_t = 0.0)]
    si_hks_weight: f64,
    /// Landmarks: `ring` (skeleton rings and tips), `point` (the vertex nearest each joint) or
    /// `both`.
    #[arg(long, value_enum, default_value_t = Landmarks::Ring)]
    landmarks: Landmarks,
    /// Ring landmarks: slab half-width in mean edge lengths.
    #[arg(long, default_value_t = 1.0)]
    slab: f64,
    /// Midline halves from joint planes refined by the surface's symmetry: `none`, `head`, or
    /// `all` (head, torso and pelvis).
    #[arg(long, value_enum, default_value_t = Symmetry::None)]
    symmetry: Symmetry,
    /// Drop the halves from ZoomOut's pools (the initial map keeps them): `none`, `head`, `all`.
    #[arg(long, value_enum, default_value_t = Symmetry::None)]
    zoomout_free_halves: Symmetry,
    /// Shuffle the target meshes' vertex ids with a fixed permutation (ground truth and mirror
    /// map follow): the method must not rely on shared vertex order.
    #[arg(long)]
    permute: bool,
    /// After each pair, the mean error per template segment: `name:initial/zoomout(points)`.
    #[arg(long)]
    segments: bool,
    /// Write PREFIX_A_B.txt per pair: `vertex match error segment` per template vertex.
    #[arg(long, value_name = "PREFIX")]
    dump: Option<String>,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum Landmarks {
    Ring,
    Point,
    Both,
}

/// Which midline segments a half option concerns.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum Symmetry {
    None,
    Head,
    All,
}

struct Prep {
    mesh: TriMesh,
    area: f64,
    vectors: Mat<f64>,
    mass: Vec<f64>,
    sihks: Mat<f64>,
    labels: Vec<Segment>,
    halves: Vec<BodySide>,
    landmarks: Mat<f64>,
    graph: EdgeGraph,
    secs: f64,
}

fn halves(mesh: &TriMesh, labels: &[Segment], j: &Skeleton, sym: Symmetry) -> Vec<i8> {
    // The pipeline's joint planes, from their one owner.
    let planes = symcorr_attach::SagittalPlanes::of(j);
    let plane = |pl: symcorr_attach::Plane| -> ([f64; 3], [f64; 3]) {
        (pl.origin.into(), pl.normal.into())
    };
    let (ho, hn) = plane(planes.pelvis);
    let (so, sn) = plane(planes.shoulders);
    let (to, tn) = plane(planes.torso);
    let fit = |seg: Segment, o: [f64; 3], n: [f64; 3]| {
        let pts: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .zip(labels)
            .filter(|(_, &l)| l == seg)
            .map(|(p, _)| *p)
            .collect();
        let stride = pts.len().div_ceil(1500).max(1);
        let pts: Vec<[f64; 3]> = pts.into_iter().step_by(stride).collect();
        refine_symmetry_plane(&pts, o, n, 10)
    };
    let (so_h, sn_h) = if sym != Symmetry::None {
        fit(Segment::Head, so, sn)
    } else {
        (so, sn)
    };
    let (to, tn) = if sym == Symmetry::All {
        fit(Segment::Torso, to, tn)
    } else {
        (to, tn)
    };
    let (ho, hn) = if sym == Symmetry::All {
        fit(Segment::Pelvis, ho, hn)
    } else {
        (ho, hn)
    };
    mesh.positions
        .iter()
        .zip(labels)
        .map(|(&x, s)| {
            let (o, n) = match s {
                Segment::Pelvis => (ho, hn),
                Segment::Torso => (to, tn),
                Segment::Head => (so_h, sn_h),
                _ => return 0,
            };
            if (Point3::from(x) - Point3::from(o)).dot(&Vector3::from(n)) >= 0.0 {
                1
            } else {
                -1
            }
        })
        .collect()
}

fn permute_mesh(mesh: &TriMesh, perm: &[u32]) -> TriMesh {
    // perm[old] = new
    let mut pos = vec![[0.0; 3]; mesh.positions.len()];
    for (o, &nw) in perm.iter().enumerate() {
        pos[nw as usize] = mesh.positions[o];
    }
    let tris = mesh
        .triangles
        .iter()
        .map(|t| {
            [
                perm[t[0] as usize],
                perm[t[1] as usize],
                perm[t[2] as usize],
            ]
        })
        .collect();
    TriMesh::new(pos, tris).expect("a permutation keeps a valid mesh valid")
}

fn prepare(mesh: TriMesh, sk: &Skeleton, args: &Args) -> Result<Prep, Box<dyn Error>> {
    let t = Instant::now();
    let lap = Laplacian::new(&mesh)?;
    let eig = eigenpairs(&lap, args.eigenpairs, &EigenOptions::default())?;
    let area = mesh.total_area();
    let shift = area.ln() / 2f64.ln();
    let sihks = si_hks(
        &eig,
        &SiHksParams {
            tau_start: -8.0 + shift,
            tau_end: 3.0 + shift,
            ..SiHksParams::default()
        },
    )?;
    let att = attach(&mesh, sk, &AttachOptions::default())?;
    let heat = HeatGeodesics::with_laplacian(&mesh, &lap, 1.0)?;
    let edge = {
        let e = mesh.edges();
        e.iter()
            .map(|[a, b]| {
                nalgebra::distance(
                    &Point3::from(mesh.positions[*a as usize]),
                    &Point3::from(mesh.positions[*b as usize]),
                )
            })
            .sum::<f64>()
            / e.len() as f64
    };
    let points: Vec<Vec<u32>> = joint_landmarks(&mesh.positions, &att.joints)
        .into_iter()
        .map(|v| vec![v])
        .collect();
    let rings = skeleton_landmarks(&mesh.positions, &att.labels, &att.joints, args.slab * edge);
    let lm: Vec<Vec<u32>> = match args.landmarks {
        Landmarks::Point => points,
        Landmarks::Both => points.into_iter().chain(rings).collect(),
        Landmarks::Ring => rings,
    };
    let landmarks = landmark_coordinates(&heat, &lm, area)?;
    let halves = halves(&mesh, &att.labels, &att.joints, args.symmetry)
        .into_iter()
        .map(|h| BodySide::of_signed_distance(f64::from(h), 0.0))
        .collect();
    let graph = EdgeGraph::new(&mesh);
    Ok(Prep {
        area,
        vectors: eig.vectors,
        mass: lap.mass.clone(),
        sihks,
        labels: att.labels,
        halves,
        landmarks,
        graph,
        mesh,
        secs: t.elapsed().as_secs_f64(),
    })
}

fn features(p: &Prep, wh: f64, scale: &[f64]) -> Mat<f64> {
    let (l, h) = (p.landmarks.ncols(), p.sihks.ncols());
    Mat::from_fn(p.mesh.num_vertices(), l + h, |i, j| {
        if j < l {
            p.landmarks[(i, j)]
        } else {
            wh * p.sihks[(i, j - l)] / scale[j - l]
        }
    })
}

fn main() {
    let args = <Args as clap::Parser>::parse();
    if let Err(e) = run(&args) {
        eprintln!("refine_eval: {e}");
        std::process::exit(1);
    }
}

/// Reads a text file, naming it in the error.
fn read_text(path: &Path) -> Result<String, String> {
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))
}

fn run(args: &Args) -> Result<(), Box<dyn Error>> {
    let root = args.dataset.as_path();
    let max_pairs = args.max_pairs.unwrap_or(usize::MAX);
    let zo = ZoomOutOptions {
        k_start: args.k_start,
        k_end: args.k_end,
        step: args.step,
        anchor_weight: args.anchor_weight,
        max_points: args.max_points,
    };
    let band = args.band;
    let wh = args.si_hks_weight;
    let permute = args.permute;
    let pairs_path = root.join("pairs.txt");
    let pairs: Vec<(String, String)> = read_text(&pairs_path)?
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| match l.split_whitespace().collect::<Vec<_>>()[..] {
            [a, b, ..] => Ok((a.to_string(), b.to_string())),
            _ => Err(format!("{}: not a pair: {l:?}", pairs_path.display())),
        })
        .take(max_pairs)
        .collect::<Result<_, _>>()?;
    let mirror_path = root.join("mirror.txt");
    let mirror: Vec<u32> = read_text(&mirror_path)?
        .lines()
        .map(|l| {
            l.trim()
                .parse()
                .map_err(|_| format!("{}: not a vertex id: {l:?}", mirror_path.display()))
        })
        .collect::<Result<_, _>>()?;
    let n0 = mirror.len();
    // A fixed permutation of target ids (perm[old] = new).
    let perm: Vec<u32> = {
        let mut v: Vec<u32> = (0..n0 as u32).collect();
        let mut s = 12345u64;
        for i in (1..n0).rev() {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let j = (s >> 33) as usize % (i + 1);
            v.swap(i, j);
        }
        v
    };
    let mut names: Vec<(String, bool)> = Vec::new();
    for (a, b) in &pairs {
        names.push((a.clone(), false));
        names.push((b.clone(), permute));
    }
    names.sort();
    names.dedup();
    let mut prep: BTreeMap<(String, bool), Prep> = BTreeMap::new();
    for (name, perm_it) in &names {
        let mesh_path = root.join("meshes").join(format!("{name}.ply"));
        let mesh = symcorr_mesh::io::read(&mesh_path)
            .map_err(|e| format!("{}: {e}", mesh_path.display()))?
            .mesh;
        let mesh = if *perm_it {
            permute_mesh(&mesh, &perm)
        } else {
            mesh
        };
        let joints_path = root.join("joints").join(format!("{name}.json"));
        let log = symcorr_kinect::read_joints(&joints_path)
            .map_err(|e| format!("{}: {e}", joints_path.display()))?;
        let sk = log
            .frames
            .first()
            .ok_or_else(|| format!("{}: no frame", joints_path.display()))?
            .skeleton
            .clone();
        let p = prepare(mesh, &sk, args).map_err(|e| format!("{name}: {e}"))?;
        prep.insert((name.clone(), *perm_it), p);
    }
    // si-HKS column scale: std over all meshes' values.
    let h = prep.values().next().ok_or("no pairs")?.sihks.ncols();
    let scale: Vec<f64> = (0..h)
        .map(|j| {
            let vals: Vec<f64> = prep
                .values()
                .flat_map(|p| (0..p.sihks.nrows()).map(move |i| p.sihks[(i, j)]))
                .collect();
            let m = vals.iter().sum::<f64>() / vals.len() as f64;
            (vals.iter().map(|x| (x - m).powi(2)).sum::<f64>() / vals.len() as f64).sqrt()
        })
        .collect();
    let (mut s_init, mut s_fin, mut f_init, mut f_fin, mut cnt, mut fc_i, mut fc_f) =
        (0.0, 0.0, 0, 0, 0usize, 0usize, 0usize);
    let mut secs = 0.0;
    for (a, b) in &pairs {
        let pa = &prep[&(a.clone(), false)];
        let pb = &prep[&(b.clone(), permute)];
        let t = Instant::now();
        let pools = SegmentPools::new(
            (&pa.labels, Some(&pa.halves)),
            (&pb.labels, Some(&pb.halves)),
            &pb.graph,
            band * pb.area.sqrt(),
        )?;
        let strip = |p: &Prep| -> Vec<BodySide> {
            p.halves
                .iter()
                .zip(&p.labels)
                .map(|(&h, &l)| match args.zoomout_free_halves {
                    Symmetry::Head if l == Segment::Head => BodySide::Midline,
                    Symmetry::All => BodySide::Midline,
                    _ => h,
                })
                .collect()
        };
        let (ha, hb) = (strip(pa), strip(pb));
        let zpools = SegmentPools::new(
            (&pa.labels, Some(&ha)),
            (&pb.labels, Some(&hb)),
            &pb.graph,
            band * pb.area.sqrt(),
        )?;
        let fa = features(pa, wh, &scale);
        let fb = features(pb, wh, &scale);
        let init: Vec<u32> = nearest_in_pools(fa.as_ref(), fb.as_ref(), &pools)?
            .into_iter()
            .map(|x| x.0)
            .collect();
        let t_init = t.elapsed().as_secs_f64();
        let z = zoomout(
            SpectralBasis {
                vectors: pa.vectors.as_ref(),
                mass: &pa.mass,
            },
            SpectralBasis {
                vectors: pb.vectors.as_ref(),
                mass: &pb.mass,
            },
            &init,
            &zpools,
            Some((fa.as_ref(), fb.as_ref())),
            &zo,
        )?;
        let t_pair = t.elapsed().as_secs_f64();
        let graph = EvalGraph::new(&pb.mesh);
        let truth = |p: u32| if permute { perm[p as usize] } else { p };
        let mirror_t: Vec<u32> = if permute {
            // mirror in new ids: new(i) -> new(mirror(old(i)))
            let mut inv = vec![0u32; n0];
            for (o, &nw) in perm.iter().enumerate() {
                inv[nw as usize] = o as u32;
            }
            (0..n0)
                .map(|i| perm[mirror[inv[i] as usize] as usize])
                .collect()
        } else {
            mirror.clone()
        };
        let pi: Vec<(u32, u32)> = init
            .iter()
            .enumerate()
            .map(|(p, &q)| (p as u32, q))
            .collect();
        let pf: Vec<(u32, u32)> = z
            .map
            .iter()
            .enumerate()
            .map(|(p, &q)| (p as u32, q))
            .collect();
        let ei = evaluate(&graph, pb.area, &pi, truth, Some(&mirror_t));
        let ef = evaluate(&graph, pb.area, &pf, truth, Some(&mirror_t));
        let (c1, f1) = ei.flip_counts();
        let (c2, f2) = ef.flip_counts();
        println!(
            "{a:>14} → {b:<14} init {:.4} flips {:.2}%  zoomout {:.4} flips {:.2}%  cov {:.3}  init {:.2}s pair {:.2}s prep {:.2}+{:.2}s",
            ei.mean_error(),
            100.0 * f1 as f64 / c1 as f64,
            ef.mean_error(),
            100.0 * f2 as f64 / c2 as f64,
            coverage(&z.map, pb.mesh.num_vertices()),
            t_init,
            t_pair,
            pa.secs,
            pb.secs
        );
        if let Some(path) = &args.dump {
            let text: String = ef
                .errors
                .iter()
                .enumerate()
                .map(|(p, e)| format!("{p} {} {e} {}\n", z.map[p], pa.labels[p].index()))
                .collect();
            let file = format!("{path}_{a}_{b}.txt");
            std::fs::write(&file, text).map_err(|e| format!("{file}: {e}"))?;
        }
        if args.segments {
            let mut acc = [(0.0, 0usize, 0.0); 17];
            for (p, (&e0, &e1)) in ei.errors.iter().zip(&ef.errors).enumerate() {
                let s = pa.labels[p].index();
                acc[s].0 += e0;
                acc[s].1 += 1;
                acc[s].2 += e1;
            }
            for (i, (a0, n, a1)) in acc.iter().enumerate() {
                if *n > 0 {
                    print!(
                        "{}:{:.3}/{:.3}({}) ",
                        Segment::ALL[i].name(),
                        a0 / *n as f64,
                        a1 / *n as f64,
                        n
                    );
                }
            }
            println!();
        }
        s_init += ei.errors.iter().sum::<f64>();
        s_fin += ef.errors.iter().sum::<f64>();
        cnt += ei.errors.len();
        f_init += f1;
        f_fin += f2;
        fc_i += c1;
        fc_f += c2;
        secs += t_pair + pa.secs + pb.secs;
    }
    println!(
        "ALL init {:.4} flips {:.3}%  zoomout {:.4} flips {:.3}%  s/pair {:.2}",
        s_init / cnt as f64,
        100.0 * f_init as f64 / fc_i as f64,
        s_fin / cnt as f64,
        100.0 * f_fin as f64 / fc_f as f64,
        secs / pairs.len() as f64
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{CommandFactory, Parser};

    #[test]
    fn command_line_is_well_formed() {
        Args::command().debug_assert();
    }

    #[test]
    fn defaults_are_the_former_environment_defaults() {
        let a = Args::parse_from(["refine_eval", "DS"]);
        assert_eq!((a.eigenpairs, a.k_start, a.k_end, a.step), (60, 20, 60, 4));
        assert_eq!(
            (a.anchor_weight, a.band, a.si_hks_weight, a.slab),
            (0.0, 0.02, 0.0, 1.0)
        );
        assert_eq!(a.max_points, DEFAULT_ZOOMOUT_POINTS);
        assert_eq!(a.landmarks, Landmarks::Ring);
        assert_eq!(
            (a.symmetry, a.zoomout_free_halves),
            (Symmetry::None, Symmetry::None)
        );
        assert!(!a.permute && !a.segments && a.dump.is_none() && a.max_pairs.is_none());
        let a = Args::parse_from(["refine_eval", "DS", "3", "--symmetry", "all"]);
        assert_eq!((a.max_pairs, a.symmetry), (Some(3), Symmetry::All));
    }
}
