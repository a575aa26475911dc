//! The generated skin, for every template at several sizes: a closed surface without
//! degenerate triangles, normalised weights of at most four joints, and at 200 random
//! postures within the joint limits (and 200 within three quarters, half and a quarter of
//! each range) no vertex far from its bones and only a bounded few triangles turned inside
//! out, at the creases of joints bent to the last quarter of their ranges, none within
//! half or a quarter of the ranges (the issue asked for none at all; skinning does not get
//! there, see the bounds at the end of `check`). The counts are printed, by the joint
//! that moves each inverted triangle most.

use std::collections::HashMap;
use troupe_body::glam::DVec3;
use troupe_body::kinematics::forward_kinematics;
use troupe_body::skin::MAX_TRIANGLES;
use troupe_body::{templates, Skeleton, Skin, TemplateParams, Transform};

#[path = "support/postures.rs"]
mod postures;
use postures::{counted_at, inverted, Lcg};

/// The bone segments of a joint: to each child joint and end site (a point for a leaf).
fn bones(skeleton: &Skeleton, globals: &[Transform], j: usize) -> Vec<(DVec3, DVec3)> {
    let from = globals[j].translation;
    let mut out: Vec<(DVec3, DVec3)> = skeleton
        .joints()
        .iter()
        .enumerate()
        .filter(|(_, c)| c.parent == Some(j))
        .map(|(c, _)| (from, globals[c].translation))
        .collect();
    out.extend(
        skeleton
            .end_sites()
            .iter()
            .filter(|(e, _)| *e == j)
            .map(|(_, off)| (from, globals[j].transform_point(*off))),
    );
    if out.is_empty() {
        out.push((from, from));
    }
    out
}

fn segment_distance(p: DVec3, (a, b): (DVec3, DVec3)) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-18)).clamp(0.0, 1.0);
    (p - (a + ab * t)).length()
}

/// The bone segments of every skinning slot in joint frames `globals`: a joint's own; a
/// helper's are its joint's and the joint's parent's (it sits at the joint between them).
fn slot_bones(skeleton: &Skeleton, skin: &Skin, globals: &[Transform]) -> Vec<Vec<(DVec3, DVec3)>> {
    let mut segs: Vec<_> = (0..skeleton.joints().len())
        .map(|j| bones(skeleton, globals, j))
        .collect();
    for h in &skin.helpers {
        let both = [segs[h.joint].clone(), segs[h.parent].clone()].concat();
        segs.push(both);
    }
    segs
}

/// Distance from `p` to each joint's nearest bone, for the joints that move it.
fn distances_to_bones(
    p: DVec3,
    joints: &[u16; 4],
    weights: &[f32; 4],
    segs: &[Vec<(DVec3, DVec3)>],
) -> [f64; 4] {
    let mut out = [0.0; 4];
    for ((d, &j), &w) in out.iter_mut().zip(joints).zip(weights) {
        if w > 0.0 {
            *d = segs[j as usize]
                .iter()
                .map(|&s| segment_distance(p, s))
                .fold(f64::INFINITY, f64::min);
        }
    }
    out
}

/// The postures' sets: each spans this part of every joint's range around zero, and has
/// this many postures.
const SPANS: [(f64, usize); 4] = [(1.0, 200), (0.75, 200), (0.5, 200), (0.25, 200)];

/// The inverted triangles counted over one set of postures.
#[derive(Default)]
struct Span {
    part: f64,
    postures: usize,
    /// Over all the set's postures.
    all: usize,
    /// At its worst posture.
    worst: usize,
    /// Over all its postures, those at the hands (moved most by a wrist or a finger).
    at_hands: usize,
    /// Over all its postures, by the joint that moves each most.
    by_joint: HashMap<String, usize>,
}

