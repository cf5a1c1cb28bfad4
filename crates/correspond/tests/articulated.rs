//! Skeleton-driven articulated alignment on the capsule body: a target made by skinning the
//! template onto a bent skeleton (same connectivity, so the identity is the truth), whole and
//! as a front-only partial view with renumbered vertices.

use nalgebra::Point3;
use symcorr_attach::testbody::{capsule_body, t_pose};
use symcorr_attach::{attach, AttachOptions};
use symcorr_correspond::{
    articulated_match, articulated_match_indexed, bone_transforms, outward_normals, skin,
    ArticulatedIndex, ArticulatedInputs, ArticulatedMatches, ArticulatedOptions, ArticulatedStart,
    CorrespondError,
};
use symcorr_mesh::TriMesh;
use symcorr_skeleton::{Joint, Segment, Skeleton};
use symcorr_spectral::EdgeGraph;

/// Euclidean distance between two stored mesh positions.
fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    nalgebra::distance(&Point3::from(a), &Point3::from(b))
}

/// Rotates the joints below `pivot` in the chain `chain` by `angle` about the z axis.
fn bend(sk: &mut Skeleton, pivot: Joint, chain: &[Joint], angle: f64) {
    let o = sk.position(pivot);
    let turn = nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::z_axis(), angle);
    for &j in chain {
        sk.positions[j.index()] = o + turn * (sk.position(j) - o);
    }
}

struct Body {
    mesh: TriMesh,
    skeleton: Skeleton,
}

fn bodies() -> (Body, Body, symcorr_attach::Attachment) {
    let sk = t_pose(1.0);
    let (mesh, _) = capsule_body(&sk, 0.03);
    let att = attach(&mesh, &sk, &AttachOptions::default()).unwrap();
    let mut bent = sk.clone();
    bend(
        &mut bent,
        Joint::ElbowLeft,
        &[Joint::WristLeft, Joint::HandLeft],
        1.0,
    );
    bend(
        &mut bent,
        Joint::KneeRight,
        &[Joint::AnkleRight, Joint::FootRight],
        -0.6,
    );
    // Move the whole body as well: the target lives in another frame.
    for p in bent.positions.iter_mut() {
        *p += nalgebra::Vector3::new(0.3, -0.1, 2.0);
    }
    let normals = mesh.vertex_normals();
    let (posed, _) = skin(
        &mesh.positions,
        &normals,
        &att.weights,
        &bone_transforms(&sk, &bent),
    );
    let posed = posed.into_iter().map(|p| p.into()).collect();
    let target = TriMesh::new(posed, mesh.triangles.clone()).unwrap();
    (
        Body { mesh, skeleton: sk },
        Body {
            mesh: target,
            skeleton: bent,
        },
        att,
    )
}

fn side<'a>(
    mesh: &'a TriMesh,
    att: &'a symcorr_attach::Attachment,
    normals: &'a [[f64; 3]],
    boundary: Option<&'a [bool]>,
) -> ArticulatedInputs<'a> {
    ArticulatedInputs {
        boundary,
        neighbors: None,
        positions: &mesh.positions,
        normals,
        labels: &att.labels,
        joints: &att.joints,
        area: mesh.total_area(),
        triangles: Some(&mesh.triangles),
        viewpoint: None,
    }
}

/// The mesh's vertex normals turned to point out of the body.
fn outward(mesh: &TriMesh, att: &symcorr_attach::Attachment) -> Vec<[f64; 3]> {
    outward_normals(
        &mesh.positions,
        mesh.vertex_normals(),
        &att.labels,
        &att.joints,
    )
}

