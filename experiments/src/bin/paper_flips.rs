//! Where the paper pipeline's flips come from: every variant of the matching options on every
//! pair of a dataset with the rig's reference labels, flips classified by cause. See `--help`
//! and experiments/README.md.

use nalgebra::{Point3, Vector3};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;
use symcorr::io::{read_mesh, read_skeleton};
use symcorr::{Method, Mode, Pipeline, PipelineOptions, PreparedMesh};
use symcorr_attach::{BodySide, Joint, Segment};
use symcorr_correspond::{
    candidates, match_points, refine_symmetry_plane, select, skeleton_filter, Candidate,
    MatchOptions, PaperFilter,
};
use symcorr_eval::{evaluate, Dataset, EvalGraph};

struct Mesh {
    p: PreparedMesh,
    reference: Vec<Segment>,
    graph: EvalGraph,
    /// Signed distance over √area (0 on limbs) to the segment's plane: joint planes, refined by
    /// symmetry for the segments of bit mask k (1 pelvis, 2 torso, 4 head).
    sd: Vec<Vec<f64>>,
    /// Per plane set and segment, the 90th percentile of |sd| (half-width).
    width: Vec<[f64; 17]>,
}

/// The joint planes of `symcorr::midline_halves` (refined by the surface's symmetry with
/// `sym`), as signed distances over √area.
fn signed_distances(m: &PreparedMesh, sym: u8, skull_t: f64) -> Vec<f64> {
    let j = &m.attachment.joints;
    let p = |x: Joint| j.position(x);
    // The pipeline's joint planes, from their one owner.
    let planes = symcorr_attach::SagittalPlanes::of(j);
    let plane = |pl: symcorr_attach::Plane| -> ([f64; 3], [f64; 3]) {
        (pl.origin.into(), pl.normal.into())
    };
    let (ho, hn) = plane(planes.pelvis);
    let (so, sn) = plane(planes.shoulders);
    let (to, tn) = plane(planes.torso);
    let fit = |seg: Segment, o: [f64; 3], n: [f64; 3]| {
        let bit = match seg {
            Segment::Pelvis => 1,
            Segment::Torso => 2,
            _ => 4,
        };
        if sym & bit == 0 {
            return (o, n);
        }
        let pts: Vec<[f64; 3]> = m
            .mesh
            .positions
            .iter()
            .zip(m.labels())
            .filter(|(_, &l)| l == seg)
            .map(|(x, _)| *x)
            .collect();
        let stride = pts.len().div_ceil(1500).max(1);
        let pts: Vec<[f64; 3]> = pts.into_iter().step_by(stride).collect();
        refine_symmetry_plane(&pts, o, n, 10)
    };
    let (ho, hn) = fit(Segment::Pelvis, ho, hn);
    let (to, tn) = fit(Segment::Torso, to, tn);
    let (so, sn) = fit(Segment::Head, so, sn);
    // Bit 8: the skull (head vertices beyond half the neck→head bone) gets its own plane,
    // fitted by symmetry on the skull alone, starting at the head joint.
    let (sc, hj) = (p(Joint::ShoulderCenter), p(Joint::Head));
    let bone = hj - sc;
    let bl2 = bone.norm_squared();
    let tpos = |x: [f64; 3]| (Point3::from(x) - sc).dot(&bone) / bl2;
    let skull = if sym & 8 != 0 {
        let pts: Vec<[f64; 3]> = m
            .mesh
            .positions
            .iter()
            .zip(m.labels())
            .filter(|(x, &l)| l == Segment::Head && tpos(**x) > skull_t)
            .map(|(x, _)| *x)
            .collect();
        let stride = pts.len().div_ceil(1500).max(1);
        let pts: Vec<[f64; 3]> = pts.into_iter().step_by(stride).collect();
        Some(refine_symmetry_plane(&pts, hj.into(), sn, 10))
    } else {
        None
    };
    let s = m.area.sqrt();
    m.mesh
        .positions
        .iter()
        .zip(m.labels())
        .map(|(&x, l)| {
            let (o, n) = match l {
                Segment::Pelvis => (ho, hn),
                Segment::Torso => (to, tn),
                Segment::Head => match skull {
                    Some(pl) if tpos(x) > skull_t => pl,
                    _ => (so, sn),
                },
                _ => return 0.0,
            };
            (Point3::from(x) - Point3::from(o)).dot(&Vector3::from(n)) / s
        })
        .collect()
}

