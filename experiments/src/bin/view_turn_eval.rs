//! The measurement behind `Pipeline::run_on_view`: single-view scan pairs matched with the
//! target's joints as given (optionally turned about their spine first: a log in a frame turned
//! about the vertical, a tracker that took a back for a front) and with those joints turned
//! back half a turn, each by `Pipeline::run`; then `run_on_view`'s rule (below the retry
//! threshold keep the turned fit when `turn_verdict` says so, refuse the pair when it says
//! neither fit holds clearly more, refuse a kept fit under `MIN_VIEW_HELD`) replayed at several
//! thresholds.
//!
//! ```text
//! cargo run --release -p symcorr-experiments --bin view_turn_eval -- \
//!     --dataset target/bench-data/bodies20_kinect --turn-deg 180
//! ```
//!
//! One line per pair: `refused` when the attachment's fit checks refuse the (turned) joints,
//! else for the fit on the joints as given and on them turned back the fraction of its view the
//! fit holds (`view_held`), the template points it lays on the scan (`ViewHold::held`) and their
//! surface (`ViewHold::held_area`), the mean error and the flips of the listed matches (`bench`'s evaluation). Then per retry
//! threshold: fits turned, refused, the mean of the pairs' mean errors, the pooled flips and
//! the pairs with more than a fifth of their matches flipped.

use clap::Parser;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::PathBuf;
use symcorr::bench::evaluate_pair;
use symcorr::{Pipeline, PipelineOptions, PreparedMesh};
use symcorr_eval::{Dataset, EvalGraph, Evaluation};

/// Single-view pairs with (turned) target joints, fitted as given and turned back.
#[derive(Parser, Debug)]
struct Args {
    /// A scan dataset (bench layout with truth/): the targets are single views.
    #[arg(long)]
    dataset: PathBuf,
    /// Pairs file (default: DATASET/pairs.txt).
    #[arg(long)]
    pairs: Option<PathBuf>,
    /// Turn of every target's joints about their spine, degrees (0: as given).
    #[arg(long, default_value_t = 180.0)]
    turn_deg: f64,
}

/// A fit's figures: view held (share, points, surface), mean error, (flips, counted matches).
struct Fit {
    view_hold: Option<symcorr::ViewHold>,
    mean_error: f64,
    flips: usize,
    counted: usize,
}

fn fit(e: &Evaluation, corr: &symcorr::Correspondence) -> Fit {
    let (counted, flips) = e.flip_counts();
    Fit {
        view_hold: corr.view_hold(),
        mean_error: e.mean_error(),
        flips,
        counted,
    }
}

enum Outcome {
    RefusedAtAttachment(String),
    /// The fits on the joints as given (turned by `--turn-deg`) and turned back half a turn
    /// (`None`: the turned target was refused).
    Matched {
        given: Fit,
        turned: Option<Fit>,
    },
}