#[test]
fn a_skinned_copy_is_matched_to_itself() {
    let (a, b, att_a) = bodies();
    let att_b = attach(&b.mesh, &b.skeleton, &AttachOptions::default()).unwrap();
    let na = outward(&a.mesh, &att_a);
    let nb = outward(&b.mesh, &att_b);
    let out = articulated_match(
        &side(&a.mesh, &att_a, &na, None),
        &att_a.weights,
        &side(&b.mesh, &att_b, &nb, None),
        &EdgeGraph::new(&b.mesh),
        &ArticulatedOptions::default(),
        ArticulatedStart::Skeletons,
    )
    .unwrap();
    assert_eq!(out.pairs.len(), a.mesh.num_vertices());
    let err: Vec<f64> = out
        .pairs
        .iter()
        .map(|m| {
            dist(
                b.mesh.positions[m.target as usize],
                b.mesh.positions[m.template as usize],
            )
        })
        .collect();
    let mean = err.iter().sum::<f64>() / err.len() as f64;
    // Edge length of the capsule body is 3 cm; the skinning is exactly representable.
    assert!(mean < 0.01, "mean error {mean}");
    let seen = out.has_counterpart.iter().filter(|&&h| h).count();
    assert!(
        seen as f64 > 0.98 * a.mesh.num_vertices() as f64,
        "{seen} of {} with a counterpart on a whole surface",
        a.mesh.num_vertices()
    );
    // No match lands on the other side of the body (x < 0 is the subject's left here).
    let crossed = out
        .pairs
        .iter()
        .filter(|m| {
            let (p, q) = (
                a.mesh.positions[m.template as usize][0],
                b.mesh.positions[m.target as usize][0] - 0.3,
            );
            p.abs() > 0.15 && p * q < 0.0
        })
        .count();
    assert_eq!(crossed, 0);
}

/// The setup of the single-view checks: the capsule body `a` (template) with its attachment and
/// outward normals, and the front view of the second body (vertex ids kept, `new_id`) with its
/// attachment and outward normals.
struct FrontScan {
    a: Body,
    att_a: symcorr_attach::Attachment,
    scan: TriMesh,
    new_id: Vec<u32>,
    att_s: symcorr_attach::Attachment,
    na: Vec<[f64; 3]>,
    ns: Vec<[f64; 3]>,
}

impl FrontScan {
    fn new() -> FrontScan {
        let (a, b, att_a) = bodies();
        let (scan, new_id) = front_view(&b.mesh, false);
        let att_s = attach(&scan, &b.skeleton, &AttachOptions::default()).unwrap();
        let na = outward(&a.mesh, &att_a);
        let ns = outward(&scan, &att_s);
        FrontScan {
            a,
            att_a,
            scan,
            new_id,
            att_s,
            na,
            ns,
        }
    }
}

/// The front view of `mesh`: its triangles facing +z (the camera) as a mesh of their own, and
/// per body vertex its id in that mesh (`u32::MAX`: not in view). `reverse` numbers the kept
/// vertices in reverse order.
fn front_view(mesh: &TriMesh, reverse: bool) -> (TriMesh, Vec<u32>) {
    let tn = mesh.triangle_normals();
    let front: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .zip(&tn)
        .filter(|(_, n)| n[2] > 0.2)
        .map(|(t, _)| *t)
        .collect();
    let mut used: Vec<u32> = front.iter().flatten().copied().collect();
    used.sort_unstable();
    used.dedup();
    if reverse {
        used.reverse();
    }
    let mut new_id = vec![u32::MAX; mesh.num_vertices()];
    for (i, &v) in used.iter().enumerate() {
        new_id[v as usize] = i as u32;
    }
    let scan = TriMesh::new(
        used.iter().map(|&v| mesh.positions[v as usize]).collect(),
        front
            .iter()
            .map(|t| t.map(|v| new_id[v as usize]))
            .collect(),
    )
    .unwrap();
    (scan, new_id)
}

/// Template vertices given a counterpart that the front view shows (true positives) and that it
/// does not (false positives); `new_id` as from [`front_view`].
fn counterparts(out: &ArticulatedMatches, new_id: &[u32]) -> (usize, usize) {
    let (mut tp, mut fp) = (0usize, 0usize);
    for (m, &seen) in out.pairs.iter().zip(&out.has_counterpart) {
        match (new_id[m.template as usize] != u32::MAX, seen) {
            (true, true) => tp += 1,
            (false, true) => fp += 1,
            _ => {}
        }
    }
    (tp, fp)
}