/// `labels/NAME.txt`: one segment index per line.
fn read_labels(path: &Path) -> Result<Vec<Segment>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    text.lines()
        .enumerate()
        .map(|(i, l)| {
            l.trim()
                .parse()
                .ok()
                .and_then(Segment::from_index)
                .ok_or_else(|| format!("{}:{}: not a segment index: {l:?}", path.display(), i + 1))
        })
        .collect()
}

#[derive(Default, Clone, Copy)]
struct Rule {
    /// Refine these segments' planes by symmetry (1 pelvis, 2 torso, 4 head).
    sym: u8,
    /// Halves (signs) from the chosen planes instead of `PreparedMesh::halves`.
    own_halves: bool,
    /// Normalise by the segment's half-width instead of √area.
    width: bool,
    /// Keep a candidate when |s(q) − s(p)| ≤ diff.
    diff: Option<f64>,
    /// Keep a candidate when s(q)·sign(s(p)) ≥ ratio·|s(p)|.
    ratio: Option<f64>,
    /// Selection term λ·|s(q) − s(p)|.
    lambda: f64,
    /// The library's sagittal band (ratio 0.5) on the library's coordinates.
    libband: bool,
    /// Limbs: keep a candidate when its position along the segment's bone chain differs from
    /// the point's by at most this fraction of the chain.
    axial: Option<f64>,
    /// Filter first: the N nearest descriptors among the *compatible* target vertices (same
    /// segment and half), instead of the compatible survivors of the N nearest overall.
    first: Option<usize>,
    /// Spatially diverse candidates: walk the compatible target vertices by descriptor
    /// distance and skip one within this distance (over √area) of a candidate already taken.
    diverse: Option<f64>,
    /// Adaptive widening: a point whose best eq. 8 gap exceeds this gets `widen` candidates.
    gap: Option<f64>,
    /// See `gap`.
    widen: usize,
    /// Reverse nearest neighbours: keep a candidate `q` of `p` only if `p` is among the `k`
    /// template vertices nearest `q` in descriptor space (hubs are near many points but have
    /// only `k` reverse neighbours); a point whose candidates all fail keeps them.
    reverse: Option<usize>,
}

/// Position along the segment's chain (first joint → last joint), 0..1, per vertex (0 on
/// midline segments).
fn axial(m: &PreparedMesh) -> Vec<f64> {
    let j = &m.attachment.joints;
    m.mesh
        .positions
        .iter()
        .zip(m.labels())
        .map(|(&x, &l)| {
            if matches!(l, Segment::Pelvis | Segment::Torso | Segment::Head) {
                return 0.0;
            }
            let b = l.bones();
            let (a, c) = (j.position(b[0].parent), j.position(b[b.len() - 1].child));
            let d = c - a;
            (Point3::from(x) - a).dot(&d) / d.norm_squared()
        })
        .collect()
}