fn check(skeleton: &Skeleton, label: &str) {
    let started = std::time::Instant::now();
    let skin = Skin::build(skeleton).unwrap();
    let built = started.elapsed();
    let h = skin
        .positions
        .iter()
        .map(|p| p[1] as f64)
        .fold(0.0, f64::max);
    let n = skin.positions.len();
    let tris = skin.triangle_count();
    eprintln!(
        "{label}: {n} vertices, {tris} triangles (far {}), built in {built:?}",
        skin.far_indices.len() / 3
    );
    assert!(
        tris <= MAX_TRIANGLES && tris > 5_000,
        "{label}: {tris} triangles"
    );

    // Closed: every directed edge appears once, and its reverse once.
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in skin.indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &count) in &edges {
        assert_eq!(
            count, 1,
            "{label}: edge {a}-{b} used {count} times the same way"
        );
        assert_eq!(
            edges.get(&(b, a)),
            Some(&1),
            "{label}: edge {a}-{b} has no twin: the surface has a hole"
        );
    }
    // Euler characteristic V - E + F: 2 for one closed surface of genus 0.
    let chi = n as i64 - (edges.len() / 2) as i64 + tris as i64;
    assert_eq!(chi, 2, "{label}: Euler characteristic {chi}");

    // No degenerate triangles at rest: three distinct vertices, not (nearly) on a line.
    let pos = |i: u32| DVec3::from(skin.positions[i as usize].map(f64::from));
    for t in skin.indices.chunks_exact(3) {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "{label}: repeated vertex in {t:?}"
        );
        let [a, b, c] = [pos(t[0]), pos(t[1]), pos(t[2])];
        let area = (b - a).cross(c - a).length() / 2.0;
        let longest = (b - a).length().max((c - b).length()).max((a - c).length());
        assert!(
            area > 1e-12 && area / (longest * longest) > 1e-3,
            "{label}: triangle {t:?} is degenerate: area {area:e} m², longest edge {longest:e} m"
        );
    }

    // Weights: at most four, each in [0, 1], summing to one; joints exist.
    for (js, ws) in skin.joints.iter().zip(&skin.weights) {
        let sum: f32 = ws.iter().sum();
        assert!(
            (sum - 1.0).abs() < 1e-6,
            "{label}: weights {ws:?} sum to {sum}"
        );
        assert!(
            ws.iter().all(|w| (0.0..=1.0).contains(w)),
            "{label}: weights {ws:?}"
        );
        assert!(js.iter().all(|&j| (j as usize) < skin.rest.len()));
    }

    // The bound: at rest, how far each vertex lies from the bones that move it.
    let rest_segs = slot_bones(skeleton, &skin, &skin.rest);
    let rest_distance: Vec<[f64; 4]> = (0..n)
        .map(|v| distances_to_bones(pos(v as u32), &skin.joints[v], &skin.weights[v], &rest_segs))
        .collect();
    let slack = 0.05 * h;

    // The hands: the wrists and every joint below them.
    let in_hand: Vec<bool> = (0..skeleton.joints().len())
        .map(|j| {
            std::iter::successors(Some(j), |&k| skeleton.joints()[k].parent)
                .any(|k| skeleton.joints()[k].name.ends_with("wrist"))
        })
        .collect();

    let mut rng = Lcg(7);
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    let mut worst_excess = (0.0f64, 0, 0);
    let mut spans: Vec<Span> = SPANS
        .iter()
        .map(|&(part, postures)| Span {
            part,
            postures,
            ..Span::default()
        })
        .collect();
    let mut posture = 0;
    for span in &mut spans {
        for _ in 0..span.postures {
            let q = postures::posture(skeleton, &mut rng, span.part);
            forward_kinematics(skeleton, &q, &mut globals);
            let posed = skin.deform(&globals);
            let frames = skin.frames(&globals);
            let segs = slot_bones(skeleton, &skin, &globals);
            for v in 0..n {
                // How much further the vertex is from its bones than at rest, each bone's
                // share by its weight: a vertex moved 2 % by the upper arm does not stray
                // when the arm is raised away from it, one pulled from all its bones does.
                let d = distances_to_bones(posed[v], &skin.joints[v], &skin.weights[v], &segs);
                let excess: f64 = (0..4)
                    .map(|k| (d[k] - rest_distance[v][k]) * skin.weights[v][k] as f64)
                    .sum();
                if excess > worst_excess.0 {
                    worst_excess = (excess, posture, v);
                }
            }
            // Inverted triangles (`postures::inverted`), each counted at the joint that
            // most moves its first vertex.
            let mut inverted_here = 0;
            for t in inverted(&skin, &posed, &frames) {
                inverted_here += 1;
                let joint = counted_at(&skin, t);
                if in_hand[joint] {
                    span.at_hands += 1;
                }
                *span
                    .by_joint
                    .entry(skeleton.joints()[joint].name.clone())
                    .or_default() += 1;
            }
            span.all += inverted_here;
            span.worst = span.worst.max(inverted_here);
            posture += 1;
        }
    }
    let (excess, posture, v) = worst_excess;
    for span in &spans {
        let mut places: Vec<_> = span.by_joint.iter().collect();
        places.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
        eprintln!(
            "{label}: at {} of the ranges, {} inverted triangles over {} postures ({} at the hands), {} at the worst; by joint: {places:?}",
            span.part, span.all, span.postures, span.at_hands, span.worst
        );
    }
    eprintln!(
        "{label}: a vertex strays at most {:.3} h ({excess:.3} m) further from its bones than at rest",
        excess / h
    );
    assert!(
        excess <= slack,
        "{label}, posture {posture}: vertex {v} at {:?} moved by {:?} strays {excess:.3} m further from its bones than at rest",
        skin.positions[v],
        skin.joints[v]
            .iter()
            .zip(skin.weights[v])
            .filter(|(_, w)| *w > 0.0)
            .map(|(&j, w)| (skeleton.joints()[skin.slot_joint(j as usize)].name.as_str(), w))
            .collect::<Vec<_>>(),
    );
    // Skinning folds the inner side of a strongly bent joint unless its band of weights is
    // long enough: on a band of length L that turns the skin at distance r from the joint
    // by θ, a linear blend of two rotations folds when L < 2·r·tan(θ/2); the groin at a hip
    // flexed by 120° asks for a band longer than the pelvis (docs/viewer.md). So a few
    // triangles turn over in the last quarter of the ranges (docs/skin-notes.md has every
    // step and the draws behind these figures): over each size's 200 postures within the
    // whole ranges 18-50 (0.09-0.25 a posture, 2-10 at the worst, 0-2 at the hands), within
    // three quarters 0-1, within half or a quarter none. The bounds keep them there: a
    // change that folds more fails.
    let [full, three_quarters, half, quarter] = &spans[..] else {
        unreachable!("four sets of postures")
    };
    let fraction = |k: usize| k as f64 / tris as f64;
    assert!(
        full.all as f64 <= 0.3 * full.postures as f64
            && fraction(full.worst) <= 0.0005
            && full.at_hands <= 3,
        "{label}: {} triangles turned inside out over the {} postures within the whole ranges ({} at the worst, {} at the hands)",
        full.all,
        full.postures,
        full.worst,
        full.at_hands
    );
    assert!(
        three_quarters.all <= 1 && half.all == 0 && quarter.all == 0,
        "{label}: {}, {} and {} triangles turned inside out within three quarters, half and a quarter of the ranges",
        three_quarters.all,
        half.all,
        quarter.all
    );
}