#[test]
fn a_front_view_reports_the_back_as_without_counterpart() {
    let (a, b, att_a) = bodies();
    // Vertices renumbered in reverse: the scan's ids are not the body's.
    let (scan, new_id) = front_view(&b.mesh, true);
    let att_s = attach(&scan, &b.skeleton, &AttachOptions::default()).unwrap();
    let na = outward(&a.mesh, &att_a);
    // Wound the other way round: outward_normals must turn them.
    let ns = outward_normals(
        &scan.positions,
        scan.vertex_normals()
            .iter()
            .map(|n| [-n[0], -n[1], -n[2]])
            .collect(),
        &att_s.labels,
        &att_s.joints,
    );
    let out = articulated_match(
        &side(&a.mesh, &att_a, &na, None),
        &att_a.weights,
        &side(&scan, &att_s, &ns, Some(&scan.boundary_vertices())),
        &EdgeGraph::new(&scan),
        &ArticulatedOptions::default(),
        ArticulatedStart::Skeletons,
    )
    .unwrap();
    let (mut tp, mut fp, mut fneg, mut err, mut n_err) = (0, 0, 0, 0.0, 0);
    for (m, &seen) in out.pairs.iter().zip(&out.has_counterpart) {
        let visible = new_id[m.template as usize] != u32::MAX;
        match (visible, seen) {
            (true, true) => tp += 1,
            (false, true) => fp += 1,
            (true, false) => fneg += 1,
            _ => {}
        }
        if visible {
            err += dist(
                scan.positions[m.target as usize],
                scan.positions[new_id[m.template as usize] as usize],
            );
            n_err += 1;
        }
    }
    let mean = err / n_err as f64;
    assert!(mean < 0.015, "mean error on the visible part {mean}");
    // The counterpart flag separates the seen front from the unseen back.
    let precision = tp as f64 / (tp + fp) as f64;
    let recall = tp as f64 / (tp + fneg) as f64;
    assert!(
        precision > 0.9 && recall > 0.9,
        "precision {precision}, recall {recall}"
    );
}

/// Without the normal test, without border flags and with a gate wider than a limb, the back
/// of a limb pairs with its front; the reciprocal check refuses it (the front's scan points are nearest the
/// template's front) and keeps the front.
#[test]
fn the_reciprocal_check_refuses_the_back_of_a_limb_without_the_normal_test() {
    let FrontScan {
        a,
        att_a,
        scan,
        new_id,
        att_s,
        na,
        ns,
    } = FrontScan::new();
    let run = |reciprocal_radius| {
        // A gate wider than a limb, no normal test, no border: the back of an arm pairs with
        // its front.
        let options = ArticulatedOptions {
            min_normal_cosine: -1.0,
            gate_end: 0.1,
            reciprocal_radius,
            ..ArticulatedOptions::default()
        };
        let out = articulated_match(
            &side(&a.mesh, &att_a, &na, None),
            &att_a.weights,
            // No border flags: the boundary gate would refuse the back's flank pairs itself.
            &side(&scan, &att_s, &ns, None),
            &EdgeGraph::new(&scan),
            &options,
            ArticulatedStart::Skeletons,
        )
        .unwrap();
        counterparts(&out, &new_id)
    };
    let (tp_off, fp_off) = run(None);
    let (tp_on, fp_on) = run(Some(0.03));
    assert!(
        fp_on * 2 < fp_off,
        "hidden vertices given a counterpart: {fp_off} without the check, {fp_on} with it"
    );
    assert!(
        tp_on as f64 > 0.9 * tp_off as f64,
        "shown vertices given a counterpart: {tp_off} without the check, {tp_on} with it"
    );
}