fn main() -> Result<(), String> {
    let args = Args::parse();
    let dataset = Dataset::open(&args.dataset, args.pairs.as_deref()).map_err(|e| e.to_string())?;
    let mirror = dataset.mirror.as_deref();
    let pipeline = Pipeline::new(PipelineOptions {
        mode: symcorr::Mode::Dense,
        ..PipelineOptions::default()
    });
    let angle = args.turn_deg.to_radians();
    let read = |name: &str, turn: bool| -> Result<PreparedMesh, String> {
        let mesh =
            symcorr::io::read_mesh(&dataset.meshes[name], u64::MAX).map_err(|e| e.to_string())?;
        let mut sk =
            symcorr::io::read_skeleton(&dataset.joints[name], None).map_err(|e| e.to_string())?;
        if turn && angle != 0.0 {
            sk = sk
                .turned_about_spine(angle)
                .ok_or("hip and shoulder centres coincide")?;
        }
        pipeline.prepare(mesh, &sk).map_err(|e| e.to_string())
    };
    let templates: BTreeMap<String, PreparedMesh> = dataset
        .pairs
        .iter()
        .map(|(a, _)| a.clone())
        .collect::<std::collections::BTreeSet<_>>()
        .into_par_iter()
        .map(|a| read(&a, false).map(|p| (a, p)))
        .collect::<Result<_, String>>()?;
    let graphs: BTreeMap<&str, EvalGraph> = templates
        .iter()
        .map(|(a, p)| (a.as_str(), EvalGraph::new(&p.mesh)))
        .collect();
    let outcomes: Vec<(String, String, Outcome)> = dataset
        .pairs
        .par_iter()
        .map(|(a, b)| {
            let template = &templates[a];
            let truth = dataset
                .truth
                .get(b)
                .ok_or(format!("{b}: no truth table (not a scan?)"))
                .and_then(|p| symcorr_eval::read_truth(p).map_err(|e| e.to_string()))?;
            let target = match read(b, true) {
                Ok(t) => t,
                Err(e) => return Ok((a.clone(), b.clone(), Outcome::RefusedAtAttachment(e))),
            };
            let evaluate = |target: &PreparedMesh, corr: &symcorr::Correspondence| {
                let (e, _) = evaluate_pair(
                    template,
                    target,
                    Some(&truth),
                    &graphs[a.as_str()],
                    corr,
                    mirror,
                );
                fit(&e, corr)
            };
            let corr = pipeline.run(template, &target).map_err(|e| e.to_string())?;
            let given = evaluate(&target, &corr);
            let turned = pipeline.prepare_turned(&target).and_then(|t| {
                let corr = pipeline.run(template, &t).ok()?;
                Some(evaluate(&t, &corr))
            });
            Ok((a.clone(), b.clone(), Outcome::Matched { given, turned }))
        })
        .collect::<Result<_, String>>()?;

    println!("template target | given: view_held held_points error flips | turned back: the same");
    let vh = |v: Option<symcorr::ViewHold>| {
        v.map_or("- 0 0".to_string(), |v| {
            format!("{:.3} {} {:.4}", v.fraction(), v.held, v.held_area)
        })
    };
    let mut refused_attach = 0;
    for (a, b, o) in &outcomes {
        match o {
            Outcome::RefusedAtAttachment(e) => {
                refused_attach += 1;
                let short: String = e.chars().take(90).collect();
                println!("{a} {b} | refused at attachment: {short}");
            }
            Outcome::Matched { given, turned } => {
                let t = turned.as_ref().map_or("refused".to_string(), |f| {
                    format!(
                        "{} {:.4} {}/{}",
                        vh(f.view_hold),
                        f.mean_error,
                        f.flips,
                        f.counted
                    )
                });
                println!(
                    "{a} {b} | {} {:.4} {}/{} | {t}",
                    vh(given.view_hold),
                    given.mean_error,
                    given.flips,
                    given.counted
                );
            }
        }
    }
    println!(
        "pairs {} refused at attachment {refused_attach}",
        outcomes.len()
    );
    // `Pipeline::run_on_view`'s rule at each retry threshold: below it, the turned fit is kept
    // when `turn_verdict` says so and the pair refused when it cannot tell; a kept fit below
    // `MIN_VIEW_HELD` is refused.
    for threshold in [0.0, 0.75, 0.8, 0.85, 0.9, 0.95] {
        let (mut n, mut err, mut flips, mut counted, mut mostly, mut turned_n, mut refused) =
            (0, 0.0, 0, 0, 0, 0, 0);
        // Refused as undetermined, and of those the pairs whose given fit was mostly flipped.
        let (mut undetermined, mut undetermined_mostly) = (0, 0);
        for (_, _, o) in &outcomes {
            let Outcome::Matched { given, turned } = o else {
                continue;
            };
            let mut kept = given;
            if given.view_hold.is_some_and(|h| h.fraction() < threshold) {
                if let Some(t) = turned {
                    match symcorr::turn_verdict(given.view_hold, t.view_hold) {
                        symcorr::TurnVerdict::Turned => {
                            kept = t;
                            turned_n += 1;
                        }
                        symcorr::TurnVerdict::Given => {}
                        symcorr::TurnVerdict::Undetermined => {
                            undetermined += 1;
                            undetermined_mostly += usize::from(5 * given.flips > given.counted);
                            continue;
                        }
                    }
                }
            }
            if kept
                .view_hold
                .is_some_and(|h| h.fraction() < symcorr::MIN_VIEW_HELD)
            {
                refused += 1;
                continue;
            }
            n += 1;
            err += kept.mean_error;
            flips += kept.flips;
            counted += kept.counted;
            mostly += usize::from(5 * kept.flips > kept.counted);
        }
        println!(
            "retry below {threshold:.2}: turned {turned_n} undetermined {undetermined} (given mostly flipped {undetermined_mostly}) refused {refused} matched {n} mean error {:.4} flips {flips}/{counted} ({:.3} %) pairs mostly flipped {mostly}",
            err / n.max(1) as f64,
            100.0 * flips as f64 / counted.max(1) as f64
        );
    }
    Ok(())
}