/// Parses a variant (parts joined by `+`, see `Args::variants`) into the library's matching
/// options and, for the custom parts, a [`Rule`] applied by [`custom`].
fn variant(name: &str) -> Result<(MatchOptions, Option<Rule>), String> {
    let mut o = MatchOptions::default();
    let mut r = Rule::default();
    let mut custom = false;
    for part in name.split('+') {
        let num = |pre: &str| part.strip_prefix(pre).and_then(|x| x.parse::<f64>().ok());
        match part {
            "base" => {}
            "paper" => o.filter = PaperFilter::Strict,
            "noband" => {
                o.filter = PaperFilter::Extended {
                    sagittal_ratio: None,
                }
            }
            "off" => o.filter = PaperFilter::Off,
            "sym" => r.sym = 7,
            "own" => r.own_halves = true,
            "w" => r.width = true,
            "c" => custom = true,
            "lib" => r.libband = true,
            _ => {
                let bad = || format!("variant {name:?}: bad part {part:?}");
                if let Some(x) = part.strip_prefix("band") {
                    o.filter = PaperFilter::Extended {
                        sagittal_ratio: Some(x.parse().map_err(|_| bad())?),
                    };
                    continue;
                }
                if let Some(n) = part.strip_prefix('n') {
                    o.candidates.nearest = Some(n.parse().map_err(|_| bad())?);
                    continue;
                } else if let Some(x) = num("s") {
                    r.sym = x as u8;
                } else if let Some(x) = num("d") {
                    r.diff = Some(x);
                } else if let Some(x) = num("r") {
                    r.ratio = Some(x);
                } else if let Some(x) = num("a") {
                    r.axial = Some(x);
                } else if let Some(x) = num("l") {
                    r.lambda = x;
                } else if let Some(x) = num("f") {
                    r.first = Some(x as usize);
                } else if let Some(x) = num("x") {
                    r.diverse = Some(x);
                } else if let Some(x) = num("g") {
                    r.gap = Some(x);
                } else if let Some(x) = num("w") {
                    r.widen = x as usize;
                } else if let Some(x) = num("k") {
                    r.reverse = Some(x as usize);
                } else {
                    return Err(format!("variant {name:?}: unknown part {part:?}"));
                }
            }
        }
        if !["base", "paper", "off", "noband"].contains(&part)
            && !part.starts_with('n')
            && !part.starts_with("band")
        {
            custom = true;
        }
    }
    Ok((o, custom.then_some(r)))
}

/// Every target vertex compatible with template point `p` (same segment, not the other
/// half), nearest descriptor first.
fn compatible_by_descriptor(
    ta: &PreparedMesh,
    tb: &PreparedMesh,
    halves: (&[BodySide], &[BodySide]),
    p: usize,
) -> Vec<Candidate> {
    let lp = ta.labels()[p];
    let mut all: Vec<Candidate> = (0..tb.num_vertices())
        .filter(|&q| tb.labels()[q] == lp && !halves.0[p].opposes(halves.1[q]))
        .map(|q| Candidate {
            vertex: q as u32,
            distance: pd(ta).descriptors.distance(p, &pd(tb).descriptors, q),
        })
        .collect();
    all.sort_by(|a, b| a.distance.total_cmp(&b.distance));
    all
}