/// Seen from far along +z, the back of the body faces away from the camera. With the normal
/// test, the border flags and the occlusion test all out of play, the facing test alone
/// refuses the back's pairs and keeps the front's.
#[test]
fn the_facing_test_refuses_the_back_seen_from_the_viewpoint() {
    let FrontScan {
        a,
        att_a,
        scan,
        new_id,
        att_s,
        na,
        ns,
    } = FrontScan::new();
    let run = |min_facing_cosine| {
        let options = ArticulatedOptions {
            min_normal_cosine: -1.0,
            gate_end: 0.1,
            // Nothing is occluded by less than this: the occlusion test hides no vertex.
            occlusion_tolerance: 100.0,
            min_facing_cosine,
            ..ArticulatedOptions::default()
        };
        let target = ArticulatedInputs {
            viewpoint: Some(Point3::new(0.0, 1.0, 100.0)),
            ..side(&scan, &att_s, &ns, None)
        };
        let out = articulated_match(
            &side(&a.mesh, &att_a, &na, None),
            &att_a.weights,
            &target,
            &EdgeGraph::new(&scan),
            &options,
            ArticulatedStart::Skeletons,
        )
        .unwrap();
        counterparts(&out, &new_id)
    };
    // A cosine of -1 lets every vertex through: no facing test.
    let (tp_off, fp_off) = run(-1.0);
    let (tp_on, fp_on) = run(0.0);
    assert!(
        fp_on * 4 < fp_off,
        "hidden vertices given a counterpart: {fp_off} without the test, {fp_on} with it"
    );
    assert!(
        tp_on as f64 > 0.9 * tp_off as f64,
        "shown vertices given a counterpart: {tp_off} without the test, {tp_on} with it"
    );
}

/// The confidence ranks a region the fit had to pull away from its joints below one where the
/// joints and the surface agree: the scan's left wrist and hand joints are slid 4 cm along the
/// forearm (the surface is not), so the skeletons pose the left forearm off the scan and the
/// ICP moves it back. Each forearm's vertices lie on the scan after the fit, so their own
/// distances hardly differ; the skeleton-pose disagreement and the bone residual do.
#[test]
fn a_forearm_pulled_away_from_its_joints_gets_the_lower_confidence() {
    let (a, b, att_a) = bodies();
    let (scan, _) = front_view(&b.mesh, false);
    let na = outward(&a.mesh, &att_a);
    let run = |slide: f64| {
        let mut joints = b.skeleton.clone();
        let (elbow, wrist) = (
            joints.position(Joint::ElbowLeft),
            joints.position(Joint::WristLeft),
        );
        let along = (wrist - elbow).normalize() * slide;
        for j in [Joint::WristLeft, Joint::HandLeft] {
            joints.positions[j.index()] += along;
        }
        let att_s = attach(&scan, &joints, &AttachOptions::default()).unwrap();
        let ns = outward(&scan, &att_s);
        let out = articulated_match(
            &side(&a.mesh, &att_a, &na, None),
            &att_a.weights,
            &side(&scan, &att_s, &ns, Some(&scan.boundary_vertices())),
            &EdgeGraph::new(&scan),
            &ArticulatedOptions::default(),
            ArticulatedStart::Skeletons,
        )
        .unwrap();
        let mean = |segment: Segment| {
            let c: Vec<f64> = out
                .pairs
                .iter()
                .zip(&out.has_counterpart)
                .filter(|(m, &seen)| seen && att_a.labels[m.template as usize] == segment)
                .map(|(m, _)| m.confidence)
                .collect();
            assert!(c.len() > 20, "{} shown {segment:?} vertices", c.len());
            c.iter().sum::<f64>() / c.len() as f64
        };
        mean(Segment::ForearmLeft) / mean(Segment::ForearmRight)
    };
    let (agreeing, slid) = (run(0.0), run(0.04));
    assert!(
        slid < 0.8 * agreeing,
        "left/right forearm confidence: {agreeing} with the joints on the surface, {slid} with them slid"
    );
}

