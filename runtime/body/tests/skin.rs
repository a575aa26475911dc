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
use troupe_body::skin::{FARTHEST_TRIANGLES, FAR_TRIANGLES, MAX_TRIANGLES};
use troupe_body::{templates, Skeleton, Skin, TemplateParams, Transform};

#[path = "support/postures.rs"]
mod postures;
use postures::{counted_at, inverted};

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

/// Asserts that every triangle of `indices` has its mirror image among them, `image`
/// giving each vertex's image (the image wound the other way, to face out as well).
fn assert_mirrored_triangles(label: &str, indices: &[u32], image: &[usize]) {
    let triangles: std::collections::HashSet<[usize; 3]> = indices
        .chunks_exact(3)
        .map(|t| rotated([t[0], t[1], t[2]].map(|v| v as usize)))
        .collect();
    for t in &triangles {
        assert!(
            triangles.contains(&rotated([image[t[0]], image[t[2]], image[t[1]]])),
            "{label}: triangle {t:?} has no mirror image"
        );
    }
}

/// A place's bits, -0 taken for 0 (a vertex on the sagittal plane is its own image).
fn place_bits([x, y, z]: [f32; 3]) -> [u32; 3] {
    [x + 0.0, y, z].map(f32::to_bits)
}

/// The bits of the mirror image of a place across the sagittal plane (x = 0).
fn image_bits([x, y, z]: [f32; 3]) -> [u32; 3] {
    place_bits([-x, y, z])
}