/// candidates → skeleton filter (halves) → sagittal rule → selection.
fn custom(ma: &Mesh, mb: &Mesh, points: &[u32], o: &MatchOptions, r: &Rule) -> Vec<(u32, u32)> {
    let (ta, tb) = (&ma.p, &mb.p);
    let k = r.sym as usize;
    let (sa, sb) = (&ma.sd[k], &mb.sd[k]);
    let norm = |m: &Mesh, s: &[f64], v: usize| {
        let l = m.p.labels()[v];
        if r.width {
            s[v] / m.width[k][l.index()]
        } else {
            s[v]
        }
    };
    let sign = |x: f64| BodySide::of_signed_distance(x, 0.0);
    let own: (Vec<BodySide>, Vec<BodySide>) = (
        sa.iter().map(|&x| sign(x)).collect(),
        sb.iter().map(|&x| sign(x)).collect(),
    );
    let halves = if r.own_halves {
        (&own.0[..], &own.1[..])
    } else {
        (&pd(ta).halves[..], &pd(tb).halves[..])
    };
    let mut cands = candidates(
        &pd(ta).descriptors,
        &pd(tb).descriptors,
        points,
        &o.candidates,
    )
    .unwrap();
    skeleton_filter(
        &mut cands,
        points,
        (ta.labels(), tb.labels()),
        Some(halves),
        &pd(ta).descriptors,
        &pd(tb).descriptors,
    );
    if r.first.is_some() || r.diverse.is_some() {
        let n = r
            .first
            .or(o.candidates.nearest)
            .unwrap_or(symcorr_correspond::DEFAULT_NEAREST);
        let s = mb.p.area.sqrt();
        let pos = &tb.mesh.positions;
        use rayon::prelude::*;
        cands = points
            .par_iter()
            .map(|&p| {
                let all = compatible_by_descriptor(ta, tb, halves, p as usize);
                let mut out: Vec<Candidate> = Vec::new();
                for c in all {
                    if out.len() == n {
                        break;
                    }
                    if let Some(rad) = r.diverse {
                        let x = pos[c.vertex as usize];
                        let near = out.iter().any(|o| {
                            nalgebra::distance(
                                &Point3::from(x),
                                &Point3::from(pos[o.vertex as usize]),
                            ) < rad * s
                        });
                        if near {
                            continue;
                        }
                    }
                    out.push(c);
                }
                out
            })
            .collect();
    }
    if r.libband {
        symcorr_correspond::sagittal_band(
            &mut cands,
            points,
            (ta.labels(), tb.labels()),
            (&pd(ta).sagittal, &pd(tb).sagittal),
            0.5,
            &pd(ta).descriptors,
            &pd(tb).descriptors,
        );
    }
    if let Some(k) = r.reverse {
        let all: Vec<u32> = (0..tb.num_vertices() as u32).collect();
        let back = candidates(
            &pd(tb).descriptors,
            &pd(ta).descriptors,
            &all,
            &symcorr_correspond::CandidateOptions {
                nearest: Some(k),
                threshold: None,
            },
        )
        .unwrap();
        for (list, &p) in cands.iter_mut().zip(points) {
            let kept: Vec<Candidate> = list
                .iter()
                .copied()
                .filter(|c| back[c.vertex as usize].iter().any(|b| b.vertex == p))
                .collect();
            if !kept.is_empty() {
                *list = kept;
            }
        }
    }
    if let Some(tau) = r.gap {
        let m = r.widen.max(1);
        use rayon::prelude::*;
        let widened: Vec<Option<Vec<Candidate>>> = cands
            .par_iter()
            .zip(points)
            .map(|(list, &p)| {
                let p = p as usize;
                let dp = pd(ta).profile[p];
                let best = list
                    .iter()
                    .map(|c| (pd(tb).profile[c.vertex as usize] - dp).abs())
                    .fold(f64::INFINITY, f64::min);
                if best <= tau {
                    return None;
                }
                let mut all = compatible_by_descriptor(ta, tb, halves, p);
                all.truncate(m);
                Some(all)
            })
            .collect();
        for (list, w) in cands.iter_mut().zip(widened) {
            if let Some(w) = w {
                *list = w;
            }
        }
    }
    if let Some(delta) = r.axial {
        let (xa, xb) = (axial(ta), axial(tb));
        for (list, &p) in cands.iter_mut().zip(points) {
            let p = p as usize;
            let lp = ta.labels()[p];
            if matches!(lp, Segment::Pelvis | Segment::Torso | Segment::Head) {
                continue;
            }
            let ok = |q: usize| tb.labels()[q] == lp && (xb[q] - xa[p]).abs() <= delta;
            let kept: Vec<Candidate> = list
                .iter()
                .copied()
                .filter(|c| ok(c.vertex as usize))
                .collect();
            if !kept.is_empty() {
                *list = kept;
                continue;
            }
            let best = (0..tb.num_vertices())
                .filter(|&q| ok(q))
                .map(|q| Candidate {
                    vertex: q as u32,
                    distance: pd(ta).descriptors.distance(p, &pd(tb).descriptors, q),
                })
                .min_by(|a, b| a.distance.total_cmp(&b.distance));
            if let Some(b) = best {
                *list = vec![b];
            }
        }
    }
    let midline = |l: Segment| matches!(l, Segment::Pelvis | Segment::Torso | Segment::Head);
    for (list, &p) in cands.iter_mut().zip(points) {
        let p = p as usize;
        let lp = ta.labels()[p];
        if !midline(lp) {
            continue;
        }
        let spn = norm(ma, sa, p);
        let ok = |q: usize| {
            let sq = norm(mb, sb, q);
            r.diff.is_none_or(|d| (sq - spn).abs() <= d)
                && r.ratio.is_none_or(|a| sq * spn.signum() >= a * spn.abs())
        };
        list.retain(|c| ok(c.vertex as usize));
        if list.is_empty() {
            let best = (0..tb.num_vertices())
                .filter(|&q| tb.labels()[q] == lp && !halves.0[p].opposes(halves.1[q]) && ok(q))
                .map(|q| Candidate {
                    vertex: q as u32,
                    distance: pd(ta).descriptors.distance(p, &pd(tb).descriptors, q),
                })
                .min_by(|a, b| a.distance.total_cmp(&b.distance));
            list.extend(best);
        }
    }
    if r.lambda > 0.0 {
        return cands
            .iter()
            .zip(points)
            .filter_map(|(list, &p)| {
                let pu = p as usize;
                let dp = pd(ta).profile[pu];
                let spn = if midline(ta.labels()[pu]) {
                    norm(ma, sa, pu)
                } else {
                    0.0
                };
                list.iter()
                    .map(|c| {
                        let q = c.vertex as usize;
                        let sq = if midline(tb.labels()[q]) {
                            norm(mb, sb, q)
                        } else {
                            0.0
                        };
                        (
                            (pd(tb).profile[q] - dp).abs() + r.lambda * (sq - spn).abs(),
                            c.vertex,
                        )
                    })
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .map(|(_, q)| (p, q))
            })
            .collect();
    }
    select(&cands, points, &pd(ta).profile, &pd(tb).profile)
        .iter()
        .map(|m| (m.template, m.target))
        .collect()
}

