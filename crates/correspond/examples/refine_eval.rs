//! Developer experiment: landmark initial map + segment-constrained ZoomOut on a dataset in
//! DESIGN.md's layout (ground truth = identity), without the `symcorr` driver.
//!
//! `cargo run --release -p symcorr-correspond --example refine_eval -- DATASET [MAX_PAIRS]`
//! Environment knobs: `K` (eigenpairs, 60), `KS`/`KE`/`STEP` (ZoomOut), `BAND` (√area units),
//! `WH` (si-HKS weight), `PERMUTE=1` (shuffle target vertex ids, ground truth follows).

use faer::Mat;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;
use symcorr_attach::{attach, AttachOptions};
use symcorr_correspond::*;
use symcorr_mesh::TriMesh;
use symcorr_skeleton::{Joint, Segment, Skeleton};
use symcorr_spectral::*;

fn env<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

struct Prep {
    mesh: TriMesh,
    area: f64,
    vectors: Mat<f64>,
    mass: Vec<f64>,
    sihks: Mat<f64>,
    labels: Vec<Segment>,
    halves: Vec<i8>,
    landmarks: Mat<f64>,
    graph: EdgeGraph,
    secs: f64,
}

fn halves(mesh: &TriMesh, labels: &[Segment], j: &Skeleton) -> Vec<i8> {
    let p = |x: Joint| -> [f64; 3] { j.position(x).into() };
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let mid =
        |a: [f64; 3], b: [f64; 3]| [(a[0] + b[0]) / 2., (a[1] + b[1]) / 2., (a[2] + b[2]) / 2.];
    let unit = |v: [f64; 3]| {
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / n, v[1] / n, v[2] / n]
    };
    let hn = unit(sub(p(Joint::HipLeft), p(Joint::HipRight)));
    let ho = mid(p(Joint::HipLeft), p(Joint::HipRight));
    let sn = unit(sub(p(Joint::ShoulderLeft), p(Joint::ShoulderRight)));
    let so = mid(p(Joint::ShoulderLeft), p(Joint::ShoulderRight));
    let tn = unit([hn[0] + sn[0], hn[1] + sn[1], hn[2] + sn[2]]);
    let to = mid(ho, so);
    let sym: i32 = env("SYM", 0);
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
    let (so_h, sn_h) = if sym >= 1 {
        fit(Segment::Head, so, sn)
    } else {
        (so, sn)
    };
    let (to, tn) = if sym >= 2 {
        fit(Segment::Torso, to, tn)
    } else {
        (to, tn)
    };
    let (ho, hn) = if sym >= 2 {
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
            let d = sub(x, o);
            if d[0] * n[0] + d[1] * n[1] + d[2] * n[2] >= 0.0 {
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
    TriMesh::new(pos, tris).unwrap()
}

fn prepare(mesh: TriMesh, sk: &Skeleton, k: usize) -> Prep {
    let t = Instant::now();
    let lap = Laplacian::new(&mesh).unwrap();
    let eig = eigenpairs(&lap, k, &EigenOptions::default()).unwrap();
    let area = mesh.total_area();
    let shift = area.ln() / 2f64.ln();
    let sihks = si_hks(
        &eig,
        &SiHksParams {
            tau_start: -8.0 + shift,
            tau_end: 3.0 + shift,
            ..SiHksParams::default()
        },
    )
    .unwrap();
    let att = attach(&mesh, sk, &AttachOptions::default()).unwrap();
    let heat = HeatGeodesics::with_laplacian(&mesh, &lap, 1.0).unwrap();
    let edge = {
        let e = mesh.edges();
        e.iter()
            .map(|[a, b]| {
                let (p, q) = (mesh.positions[*a as usize], mesh.positions[*b as usize]);
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
            })
            .sum::<f64>()
            / e.len() as f64
    };
    let lm_kind: String = env("LM", "ring".to_string());
    let points: Vec<Vec<u32>> = joint_landmarks(&mesh.positions, &att.joints)
        .into_iter()
        .map(|v| vec![v])
        .collect();
    let rings = skeleton_landmarks(
        &mesh.positions,
        &att.labels,
        &att.joints,
        env("SLAB", 1.0) * edge,
    );
    let lm: Vec<Vec<u32>> = match lm_kind.as_str() {
        "point" => points,
        "both" => points.into_iter().chain(rings).collect(),
        _ => rings,
    };
    let landmarks = landmark_coordinates(&heat, &lm, area).unwrap();
    let halves = halves(&mesh, &att.labels, &att.joints);
    let graph = EdgeGraph::new(&mesh);
    Prep {
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
    }
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
    let args: Vec<String> = std::env::args().collect();
    let root = Path::new(&args[1]);
    let max_pairs: usize = args
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(usize::MAX);
    let k: usize = env("K", 60);
    let zo = ZoomOutOptions {
        k_start: env("KS", 20),
        k_end: env("KE", 60),
        step: env("STEP", 4),
        anchor_weight: env("WA", 0.0),
        max_points: env("MAXP", DEFAULT_ZOOMOUT_POINTS),
    };
    let band: f64 = env("BAND", 0.02);
    let wh: f64 = env("WH", 0.0);
    let permute: bool = env("PERMUTE", 0) == 1;
    let pairs: Vec<(String, String)> = std::fs::read_to_string(root.join("pairs.txt"))
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<&str> = l.split_whitespace().collect();
            (v[0].to_string(), v[1].to_string())
        })
        .take(max_pairs)
        .collect();
    let mirror: Vec<u32> = std::fs::read_to_string(root.join("mirror.txt"))
        .unwrap()
        .lines()
        .map(|l| l.trim().parse().unwrap())
        .collect();
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
        let mesh = symcorr_mesh::io::read(root.join("meshes").join(format!("{name}.ply")))
            .unwrap()
            .mesh;
        let mesh = if *perm_it {
            permute_mesh(&mesh, &perm)
        } else {
            mesh
        };
        let log =
            symcorr_kinect::read_joints(root.join("joints").join(format!("{name}.json"))).unwrap();
        let sk = log.frames[0].skeleton.clone();
        prep.insert((name.clone(), *perm_it), prepare(mesh, &sk, k));
    }
    // si-HKS column scale: std over all meshes' values.
    let h = prep.values().next().unwrap().sihks.ncols();
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
        )
        .unwrap();
        let zh: i32 = env("ZH", 0);
        let strip = |p: &Prep| -> Vec<i8> {
            p.halves
                .iter()
                .zip(&p.labels)
                .map(|(&h, &l)| match zh {
                    1 if l == Segment::Head => 0,
                    2 => 0,
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
        )
        .unwrap();
        let fa = features(pa, wh, &scale);
        let fb = features(pb, wh, &scale);
        let init: Vec<u32> = nearest_in_pools(fa.as_ref(), fb.as_ref(), &pools)
            .unwrap()
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
        )
        .unwrap();
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
        if let Ok(path) = std::env::var("DUMP") {
            let text: String = ef
                .errors
                .iter()
                .enumerate()
                .map(|(p, e)| format!("{p} {} {e} {}\n", z.map[p], pa.labels[p].index()))
                .collect();
            std::fs::write(format!("{path}_{a}_{b}.txt"), text).unwrap();
        }
        if env("SEG", 0) == 1 {
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
}