/// Triangle `t` rotated to start at its lowest vertex (the same triangle, the same way
/// round).
fn rotated(t: [usize; 3]) -> [usize; 3] {
    let k = (0..3).min_by_key(|&k| t[k]).expect("three corners");
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
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

fn check(skeleton: &Skeleton, label: &str) -> Vec<Span> {
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
    let (far, farthest) = (skin.far_indices.len() / 3, skin.farthest_indices.len() / 3);
    assert!(
        far <= FAR_TRIANGLES && farthest <= FARTHEST_TRIANGLES,
        "{label}: {far} and {farthest} triangles at the coarse levels"
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

    // Its own mirror image across the sagittal plane (x = 0): every vertex's image a
    // vertex, every triangle's image a triangle, and every vertex's weights its image's,
    // the left's joints and helpers for the right's.
    let at: HashMap<[u32; 3], usize> = skin
        .positions
        .iter()
        .enumerate()
        .map(|(v, &p)| (place_bits(p), v))
        .collect();
    let image: Vec<usize> = skin
        .positions
        .iter()
        .map(|&p| {
            *at.get(&image_bits(p))
                .unwrap_or_else(|| panic!("{label}: no vertex at the image of {p:?}"))
        })
        .collect();
    assert_mirrored_triangles(label, &skin.indices, &image);
    let slot_name = |slot: u16| {
        let joints = skeleton.joints().len();
        let slot = slot as usize;
        match slot.checked_sub(joints) {
            Some(h) => skin.helpers[h].name.clone(),
            None => skeleton.joints()[slot].name.clone(),
        }
    };
    let other_side = |name: String| match name.split_at_checked(2) {
        Some(("l_", rest)) => format!("r_{rest}"),
        Some(("r_", rest)) => format!("l_{rest}"),
        _ => name,
    };
    for (v, &w) in image.iter().enumerate() {
        let mut shares: HashMap<String, f32> = HashMap::new();
        for k in 0..4 {
            *shares.entry(slot_name(skin.joints[v][k])).or_default() += skin.weights[v][k];
            *shares
                .entry(other_side(slot_name(skin.joints[w][k])))
                .or_default() -= skin.weights[w][k];
        }
        assert!(
            shares.values().all(|d| d.abs() < 1e-6),
            "{label}: the weights of vertex {v} and of its image {w} differ: {shares:?}"
        );
    }

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

    let mut draw = troupe_body::math::draws(7);
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
            let q = postures::posture(skeleton, &mut draw, span.part);
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
    // flexed by 120° from where the skin is bound asks for a band longer than the pelvis
    // (docs/viewer.md); bound with the hips a little flexed (`skin::binding`) it turns 100°
    // at most. So a few triangles turn over in the last quarter of the ranges
    // (docs/skin-notes.md has every step and the draws behind these figures). Each size's
    // skin is a sample of its own of where the grid's samples fall, and its folds change
    // with that as much as with the weights (docs/skin-notes.md, "The two sides
    // mirrored"), so the six sizes are bounded together
    // (`every_template_at_several_sizes_is_skinned_soundly`), and each on its own only
    // loosely: over its 200 postures within the whole ranges 7-55 (2-6 at the worst
    // posture), none within half or a quarter of the ranges.
    let [full, _, half, quarter] = &spans[..] else {
        unreachable!("four sets of postures")
    };
    let fraction = |k: usize| k as f64 / tris as f64;
    assert!(
        full.all as f64 <= 0.3 * full.postures as f64 && fraction(full.worst) <= 0.0005,
        "{label}: {} triangles turned inside out over the {} postures within the whole ranges ({} at the worst)",
        full.all,
        full.postures,
        full.worst,
    );
    assert!(
        half.all == 0 && quarter.all == 0,
        "{label}: {} and {} triangles turned inside out within half and a quarter of the ranges",
        half.all,
        quarter.all
    );
    spans
}

#[test]
fn every_template_at_several_sizes_is_skinned_soundly() {
    let mut totals: [Span; 4] = Default::default();
    for t in templates() {
        for scale in [0.8, 1.0, 1.15] {
            let params = TemplateParams {
                height: t.default_height * scale,
                mass: t.default_mass * scale.powi(3),
            };
            let skeleton = t.instantiate(params).unwrap();
            let spans = check(&skeleton, &format!("{} {:.2} m", t.name, params.height));
            for (total, span) in totals.iter_mut().zip(spans) {
                total.postures += span.postures;
                total.all += span.all;
                total.at_hands += span.at_hands;
            }
        }
    }
    // The six sizes together: over their 1,200 postures within the whole ranges 131
    // triangles turned over (214 bound where the skin is made), 9 of them at the hands;
    // within three quarters 2. The bounds keep them there: a change that folds more fails.
    let [full, three_quarters, ..] = &totals;
    eprintln!(
        "all sizes: {} inverted triangles over {} postures within the whole ranges ({} at the hands), {} within three quarters",
        full.all, full.postures, full.at_hands, three_quarters.all
    );
    assert!(
        full.all as f64 <= 0.125 * full.postures as f64 && full.at_hands <= 10,
        "{} triangles turned inside out over the {} postures of every size within the whole ranges ({} at the hands)",
        full.all,
        full.postures,
        full.at_hands
    );
    assert!(
        three_quarters.all <= 2,
        "{} triangles turned inside out over the postures of every size within three quarters of the ranges",
        three_quarters.all
    );
}

#[test]
fn the_skin_cut_along_its_regions_is_the_same_surface_one_region_per_triangle() {
    use troupe_body::skin::CutSkin;
    // The skins a scene uses: each template's at its default height (every other height
    // shares it).
    for t in templates() {
        let skeleton = t
            .instantiate(TemplateParams {
                height: t.default_height,
                mass: t.default_mass,
            })
            .unwrap();
        let skin = Skin::build(&skeleton).unwrap();
        // Every level of detail: the full one (glTF files), the coarse ones (the viewer's
        // actors far away, coloured by vertex).
        for (level, cut, triangles) in [
            ("full", CutSkin::new(&skin), &skin.indices),
            ("far", CutSkin::far(&skin), &skin.far_indices),
            ("farthest", CutSkin::farthest(&skin), &skin.farthest_indices),
        ] {
            check_cut(&format!("{} {level}", t.name), &skin, &cut, triangles);
        }
    }
}

/// `cut`, made from `skin`'s `triangles`: more triangles, each in one region;
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
        "{level} level cut: {} vertices and {tris} triangles (uncut: {} and {}); {mixed} triangles in more than one region",
        cut.positions.len(),
        used.len(),
        triangles.len() / 3
    );
    assert!(tris > triangles.len() / 3 && mixed == 0, "{level}");
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
    // Welded, the cut is closed as the triangles it was cut from are: every edge once
    // each way (every level is simplified with the same care for pinches).
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
    assert!(
        open.is_empty(),
        "{level}: {} edges not shared once each way",
        open.len()
    );
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
    // Its own mirror image, as the skin it is cut from: each vertex's image a vertex of
    // its region, to the bit or (a point cut from the edge's other end) within a
    // micrometre, and each triangle's image a triangle.
    let at: HashMap<([u32; 3], troupe_body::skin::Region), usize> = cut
        .positions
        .iter()
        .zip(&cut.regions)
        .enumerate()
        .map(|(v, (&p, &r))| ((place_bits(p), r), v))
        .collect();
    let place = |v: usize| DVec3::from(cut.positions[v].map(f64::from));
    let image: Vec<usize> = (0..cut.positions.len())
        .map(|v| {
            let (p, r) = (cut.positions[v], cut.regions[v]);
            at.get(&(image_bits(p), r)).copied().unwrap_or_else(|| {
                let want = place(v) * DVec3::new(-1.0, 1.0, 1.0);
                let nearest = (0..cut.positions.len())
                    .filter(|&w| cut.regions[w] == r)
                    .min_by(|&a, &b| {
                        (place(a) - want)
                            .length()
                            .total_cmp(&(place(b) - want).length())
                    })
                    .expect("the vertex's own region");
                let off = (place(nearest) - want).length();
                assert!(
                    off < 1e-6,
                    "{level}: vertex {v} at {p:?} has no image ({off:e} m off)"
                );
                nearest
            })
        })
        .collect();
    assert_mirrored_triangles(level, &cut.indices, &image);
}