/// Where the paper pipeline's flips come from.
///
/// Prepares every mesh of DATASET once (DESIGN.md's dataset layout plus the rig's reference
/// labels, `labels/NAME.txt`, one segment index per line, and `mirror.txt`), then runs each
/// VARIANT of the paper method's matching options (`--method paper`) on every pair and prints,
/// per variant, the mean geodesic error (over the target's √area) and the flip rate (matches
/// nearer the mirror of the true vertex than the true vertex, over the counted matches).
///
/// For the first variant (every variant with `--all`) each flip is classified:
/// `tmpl_label` (the template point's attachment label differs from its reference label),
/// `target_label` (the target's attachment label at the true vertex differs from its reference
/// label: the filter cannot keep the true match), `halves` (labels right, but the point and its
/// true vertex got opposite sagittal halves), `selection` (labels and halves right: the
/// candidates / eq. 8 picked the mirror side); then the counts by reference segment and the
/// pairs with flips.
#[derive(clap::Parser, Debug)]
#[command(name = "paper_flips", verbatim_doc_comment)]
struct Args {
    /// Dataset folder (meshes/, joints/, pairs.txt, mirror.txt, labels/).
    dataset: PathBuf,
    /// Variants to run, in order (several per argument joined by `,`; default `base`), and the
    /// word `dense` for dense mode (every template vertex; default: the sparse sample).
    ///
    /// A variant is parts joined by `+`. Library options: `base` (defaults), `paper` (no
    /// midline halves, no sagittal band), `noband`, `band<r>` (sagittal band ratio r), `off`
    /// (no skeleton filter), `n<N>` (N candidates). Custom rules (this experiment's own
    /// filter/selection): `lib` (the library's sagittal band on its coordinates), `f<N>`
    /// (filter first: the N nearest among compatible target vertices), `x<ρ>` (spatially
    /// diverse candidates, ρ in √area), `g<τ>` + `w<M>` (adaptive widening: a point whose best
    /// eq. 8 gap exceeds τ gets M candidates), `k<K>` (reverse nearest neighbours), `a<δ>`
    /// (axial band on limbs), `sym` / `s<mask>` (symmetry-refined planes: 1 pelvis, 2 torso,
    /// 4 head, 8 skull), `own` (halves from those planes), `w` (normalise by the segment's
    /// half-width), `d<x>` / `r<x>` (sagittal difference / ratio rule), `l<λ>` (selection term
    /// λ·|s(q) − s(p)|), `c` (custom path with no rule). Example: `base,paper,n10+k50`.
    #[arg(value_name = "VARIANT|dense", verbatim_doc_comment)]
    variants: Vec<String>,
    /// Dense mode (same as the positional word `dense`).
    #[arg(long)]
    dense: bool,
    /// Pairs file (default: DATASET/pairs.txt).
    #[arg(long, value_name = "FILE")]
    pairs: Option<PathBuf>,
    /// Print one line per classified flip (pair, point, labels, halves, signed distances).
    #[arg(long)]
    verbose: bool,
    /// Classify the flips of every variant, not only the first.
    #[arg(long)]
    all: bool,
    /// Before the variants, print per mesh the quality of the midline planes: the mean
    /// |sd(v) + sd(mirror(v))| per segment (pelvis, torso, head) and plane set (0, 7, 8, 12).
    #[arg(long)]
    planes: bool,
    /// Skull plane (plane set bit 8): head vertices beyond this fraction of the shoulder
    /// centre → head bone get their own symmetry-fitted plane.
    #[arg(long, value_name = "T", default_value_t = 0.5)]
    skull_t: f64,
    /// Laplace–Beltrami eigenpairs behind the si-HKS (default: the pipeline's).
    #[arg(long, value_name = "K")]
    eigenpairs: Option<usize>,
    /// si-HKS frequencies kept (default: the pipeline's).
    #[arg(long, value_name = "N")]
    si_hks_frequencies: Option<usize>,
    /// si-HKS window start: log2 of the smallest diffusion time over the area (default: the
    /// pipeline's).
    #[arg(long, value_name = "TAU", allow_hyphen_values = true)]
    si_hks_tau_start: Option<f64>,
    /// si-HKS window end: log2 of the largest diffusion time over the area (default: the
    /// pipeline's).
    #[arg(long, value_name = "TAU", allow_hyphen_values = true)]
    si_hks_tau_end: Option<f64>,
}