#[test]
fn every_template_at_several_sizes_is_skinned_soundly() {
    for t in templates() {
        for scale in [0.8, 1.0, 1.15] {
            let params = TemplateParams {
                height: t.default_height * scale,
                mass: t.default_mass * scale.powi(3),
            };
            let skeleton = t.instantiate(params).unwrap();
            check(&skeleton, &format!("{} {:.2} m", t.name, params.height));
        }
    }
}

#[test]
fn the_skin_cut_along_its_regions_is_the_same_surface_one_region_per_triangle() {
    use troupe_body::skin::CutSkin;
    let t = &templates()[0];
    let skeleton = t
        .instantiate(TemplateParams {
            height: t.default_height,
            mass: t.default_mass,
        })
        .unwrap();
    let skin = Skin::build(&skeleton).unwrap();
    // Both levels of detail: the full one (glTF files), the coarse one (the viewer's
    // actors far away, coloured by vertex).
    for (level, cut, triangles) in [
        ("full", CutSkin::new(&skin), &skin.indices),
        ("far", CutSkin::far(&skin), &skin.far_indices),
        ("farthest", CutSkin::farthest(&skin), &skin.farthest_indices),
    ] {
        check_cut(level, &skin, &cut, triangles);
    }
}

/// `cut`, made from `skin`'s `triangles`: more triangles, almost all in one region each;
/// the same area; closed once the copies on the edges are welded, as `triangles` are;
/// weights normalised.
fn check_cut(level: &str, skin: &Skin, cut: &troupe_body::skin::CutSkin, triangles: &[u32]) {
    let tris = cut.indices.len() / 3;
    let mixed = cut
        .indices
        .chunks_exact(3)
        .filter(|t| {
            let r = t
                .iter()
                .map(|&v| cut.regions[v as usize])
                .collect::<Vec<_>>();
            r[0] != r[1] || r[1] != r[2]
        })
        .count();
    let used: std::collections::HashSet<u32> = triangles.iter().copied().collect();
    eprintln!(
        "{level} level cut: {} vertices and {tris} triangles (uncut: {} and {}); {mixed} triangles where three regions meet",
        cut.positions.len(),
        used.len(),
        triangles.len() / 3
    );
    assert!(tris > triangles.len() / 3 && mixed * 500 < tris, "{level}");
    // The same surface: as much area, and closed once the copies on the edges are
    // welded (every edge between two welded vertices once each way).
    let area = |positions: &[[f32; 3]], indices: &[u32]| -> f64 {
        indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] =
                    [0, 1, 2].map(|k| DVec3::from(positions[t[k] as usize].map(f64::from)));
                (b - a).cross(c - a).length() / 2.0
            })
            .sum()
    };
    let (before, after) = (
        area(&skin.positions, triangles),
        area(&cut.positions, &cut.indices),
    );
    assert!(
        (after - before).abs() < 1e-6 * before,
        "{level}: area {before} m² became {after} m²"
    );
    // Welded, the cut is closed wherever the triangles it was cut from are: every edge
    // once each way. (The coarse level, simplified without the full level's care for
    // pinches, has a few edges that are not.)
    let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
    let mut weld = |p: [f32; 3]| {
        let n = welded.len() as u32;
        *welded.entry(p.map(f32::to_bits)).or_insert(n)
    };
    let id: Vec<u32> = cut.positions.iter().map(|&p| weld(p)).collect();
    let uncut_id: Vec<u32> = skin.positions.iter().map(|&p| weld(p)).collect();
    let open_edges = |indices: &[u32], id: &[u32]| {
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in indices.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((id[a as usize], id[b as usize])).or_default() += 1;
            }
        }
        let mut open: Vec<(u32, u32)> = edges
            .iter()
            .filter(|(&(a, b), &count)| count != 1 || edges.get(&(b, a)) != Some(&1))
            .map(|(&e, _)| e)
            .collect();
        open.sort_unstable();
        open
    };
    let (open, open_before) = (
        open_edges(&cut.indices, &id),
        open_edges(triangles, &uncut_id),
    );
    eprintln!(
        "{level} level: {} edges not shared once each way, as before the cut",
        open.len()
    );
    assert_eq!(open, open_before, "{level}: the cut opened or closed edges");
    // No holes, though: every edge has its reverse (the viewer culls back faces, so a
    // hole would show through the body).
    let mut directed = std::collections::HashSet::new();
    for t in triangles.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            directed.insert((uncut_id[a as usize], uncut_id[b as usize]));
        }
    }
    let holes = directed
        .iter()
        .filter(|(a, b)| !directed.contains(&(*b, *a)))
        .count();
    assert_eq!(holes, 0, "{level}: {holes} edges without their reverse");
    // Triangles turned over at rest (facing against their vertices' normals): a few,
    // inside small folds where a neighbour covers them, so culling them hides nothing.
    let pos = |i: u32| DVec3::from(skin.positions[i as usize].map(f64::from));
    let normal = |i: u32| DVec3::from(skin.normals[i as usize].map(f64::from));
    let turned = triangles
        .chunks_exact(3)
        .filter(|t| {
            let n = (pos(t[1]) - pos(t[0])).cross(pos(t[2]) - pos(t[0]));
            n.dot(normal(t[0]) + normal(t[1]) + normal(t[2])) <= 0.0
        })
        .count();
    eprintln!("{level} level: {turned} triangles turned over at rest");
    assert!(
        turned * 100 < triangles.len() / 3,
        "{level}: {turned} turned over"
    );
    for ws in &cut.weights {
        let sum: f32 = ws.iter().sum();
        assert!((sum - 1.0).abs() < 1e-5, "{level}: weights {ws:?}");
    }
}
