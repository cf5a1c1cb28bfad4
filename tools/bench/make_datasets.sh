#!/usr/bin/env bash
# Generates the benchmark datasets behind the README's correspondence figures (20+ pose pairs,
# same shape and different shapes, exact and noisy joints, scans, larger meshes) into
# target/bench-data/ (inside the clone, never committed):
#   bodies20/        20 poses x 2 shapes, exact joints            (58 pairs)
#   bodies20_noisy/  the same meshes, joints with sigma = 3 cm and 10 % on the surface
#   bodies20_scans/  the same templates, each target a single-view virtual-Kinect scan
#   bodies20_kinect/         templates as bodies20 (random-7 replaced by arms-tight), each target a
#                            scan as harsh as a real Kinect v1 (--scan-realism kinect-v1) from a
#                            camera drawn per body: 2.5-3.2 m, azimuth +-35 deg, 0.6-1.6 m high
#   bodies20_kinect_noisy/   the same views, tracker joints (sigma 2.5 cm, 4.5 cm at hands and
#                            feet, unseen joints inferred)
#   bodies20_kinect_profile/ the same with profile views (|azimuth| 60-90 deg, both sides)
#   heldout_kinect/          as bodies20_kinect with another second shape (female, muscular,
#                            heavy) and other cameras (--scan-seed 777): a check on a body and
#                            views the methods were not tuned on
#   bodies50k/       4 poses x 2 shapes, Loop-subdivided once (53,514 vertices)
#   bodies20_fine/   13,380-vertex templates, targets one Loop level finer (another triangulation)
#   recording/       a 10 s synthetic Kinect recording (300 frames, 640x480, turn to profile and
#                    back, corrupted joint log, ground truth) for symcorr track
# Shapes and noise are those of the committed fixtures (tools/synth/src/fixtures.rs).
# Usage: bash tools/bench/make_datasets.sh   then e.g.
#   cargo run --release -- bench target/bench-data/bodies20 --mode dense --json dense.json
set -euo pipefail
cd "$(dirname "$0")/../.."
out=target/bench-data
poses="rest,t-pose,arms-down"
for w in 0 10 20 30 40 50 60 70 80 90; do poses+=",walk-$w"; done
for s in 1 2 3 4 5 6 7; do poses+=",random-$s"; done
cargo build --release -q -p symcorr-synth
synth=target/release/symcorr-synth
common=(--shape "s0:" --shape "s1:male-young-minmuscle-maxweight=0.5" --poses "$poses")
"$synth" dataset --out "$out/bodies20" "${common[@]}"
"$synth" dataset --out "$out/bodies20_noisy" "${common[@]}" \
  --noise-sigma-cm 3 --surface-fraction 0.1 --noise-seed 2026
for d in bodies20 bodies20_noisy; do
  echo "$out/$d: $(ls "$out/$d/meshes" | wc -l) meshes, $(wc -l < "$out/$d/pairs.txt") pairs"
done
# Single-view scans: every pair's target is a virtual-Kinect view (sensor noise on)
# of the target body, with truth/NAME_scan.txt (body vertex per scan vertex).
"$synth" dataset --out "$out/bodies20_scans" "${common[@]}" --scans --scan-realism kinect
echo "$out/bodies20_scans: $(wc -l < "$out/bodies20_scans/pairs.txt") scan pairs"
# Scans as harsh as a real Kinect v1 (tools/synth/README.md, "kinect-v1"): one camera drawn
# per body, cameras/NAME_scan.json records it. Arms against the torso: arms-tight, arms-down.
kposes="rest,t-pose,arms-down,arms-tight"
for w in 0 10 20 30 40 50 60 70 80 90; do kposes+=",walk-$w"; done
for s in 1 2 3 4 5 6; do kposes+=",random-$s"; done
kinect=(--shape "s0:" --shape "s1:male-young-minmuscle-maxweight=0.5" --poses "$kposes"
  --scans --scan-realism kinect-v1 --scan-seed 2026)
"$synth" dataset --out "$out/bodies20_kinect" "${kinect[@]}" --scan-cameras frontal
"$synth" dataset --out "$out/bodies20_kinect_noisy" "${kinect[@]}" --scan-cameras frontal --scan-joints tracker
"$synth" dataset --out "$out/bodies20_kinect_profile" "${kinect[@]}" --scan-cameras profile
"$synth" dataset --out "$out/heldout_kinect" --shape "s0:" \
  --shape "s1:female-young-maxmuscle-maxweight=0.7" --poses "$kposes" --scans \
  --scan-realism kinect-v1 --scan-seed 777 --scan-cameras frontal
for d in bodies20_kinect bodies20_kinect_noisy bodies20_kinect_profile heldout_kinect; do
  echo "$out/$d: $(wc -l < "$out/$d/pairs.txt") scan pairs"
done
# Larger meshes ("50k <-> 50k"): the same bodies Loop-subdivided once (53,514 vertices),
# 4 poses x 2 shapes, for timing and for accuracy at a finer triangulation.
"$synth" dataset --out "$out/bodies50k" --shape "s0:" --shape "s1:male-young-minmuscle-maxweight=0.5" \
  --poses rest,t-pose,walk-30,random-3 --subdivide 1
echo "$out/bodies50k: $(wc -l < "$out/bodies50k/pairs.txt") pairs of $(wc -l < "$out/bodies50k/mirror.txt")-vertex meshes"
# Different triangulations (peer comparison): each target is its body subdivided once
# (53,514 vertices) while the template keeps 13,380; truth/NAME_fine.txt = body vertex ids.
"$synth" dataset --out "$out/bodies20_fine" "${common[@]}" --finer-targets 1
echo "$out/bodies20_fine: $(wc -l < "$out/bodies20_fine/pairs.txt") pairs, targets one Loop level finer"
# A synthetic Kinect recording (symcorr.recording/1): 10 s at 30 fps, 640x480, the body walking
# in place and turning to profile and back, a tracker-like corrupted joint log and ground truth.
"$synth" recording --frames 300 --fps 30 --width 640 --height 480 --seed 7 --out "$out/recording"
echo "$out/recording: $(ls "$out/recording/depth" | wc -l) depth frames"