impl Args {
    /// Dense mode, and the variants in order (`base` when none is given).
    fn variants(&self) -> (bool, Vec<String>) {
        let dense = self.dense || self.variants.iter().any(|a| a == "dense");
        let v: Vec<String> = self
            .variants
            .iter()
            .filter(|a| *a != "dense")
            .flat_map(|a| a.split(',').map(String::from).collect::<Vec<_>>())
            .collect();
        if v.is_empty() {
            (dense, vec!["base".to_string()])
        } else {
            (dense, v)
        }
    }

    /// The pipeline: the paper method, the prepared meshes' si-HKS and eigenpairs from the
    /// options.
    fn pipeline(&self, dense: bool) -> Pipeline {
        let mut prepare = symcorr::PrepareOptions::default();
        if let Some(x) = self.si_hks_frequencies {
            prepare.si_hks.frequencies = x;
        }
        if let Some(x) = self.si_hks_tau_start {
            prepare.si_hks.tau_start = x;
        }
        if let Some(x) = self.si_hks_tau_end {
            prepare.si_hks.tau_end = x;
        }
        if let Some(x) = self.eigenpairs {
            prepare.eigenpairs = x;
        }
        Pipeline::new(PipelineOptions {
            prepare,
            method: Method::Paper,
            mode: if dense {
                Mode::Dense
            } else {
                Mode::DEFAULT_SPARSE
            },
            ..PipelineOptions::default()
        })
    }
}

fn main() {
    let args = <Args as clap::Parser>::parse();
    if let Err(e) = run(&args) {
        eprintln!("paper_flips: {e}");
        std::process::exit(1);
    }
}