/// The final map without guesses for the hidden vertices (`guess_hidden: false`) gives the
/// same counterparts and the same pairs for them as the full map; the others get confidence 0.
#[test]
fn the_map_without_guesses_keeps_every_counterpart_and_its_pair() {
    let FrontScan {
        a,
        att_a,
        scan,
        att_s,
        na,
        ns,
        ..
    } = FrontScan::new();
    let neighbors = a.mesh.vertex_neighbors();
    let boundary = scan.boundary_vertices();
    let run = |guess_hidden| {
        let options = ArticulatedOptions {
            reciprocal_radius: Some(0.03),
            guess_hidden,
            ..ArticulatedOptions::default()
        };
        let mut template = side(&a.mesh, &att_a, &na, None);
        template.neighbors = Some(&neighbors);
        articulated_match(
            &template,
            &att_a.weights,
            &side(&scan, &att_s, &ns, Some(&boundary)),
            &EdgeGraph::new(&scan),
            &options,
            ArticulatedStart::Skeletons,
        )
        .unwrap()
    };
    let (full, shown) = (run(true), run(false));
    assert_eq!(full.has_counterpart, shown.has_counterpart);
    assert_eq!(full.posed, shown.posed);
    let counterparts = full.has_counterpart.iter().filter(|&&h| h).count();
    assert!(counterparts > 0 && counterparts < full.pairs.len());
    for (v, &h) in full.has_counterpart.iter().enumerate() {
        if h {
            assert_eq!(full.pairs[v], shown.pairs[v]);
            assert_eq!(full.distance[v], shown.distance[v]);
        } else {
            assert_eq!(shown.pairs[v].confidence, 0.0);
        }
    }
}

#[test]
fn an_index_built_beforehand_gives_the_same_matches_and_only_for_its_inputs() {
    let FrontScan {
        a,
        att_a,
        scan,
        att_s,
        na,
        ns,
        ..
    } = FrontScan::new();
    let neighbors = a.mesh.vertex_neighbors();
    let boundary = scan.boundary_vertices();
    let graph = EdgeGraph::new(&scan);
    let options = ArticulatedOptions::default();
    let mut template = side(&a.mesh, &att_a, &na, None);
    template.neighbors = Some(&neighbors);
    let target = side(&scan, &att_s, &ns, Some(&boundary));
    let index = ArticulatedIndex::new(&template, &target, &graph, &options).unwrap();
    let start = || ArticulatedStart::Skeletons;
    let built_here = articulated_match(
        &template,
        &att_a.weights,
        &target,
        &graph,
        &options,
        start(),
    )
    .unwrap();
    let indexed = articulated_match_indexed(
        &template,
        &att_a.weights,
        &target,
        &index,
        &options,
        start(),
    )
    .unwrap();
    assert_eq!(built_here.pairs, indexed.pairs);
    assert_eq!(built_here.posed, indexed.posed);
    assert_eq!(built_here.has_counterpart, indexed.has_counterpart);
    let stages = |m: &ArticulatedMatches| m.timings.iter().map(|t| t.0).collect::<Vec<_>>();
    assert_eq!(
        stages(&built_here)[..2],
        ["segment_pools", "pool_trees"],
        "the index's stages lead the timings when it is built here"
    );
    assert!(!stages(&indexed).contains(&"pool_trees"));
    // Another target (the scan moved by 1 cm), other options: the index is refused.
    let moved: Vec<[f64; 3]> = scan
        .positions
        .iter()
        .map(|p| [p[0] + 0.01, p[1], p[2]])
        .collect();
    let mut other = target;
    other.positions = &moved;
    let wider = ArticulatedOptions {
        band: options.band * 2.0,
        ..options
    };
    for (target, options) in [(&other, &options), (&target, &wider)] {
        let refused =
            articulated_match_indexed(&template, &att_a.weights, target, &index, options, start());
        assert!(
            matches!(refused, Err(CorrespondError::IndexMismatch)),
            "{:?}",
            refused.map(|m| m.pairs.len())
        );
    }
}