fn run(args: &Args) -> Result<(), String> {
    let root = args.dataset.as_path();
    let (dense, variants) = args.variants();
    // Every variant is checked before the (slow) preparation.
    let parsed: Vec<(MatchOptions, Option<Rule>)> = variants
        .iter()
        .map(|v| variant(v))
        .collect::<Result<_, _>>()?;
    let ds = Dataset::open(root, args.pairs.as_deref()).map_err(|e| e.to_string())?;
    let mirror = ds
        .mirror
        .clone()
        .ok_or_else(|| format!("{}: no mirror.txt", root.display()))?;
    let pipeline = args.pipeline(dense);
    let skull_t = args.skull_t;
    let t = Instant::now();
    let names = ds.used_names();
    use rayon::prelude::*;
    let meshes: BTreeMap<String, Mesh> = names
        .par_iter()
        .map(|n| -> Result<(String, Mesh), String> {
            let mesh = read_mesh(&ds.meshes[n], symcorr_mesh::io::DEFAULT_MAX_INPUT_BYTES)
                .map_err(|e| e.to_string())?;
            let sk = read_skeleton(&ds.joints[n], None).map_err(|e| e.to_string())?;
            let p = pipeline
                .prepare(mesh, &sk)
                .map_err(|e| format!("{n}: {e}"))?;
            let reference = read_labels(&root.join("labels").join(format!("{n}.txt")))?;
            let graph = EvalGraph::new(&p.mesh);
            let sd: Vec<Vec<f64>> = (0..16)
                .map(|k| {
                    if [0, 4, 7, 8, 12].contains(&k) {
                        signed_distances(&p, k, skull_t)
                    } else {
                        vec![0.0; p.num_vertices()]
                    }
                })
                .collect();
            let mut width = vec![[1.0; 17]; 16];
            for (k, d) in sd.iter().enumerate() {
                for seg in [Segment::Pelvis, Segment::Torso, Segment::Head] {
                    let mut v: Vec<f64> = d
                        .iter()
                        .zip(p.labels())
                        .filter(|(_, &l)| l == seg)
                        .map(|(x, _)| x.abs())
                        .collect();
                    if v.is_empty() {
                        continue;
                    }
                    v.sort_by(f64::total_cmp);
                    width[k][seg.index()] = v[v.len() * 9 / 10];
                }
            }
            Ok((
                n.clone(),
                Mesh {
                    p,
                    reference,
                    graph,
                    sd,
                    width,
                },
            ))
        })
        .collect::<Result<_, _>>()?;
    eprintln!(
        "prepared {} meshes in {:.1} s",
        meshes.len(),
        t.elapsed().as_secs_f64()
    );
    if args.planes {
        // Plane quality: for a perfect plane sd(v) = −sd(mirror(v)).
        for (n, m) in &meshes {
            let mut line = format!("{n:>14}");
            for seg in [Segment::Pelvis, Segment::Torso, Segment::Head] {
                for k in [0usize, 7, 8, 12] {
                    let (mut sum, mut cnt) = (0.0, 0usize);
                    for (v, &w) in mirror.iter().enumerate().take(m.p.num_vertices()) {
                        let w = w as usize;
                        if m.reference[v] == seg && m.p.labels()[v] == seg && m.p.labels()[w] == seg
                        {
                            sum += (m.sd[k][v] + m.sd[k][w]).abs();
                            cnt += 1;
                        }
                    }
                    line += &format!(" {}{k} {:.4}", &seg.name()[..2], sum / cnt.max(1) as f64);
                }
            }
            println!("{line}");
        }
    }
    for (vi, (v, (opts, rule))) in variants.iter().zip(&parsed).enumerate() {
        let classify = vi == 0 || args.all;
        let mut total = (0.0, 0usize, 0usize, 0usize);
        let mut classes: BTreeMap<&str, usize> = BTreeMap::new();
        let mut by_seg: BTreeMap<(&str, &str), usize> = BTreeMap::new();
        let mut by_pair: Vec<(String, usize, usize)> = Vec::new();
        for (a, b) in &ds.pairs {
            let (ma, mb) = (&meshes[a], &meshes[b]);
            let points = pipeline.points(&ma.p);
            let pairs: Vec<(u32, u32)> = match rule {
                None => match_points(
                    &ma.p.paper_side().expect("prepared for the paper method"),
                    &mb.p.paper_side().expect("prepared for the paper method"),
                    &points,
                    opts,
                )
                .map_err(|e| format!("{a} -> {b}: {e}"))?
                .matches
                .iter()
                .map(|m| (m.template, m.target))
                .collect(),
                Some(r) => custom(ma, mb, &points, opts, r),
            };
            let e = evaluate(&mb.graph, mb.p.area, &pairs, |v| v, Some(&mirror));
            let (c, f) = e.flip_counts();
            total.0 += e.errors.iter().sum::<f64>();
            total.1 += e.errors.len();
            total.2 += c;
            total.3 += f;
            by_pair.push((format!("{a}->{b}"), f, c));
            if !classify {
                continue;
            }
            for (i, (&(p, q), flip)) in pairs.iter().zip(&e.flips).enumerate() {
                if *flip != Some(true) {
                    continue;
                }
                let (p, q) = (p as usize, q as usize);
                let rp = ma.reference[p];
                let class = if ma.p.attachment.labels[p] != rp {
                    "tmpl_label"
                } else if mb.p.attachment.labels[p] != mb.reference[p] {
                    "target_label"
                } else if pd(&ma.p).halves[p].opposes(pd(&mb.p).halves[p]) {
                    "halves"
                } else {
                    "selection"
                };
                *classes.entry(class).or_default() += 1;
                *by_seg.entry((class, rp.name())).or_default() += 1;
                if args.verbose {
                    println!(
                        "  {a}->{b} p={p} ref={} tl={} ul={} hp={} hu={} q={q} ql={} qh={} err={:.3} cls={class} sd p {:.3} q* {:.3} q {:.3} m(q*) {}",
                        rp.name(),
                        ma.p.attachment.labels[p].name(),
                        mb.p.attachment.labels[p].name(),
                        pd(&ma.p).halves[p].sign(),
                        pd(&mb.p).halves[p].sign(),
                        mb.p.attachment.labels[q].name(),
                        pd(&mb.p).halves[q].sign(),
                        e.errors[i],
                        ma.sd[0][p],
                        mb.sd[0][p],
                        mb.sd[0][q],
                        mirror[p],
                    );
                }
            }
        }
        println!(
            "{v}: mean {:.4} flips {}/{} = {:.3} %",
            total.0 / total.1 as f64,
            total.3,
            total.2,
            100.0 * total.3 as f64 / total.2.max(1) as f64
        );
        if classify {
            println!("  classes {classes:?}");
            println!("  by segment {by_seg:?}");
            let flipped: Vec<_> = by_pair.iter().filter(|x| x.1 > 0).collect();
            println!("  pairs with flips: {flipped:?}");
        }
    }
    Ok(())
}

/// The paper's per-mesh data (the experiment prepares every mesh for the paper's method).
fn pd(m: &PreparedMesh) -> &symcorr::PaperData {
    m.paper
        .as_ref()
        .expect("paper_flips prepares its meshes for the paper's method")
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
    fn positional_words_keep_their_syntax() {
        let a = Args::parse_from(["paper_flips", "DS", "base,paper", "dense", "n10+k50"]);
        let (dense, v) = a.variants();
        assert!(dense);
        assert_eq!(v, ["base", "paper", "n10+k50"]);
        let (dense, v) = Args::parse_from(["paper_flips", "DS"]).variants();
        assert!(!dense);
        assert_eq!(v, ["base"]);
        let a = Args::parse_from(["paper_flips", "DS", "--si-hks-tau-start", "-10"]);
        assert_eq!(a.si_hks_tau_start, Some(-10.0));
    }

    #[test]
    fn variants_parse_as_before() {
        let (o, r) = variant("base").unwrap();
        assert!(r.is_none());
        assert_eq!(
            o.candidates.nearest,
            MatchOptions::default().candidates.nearest
        );
        let (o, r) = variant("paper+n10").unwrap();
        assert!(r.is_none() && o.filter == PaperFilter::Strict);
        assert_eq!(o.candidates.nearest, Some(10));
        let (o, r) = variant("band0.25+k50").unwrap();
        assert_eq!(
            o.filter,
            PaperFilter::Extended {
                sagittal_ratio: Some(0.25)
            }
        );
        assert_eq!(r.unwrap().reverse, Some(50));
        let (_, r) = variant("g0.05+w50").unwrap();
        let r = r.unwrap();
        assert_eq!((r.gap, r.widen), (Some(0.05), 50));
        assert!(variant("bogus").is_err());
        assert!(variant("nX").is_err());
    }
}