/// From a warm start a few centimetres off, two ICP rounds with each bone's step taken 1.5
/// times end nearer the truth than two rounds of steps as fitted (ICP converges linearly, the
/// over-relaxed rounds faster), and both nearer than the start; a relaxation outside (0, 2) is
/// refused.
#[test]
fn over_relaxed_warm_rounds_converge_further_in_as_many_rounds() {
    let (a, b, att_a) = bodies();
    let att_b = attach(&b.mesh, &b.skeleton, &AttachOptions::default()).unwrap();
    let (na, nb) = (outward(&a.mesh, &att_a), outward(&b.mesh, &att_b));
    let truth = bone_transforms(&a.skeleton, &b.skeleton);
    // Every bone's transform shifted 3 cm sideways and turned 0.6° about the camera's vertical
    // (2 cm at the body, 2 m away).
    let off = nalgebra::IsometryMatrix3::from_parts(
        nalgebra::Translation3::new(0.03, 0.0, 0.0),
        nalgebra::Rotation3::new(nalgebra::Vector3::new(0.0, 0.01, 0.0)),
    );
    let start = truth.map(|t| off * t);
    let graph = EdgeGraph::new(&b.mesh);
    let fit = |relaxation: f64| {
        let options = ArticulatedOptions {
            warm_iterations: 2,
            warm_nonrigid_rounds: 0,
            warm_relaxation: relaxation,
            ..ArticulatedOptions::default()
        };
        articulated_match(
            &side(&a.mesh, &att_a, &na, None),
            &att_a.weights,
            &side(&b.mesh, &att_b, &nb, None),
            &graph,
            &options,
            ArticulatedStart::Warm {
                transforms: &start,
                joints: &b.skeleton,
            },
        )
    };
    // Mean distance of the posed template from the target (the same vertices: the truth).
    let error = |posed: &[Point3<f64>]| {
        posed
            .iter()
            .zip(&b.mesh.positions)
            .map(|(p, q)| (p - Point3::from(*q)).norm())
            .sum::<f64>()
            / posed.len() as f64
    };
    let normals = a.mesh.vertex_normals();
    let (started, _) = skin(&a.mesh.positions, &normals, &att_a.weights, &start);
    let (plain, relaxed) = (fit(1.0).unwrap(), fit(1.5).unwrap());
    let (e0, e1, e15) = (error(&started), error(&plain.posed), error(&relaxed.posed));
    assert!(
        e1 < e0 && e15 < 0.8 * e1,
        "start {e0}, as fitted {e1}, relaxed {e15}"
    );
    for bad in [0.0, 2.0, f64::NAN] {
        match fit(bad) {
            Err(CorrespondError::InvalidOptions(m)) => assert!(m.contains("warm_relaxation")),
            other => panic!("{bad}: {:?}", other.map(|_| ())),
        }
    }
}

/// Mean confidence of the shown head vertices over that of the other shown vertices, without
/// and with the head twist doubt at `scale`, matching the capsule body (a nose added:
/// a round head has no twist to see) to a front view of itself whose head is turned by
/// `turn_deg` about its bone while the joints are not. Also checks that the doubt changes
/// confidences only, and only of head vertices, only downwards.
fn head_confidence_share(turn_deg: f64, scale: f64) -> (f64, f64) {
    let sk = t_pose(1.0);
    let (plain, _) = capsule_body(&sk, 0.012);
    let head_bone = symcorr_skeleton::BONES
        .iter()
        .position(|b| b.parent == Joint::ShoulderCenter && b.child == Joint::Head)
        .unwrap();
    let head_weight = |att: &symcorr_attach::Attachment, v: usize| -> f64 {
        att.weights
            .row(v)
            .iter()
            .filter(|&&(b, _)| b == head_bone)
            .map(|&(_, w)| w)
            .sum()
    };
    // A nose: the head's front pushed out towards +z, most at its middle.
    let plain_att = attach(&plain, &sk, &AttachOptions::default()).unwrap();
    let centre = sk.position(Joint::Head);
    let mut positions = plain.positions.clone();
    for (v, p) in positions.iter_mut().enumerate() {
        let d = Point3::from(*p) - centre;
        if head_weight(&plain_att, v) > 0.5 && d.z > 0.0 {
            p[2] += 0.06 * (-(d.x * d.x + d.y * d.y) / (2.0 * 0.03f64.powi(2))).exp();
        }
    }
    let mesh = TriMesh::new(positions, plain.triangles).unwrap();
    let att = attach(&mesh, &sk, &AttachOptions::default()).unwrap();
    let on_head = |v: usize| head_weight(&att, v) > 0.5;
    // The target: the same body, its head turned about the neck → head bone (the joints
    // stay), each vertex by its weight on the head bone.
    let pivot = sk.position(Joint::ShoulderCenter);
    let axis = nalgebra::Unit::new_normalize(sk.position(Joint::Head) - pivot);
    let mut turned = mesh.positions.clone();
    for (v, p) in turned.iter_mut().enumerate() {
        let w = head_weight(&att, v);
        if w > 0.0 {
            let r = nalgebra::Rotation3::from_axis_angle(&axis, w * turn_deg.to_radians());
            *p = (pivot + r * (Point3::from(*p) - pivot)).into();
        }
    }
    let body = TriMesh::new(turned, mesh.triangles.clone()).unwrap();
    let (scan, _) = front_view(&body, false);
    let att_s = attach(&scan, &sk, &AttachOptions::default()).unwrap();
    let (na, ns) = (outward(&mesh, &att), outward(&scan, &att_s));
    let boundary = scan.boundary_vertices();
    let run = |head_twist_doubt| {
        let options = ArticulatedOptions {
            head_twist_doubt,
            ..ArticulatedOptions::default()
        };
        let target = ArticulatedInputs {
            viewpoint: Some(Point3::new(0.0, 0.5, 3.0)),
            ..side(&scan, &att_s, &ns, Some(&boundary))
        };
        articulated_match(
            &side(&mesh, &att, &na, None),
            &att.weights,
            &target,
            &EdgeGraph::new(&scan),
            &options,
            ArticulatedStart::Skeletons,
        )
        .unwrap()
    };
    let (off, on) = (run(None), run(Some(scale)));
    let (mut head, mut rest, mut head_off, mut rest_off) = (vec![], vec![], vec![], vec![]);
    for (v, (p, q)) in off.pairs.iter().zip(&on.pairs).enumerate() {
        assert_eq!((p.template, p.target), (q.template, q.target));
        if head_weight(&att, v) > 0.0 {
            assert!(
                q.confidence <= p.confidence,
                "vertex {v}: {} > {}",
                q.confidence,
                p.confidence
            );
        } else {
            assert_eq!(q.confidence, p.confidence, "vertex {v} is not on the head");
        }
        if on.has_counterpart[v] {
            if on_head(v) {
                head.push(q.confidence);
                head_off.push(p.confidence);
            } else {
                rest.push(q.confidence);
                rest_off.push(p.confidence);
            }
        }
    }
    assert!(
        head.len() > 20 && rest.len() > 20,
        "{} head, {} other shown vertices",
        head.len(),
        rest.len()
    );
    let mean = |c: &[f64]| c.iter().sum::<f64>() / c.len() as f64;
    (mean(&head_off) / mean(&rest_off), mean(&head) / mean(&rest))
}

/// The head twist doubt (`ArticulatedOptions::head_twist_doubt`, at a scale of one standard
/// error) lowers the confidence of a head turned 30° against the joints, and leaves a head
/// that is not turned as it was.
#[test]
fn the_head_twist_doubt_lowers_a_turned_head() {
    let (straight, turned) = (
        head_confidence_share(0.0, 1.0),
        head_confidence_share(30.0, 1.0),
    );
    eprintln!(
        "head confidence over the rest (off, on): straight {straight:.3?}, turned {turned:.3?}"
    );
    assert!(
        turned.1 < 0.8 * turned.0,
        "turned head, off and on: {turned:?}"
    );
    assert!(
        straight.1 > 0.95 * straight.0,
        "straight head, off and on: {straight:?}"
    );
}
