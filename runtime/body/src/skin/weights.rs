//! Skin weights: how much each joint moves each vertex, in three steps.
//!
//! 1. **Near weights**: a vertex belongs to the volume it is nearest to; that volume's
//!    joint and the joints next to it (parent and children) share the vertex by how close
//!    their volumes come, fading out over each volume's reach. So an elbow vertex is
//!    shared by the upper arm and the forearm, while a hand hanging by the hip takes
//!    nothing from the pelvis.
//! 2. **Diffusion over the surface** (bone-heat style smoothing, as in Baran & Popović's
//!    Pinocchio): the near weights jump where a vertex's nearest volume changes (the
//!    joints allowed to share it change with it), and they blend over too short a band
//!    where a joint bends far. Each vertex's weights are averaged with its neighbours'
//!    along the surface's edges, over a distance proportional to the reach of the nearest
//!    volume (which grows with the limb's thickness); the jumps become smooth ramps and
//!    each joint's bend spreads over a wider band, so far fewer triangles turn over where
//!    a joint bends.
//! 3. **Through the helpers**: the weight a vertex gives a helped joint and its parent's
//!    end (the band across a shoulder: the clavicle and the chest's vt1) is moved onto the
//!    chain parent → helpers → joint ([`super::helpers`]), to the two neighbours on the
//!    chain that bracket the joint's share, so the vertex turns by about the same part of
//!    the bend but as a blend of two nearly equal rotations. Those helpers take the
//!    joint's swing only; what is left of the joint's own weight goes down the limb's
//!    twist helpers, by how far along the bone the vertex lies ([`TWIST_SPAN`]). At the
//!    hips, knees, elbows, vc4 and the skullbase the joint's weight near the joint goes
//!    likewise to its sliding helper, and back to the joint further down the limb (up
//!    the neck; under the jaw, [`HEAD_SPAN`]). First, below vc4 the head's weight gives
//!    way to vc4's ([`HEAD_FLOOR`]), so that none of it reaches the root of the neck.
//!    Last, the weight two neighbouring fingers' knuckles share (the web between them)
//!    goes through the helper between them ([`super::helpers::WEBS`]) in the same way:
//!    onto the two of knuckle, helper and knuckle that bracket the pair's split.
//! 4. **Four at most**: the four heaviest joints keep the excess of their weight over the
//!    fifth heaviest (or over a trace of 5 %, whichever is more), so a joint's weight
//!    reaches zero before it drops out and the weights stay continuous over the surface;
//!    they are normalised to sum to one.

use super::helpers::Helper;
use super::volumes::{Join, Volume};
use glam::DVec3;

/// Up to four joints and their weights, heaviest first; unused slots hold joint 0 with
/// weight 0 (glTF's convention).
pub type Influences = ([u16; 4], [f32; 4]);

/// Smoothing length over the surface, as a multiple of the reach of the volume nearest
/// to the vertex (the reach grows with the limb's thickness: 12 cm on the trunk, 9 cm on
/// the arms, 1.2 cm on the fingers for a 1.75 m adult). Where the edges are long it is
/// capped at [`MOST_EDGES`]. With the shoulders' helper joints, 1.2 turned fewer
/// triangles over than 0.6 (the rotation about the shoulder needs a long band); without
/// them it turned more.
const SMOOTHING_PER_REACH: f64 = 1.2;
/// The widest smoothing, in mean edge lengths around the vertex (√60: what 60 rounds of
/// moving all the way to the neighbours' mean reach, the cap the weights were tuned
/// with).
const MOST_EDGES: f64 = 7.745_966_692_414_834;
/// How much wider the bands are where a vertex's nearest volume is one of the joints
/// given this `band` in [`skin_weights`] (the groin and the lower belly; the upper arms have
/// [`UPPER_ARM`]), in
/// both the smoothing length and its cap: a hip flexed to 120° folds a band shorter than
/// about twice the skin's distance from the hip. 1.5 took the children's worst full-range
/// posture from 71-103 inverted triangles to 56-69 and changed nothing at half ranges;
/// 2 did worse for the smallest child. Raised later to 1.55 (with [`UPPER_ARM`] and
/// [`NECK_ROOT`]): the hips' and the pelvis's inverted triangles in the skin test (summed
/// over its six sizes' 50 full-range postures) went from 17 to 14, all of them from 46
/// to 43 (1.4: 49); 1.6, 1.65 and 1.7 alike gave 40, because [`SMOOTHING_ROUNDS`] capped
/// the widest vertices' smoothing. With the rounds they lack run for them alone
/// (`diffuse`), 1.65 took the hips and the pelvis to 8 and all of them to 37, every size
/// fewer or as many; 1.6 and 1.68 gave 38, 1.7 40 (the 1.38 m child's worst posture one
/// worse), 1.85 and 2 gave 53 and 85 (the lower belly folding). Those 50 postures were
/// too few: the weights had been tuned to them, and ten other draws of 50 folded about
/// 80 times as many per posture (`examples/skin_folds.rs`). Measured on those draws, five to choose
/// by and five held out, 1.8 turned 1,510 triangles over against 1,666 at 1.65, fewer on
/// both halves (475 + 1,035 against 510 + 1,156) and at the hips above all (the hips and
/// the pelvis 1,004 → 848); 1.5 1,987, 2.0 1,558, 2.3 11,294 (almost all at the hips
/// and the pelvis).
pub(crate) const WIDER: f64 = 1.8;
/// How much narrower the bands are at the root of the neck and the chest beside it (the
/// joints given this `band`): a child's neck is short, and smoothed over the usual length
/// the head's weight (skullbase) reached the top of the shoulders, where a head turned
/// 45° or an arm raised folded the skin between five joints. 0.6 took the triangles
/// turned over at half ranges, summed over the skin test's six sizes and 50 postures,
/// from 97 to 1, and at full ranges from 1,799 to 1,098; 0.45 and 0.75 did a little worse,
/// vc4 and the skullbase without vt1 (or vt1 alone) much less. vc4 now has its own,
/// narrower still ([`NECK`]).
pub(crate) const NARROWER: f64 = 0.6;
/// How much wider the bands are at the upper arms (the shoulders' volumes): a little less
/// than the groin's [`WIDER`]. 1.5 (the groin's) was set before the skin was made in the
/// A-pose; since then, and with the sliding helpers, 1.4 took the shoulders' inverted
/// triangles in the skin test (summed over its six sizes' 50 full-range postures) from
/// 18 to 5, all of them from 70 to 57, and the 0.96 m child's worst posture from 5 to 1
/// (the elbow's crease and the armpit); 1.35 and 1.45 did as well (with [`NECK_ROOT`]:
/// 44 and 47 against 46), 1.3 turned one over at half ranges, 1.6 failed (33 at the
/// 0.96 m child's worst posture). Narrowed to 1.35 once the webs between the fingers had
/// their helpers: the shoulders' from 3 to 1 and all of them from 14 to 12 (the elbow's
/// crease at 147° with the arm raised and an arm raised 179° unfolded), every size fewer
/// or as many; 1.32 and 1.37 gave 12 as well, 1.4 14, 1.45 15, 1.3 one at half ranges.
pub(crate) const UPPER_ARM: f64 = 1.35;
/// How narrow the band is at vt1, the root of the neck: a little wider than the
/// [`NARROWER`] of the skullbase and the clavicles (vc4's was that too, then). With [`UPPER_ARM`] it took vt1's
/// inverted triangles in the skin test from 23 (at 0.6) to 16 and all of them from 57 to
/// 46; 0.65 and 0.75 gave 50 and 51 (0.75 leaves the 1.38 m child's worst posture at 3,
/// one more than before), 0.8 alone failed the test (24 over the 1.20 m child's 50).
pub(crate) const NECK_ROOT: f64 = 0.7;
/// How narrow the band is at vc4, the neck (its volume): narrower than the [`NARROWER`]
/// of the skullbase and the clavicles, so that less of vc4's turn reaches the root of the
/// neck, where vt1, vc4, a clavicle and the head's helper share the skin and a neck bent
/// and twisted 30-35° with a clavicle raised to its 40° folded it. In the skin test
/// (six sizes' 50 full-range postures, the groin at [`WIDER`]) it took vt1's inverted
/// triangles from 16 to 11 and all of them from 37 to 32, every size fewer or as many;
/// 0.4 and 0.5 gave 31 and 32 (0.4 one more for the 2.01 m adult), 0.35 33, 0.3 47,
/// 0.55 35, 0.7 51.
pub(crate) const NECK: f64 = 0.45;
/// How much wider the bands are at the palms (the wrists' volumes): the knuckles'
/// bands reach further into the palm, and the forearm's (the elbow's) weight no longer
/// reaches a small hand's knuckles, where a little finger bent 64-84° with the wrist
/// bent back 55-70° folded the skin. In the skin test (six sizes' 50 full-range
/// postures, with [`WIDER`] and [`NECK`]) it took the hands' inverted triangles from 10
/// to 7 and all of them from 32 to 29, every size fewer or as many; 1.4 and 1.6 gave the
/// same, 1.2 and 1.3 8 at the hands, 2 8, 0.8 14.
pub(crate) const PALM: f64 = 1.5;
/// How much narrower the bands are at the middle phalanges of the index, middle and ring
/// fingers (the volumes of their middle joints, `index2`, …): the phalanx is short, and
/// smoothed over the usual length the knuckle's and the last joint's weights met on it,
/// so a vertex there blended three joints turned by 61°, 169° and 243° from the palm (the
/// 1.20 m child's ring finger, its knuckle at 61°, its middle joint at 108° and its last
/// joint at 74°), which folded it. In the skin test (six sizes' 50 full-range postures)
/// it took that fold away, no other moving; 0.65 and 0.75 did the same, 0.85 and 1.2 not,
/// and the little finger's middle phalanx narrowed as well (0.65-0.8) folded the 2.01 m
/// adult's little finger bent 82° and 109° instead.
pub(crate) const FINGER_MIDDLE: f64 = 0.7;
/// How much narrower the band is at the little finger's first phalanx (the volume of its
/// knuckle, `pinky1`): less of its weight, and of its middle joint's, reaches the web
/// beside the ring finger and the palm, where the 0.96 m child's little finger bent 83°
/// (its middle joint 101°) beside a ring finger turned away folded the skin shared by the
/// palm (the wrist), the knuckle, the web's helper and the middle joint. In the skin test
/// it took that fold away, no other moving; 0.8 and 0.9 did the same, 0.7 folded one at
/// the 1.38 m child's wrist, 1.2 one at the 0.96 m child's palm. (All the knuckles'
/// bands at 0.8, measured a round before, folded more: 18 against 14.)
pub(crate) const LITTLE_KNUCKLE: f64 = 0.85;
/// Smoothing rounds: each moves a vertex's weights at most all the way to its
/// neighbours' mean, so they reach √150 edge lengths; the few vertices that ask for more
/// ((WIDER × MOST_EDGES)² = 163 at the groin) get the rounds they lack alone (`diffuse`).
/// 200 rounds for every vertex moved every vertex's weights a little, and the folds
/// elsewhere with them.
const SMOOTHING_ROUNDS: usize = 150;

/// Weights under this (after smoothing, in a normalised row) are dropped, continuously:
/// every weight kept is lowered by it. Smoothing leaves traces of a joint far from it
/// (a few per cent of the shoulder on the chest below the armpit) that would tie the
/// skin there to a bone that moves away from it.
const TRACE: f64 = 0.05;

/// Weights under this are dropped while smoothing.
const NEGLIGIBLE: f64 = 1e-4;

/// A vertex's weights while they are smoothed: (joint, weight) pairs summing to one
/// (less the negligible ones dropped).
type Row = Vec<(u16, f64)>;

/// The weights of every vertex of a closed surface (bind-pose positions `positions`,
/// triangles `indices`); `band` scales the smoothing's length and cap for the vertices
/// whose nearest volume is each joint's ([`WIDER`], [`UPPER_ARM`], [`NARROWER`],
/// [`NECK_ROOT`], [`NECK`], [`PALM`], [`FINGER_MIDDLE`], [`LITTLE_KNUCKLE`] or 1).
pub(crate) fn skin_weights(
    positions: &[DVec3],
    indices: &[u32],
    volumes: &[Volume],
    neighbours: &impl Fn(usize, usize) -> bool,
    chains: &Chains,
    band: &[f64],
) -> Vec<Influences> {
    let mut rows = Vec::with_capacity(positions.len());
    let mut smoothing = Vec::with_capacity(positions.len());
    for &p in positions {
        let (near, reach, home) = near_weights(p, volumes, neighbours);
        let total: f64 = near.iter().map(|(_, w)| w).sum();
        rows.push(near.iter().map(|&(j, w)| (j as u16, w / total)).collect());
        let widen = band[home];
        smoothing.push(Smoothing {
            length: SMOOTHING_PER_REACH * reach * widen,
            most_edges: MOST_EDGES * widen,
        });
    }
    diffuse(&mut rows, positions, indices, &smoothing);
    rows.iter()
        .zip(positions)
        .map(|(row, &p)| four_heaviest(&chains.route(row, p)))
        .collect()
}

/// The chains of skinning slots across the helped joints, and the webs between pairs of
/// joints.
pub(crate) struct Chains(Vec<Chain>, Vec<Web>, Option<Lean>);

/// The lower belly's skin leaning on the pelvis beside a flexed hip: where the hips'
/// sliding helpers (`by`) have weight `w` (the larger of the two), that share of the
/// lower spine's (`from`, vl5) weight goes to the pelvis (`to`), so that the belly
/// above the groin blends the pelvis and the flexed hip's helper rather than three
/// rotations: the lumbar spine bent forward squeezes the belly above vl5 while the
/// thigh comes up into it, and the three-way blend folded a triangle there (the 1.20 m
/// child's hip flexed 106° with vl5 bent 37° forward). Continuous: where the helpers'
/// weight fades out nothing moves.
pub(crate) struct Lean {
    pub(crate) from: u16,
    pub(crate) to: u16,
    pub(crate) by: Vec<u16>,
}

/// The helpers between two joints (the web between two fingers' knuckles,
/// `helpers::WEBS`): the skin that both joints share blends them through the helpers,
/// as a chain does a joint and its parent.
struct Web {
    /// The joint the helpers take their share from ([`Helper::joint`]).
    first: u16,
    /// The other ([`Helper::pair`]).
    second: u16,
    /// The helpers' slots and their shares of the way from the first to the second,
    /// ascending.
    links: Vec<(u16, f64)>,
}

/// One helped joint's chain: its parent end, its helpers' slots by fraction, the joint.
struct Chain {
    /// The joints at the parent's end of the chain: the helped joint's parent, then
    /// `ends - 1` of its next ancestors (see [`Chains::new`]).
    parents: Vec<u16>,
    joint: u16,
    /// Helper slots across the joint and the fraction of the joint's swing each takes,
    /// ascending.
    links: Vec<(u16, f64)>,
    /// Helper slots along the limb (the whole swing), ascending by the fraction of the
    /// joint's twist each takes, and each one's place on the ladder: evenly spaced from
    /// 0, the joint itself being at 1 (the shoulder's rungs at 0, ¼, ½ and ¾ of the
    /// twist are at 0, ¼, ½ and ¾; a sliding helper is a ladder of one rung, at 0).
    ladder: Vec<(u16, f64)>,
    /// The bone at rest, from the joint to its child.
    bone: (DVec3, DVec3),
    /// Where along the bone the ladder runs (see [`TWIST_SPAN`]).
    span: (f64, f64),
    /// Where the joint's weight gives way to its parent's below the parent (see
    /// [`HEAD_FLOOR`]): the parent, its place at rest, and the span as fractions of the
    /// way from the joint down to the parent.
    floor: Option<(u16, DVec3, (f64, f64))>,
}

/// Where along its bone (0 at the joint, 1 at the child) a vertex starts to take the
/// joint's twist, and where it takes all of it: below the armpit, and before the elbow's
/// band (which blends the whole twist with the forearm). Starting at 0.1-0.2 or ending at
/// 0.7 turned more triangles over at the 1.40 m adult's worst posture (95-96 against 85).
/// Likewise where the limb's skin goes from a sliding helper back to its joint.
pub(crate) const TWIST_SPAN: (f64, f64) = (0.3, 0.8);
/// [`TWIST_SPAN`] for the head's sliding helper, along the skullbase's bone to the top of
/// the head: the neck is the helper's and the head its joint's, handed over from 10 %
/// of the way below the skullbase to 5 % above it (the jaw's underside), so that the face
/// stays rigid as the head nods: at a 40° nod the 1.75 m adult's face moves by 0.1 mm
/// against the skull, as without the helper. Handed over from 0 to 20 % (across the
/// mouth), as many triangles turned over (147) but the mouth moved by 6.6 mm; lower, in
/// the neck (from 30 % below to 10 % below, or 50 % to 20 %), the band folded: 105
/// triangles over the 1.40 m adult's 50 postures alone, 13 at its worst posture.
pub(crate) const HEAD_SPAN: (f64, f64) = (-0.1, 0.05);
/// How far down the neck the head's weight (the skullbase's, before its helper takes
/// it) reaches, as fractions of the way from the skullbase down to vc4: all of it above
/// 0.9 of the way, none below 1.6 (below vc4, a little past halfway to vt1), vc4 taking
/// it in between. A child's neck is short, and smoothed over the surface the head's
/// weight reached the root of the neck (13-25 % of the skin beside it, where vt1, vc4
/// and a clavicle share it): a head turned 48° and tilted 30° swung that skin by its
/// distance from the skullbase against its neighbours, with the neck bent and a
/// clavicle raised. In the skin test (six sizes' 50 full-range postures, with
/// [`WIDER`](super::weights::WIDER), [`NECK`] and [`PALM`]) it took the inverted
/// triangles at the root of the neck (vt1) from 11 to none and all of them from 29 to
/// 19; 0.9 to 1.5 gave 19, 0.9 to 1.4 20, 0.85 or 1.0 to 1.5 21, 1.1 to 1.5 27,
/// 0.75 to 1.5 28 (the band in the neck folding), 1.0 to 2.0 25. Measured in the head's
/// height instead, as [`HEAD_SPAN`] is (from 60 % to 30 % of it below the skullbase),
/// 23: the children's vc4 lies higher in those terms (28 % below, the adults' 39 %).
pub(crate) const HEAD_FLOOR: (f64, f64) = (0.9, 1.6);

impl Chains {
    /// The chains of `helpers`, whose slots start at `first_slot` (the number of joints),
    /// each with `ends` joints at its parent's end: the helped joint's parent and its next
    /// ancestors (`parent_of` gives a joint's parent); `bone` gives a helped joint's bone
    /// at rest, from the joint to its child, and `span` where along it the ladder runs
    /// ([`TWIST_SPAN`], [`HEAD_SPAN`]), and `floor` how far below the joint its weight
    /// reaches ([`HEAD_FLOOR`]; `None`: as smoothed). At the shoulder the armpit is shared between
    /// the arm and the chest (vt1, vt6), which are the clavicle's ancestors: counted at
    /// the chain's parent end, their share of an armpit vertex blends with the arm's
    /// through helpers a quarter of the bend apart, instead of a straight blend of the
    /// chest and an arm turned by up to 180°. A joint with a ladder but no helpers across
    /// it (a sliding helper's) has no parent's end: the band across it keeps its weights.
    pub(crate) fn new(
        helpers: &[Helper],
        first_slot: usize,
        ends: usize,
        parent_of: impl Fn(usize) -> Option<usize>,
        bone: impl Fn(usize) -> (DVec3, DVec3),
        span: impl Fn(usize) -> (f64, f64),
        floor: impl Fn(usize) -> Option<(f64, f64)>,
    ) -> Chains {
        // A helper between two joints belongs to their web, not to a chain.
        let mut chains: Vec<Chain> = Vec::new();
        let mut webs = Vec::new();
        for (i, h) in helpers.iter().enumerate() {
            let slot = (first_slot + i) as u16;
            if let Some(pair) = &h.pair {
                let (first, second) = (h.joint as u16, pair.joint as u16);
                let at = webs
                    .iter()
                    .position(|w: &Web| w.first == first && w.second == second)
                    .unwrap_or_else(|| {
                        webs.push(Web {
                            first,
                            second,
                            links: Vec::new(),
                        });
                        webs.len() - 1
                    });
                webs[at].links.push((slot, pair.share));
                continue;
            }
            let c = match chains.iter().position(|c| c.joint as usize == h.joint) {
                Some(c) => &mut chains[c],
                None => {
                    let parents = std::iter::successors(Some(h.parent), |&j| parent_of(j))
                        .take(ends)
                        .map(|j| j as u16)
                        .collect();
                    chains.push(Chain {
                        parents,
                        joint: h.joint as u16,
                        links: Vec::new(),
                        ladder: Vec::new(),
                        bone: bone(h.joint),
                        span: span(h.joint),
                        floor: floor(h.joint).map(|f| (h.parent as u16, bone(h.parent).0, f)),
                    });
                    chains.last_mut().expect("just pushed")
                }
            };
            if h.swing < 1.0 {
                c.links.push((slot, h.swing));
            } else {
                c.ladder.push((slot, h.twist));
            }
        }
        for w in &mut webs {
            w.links.sort_by(|a, b| a.1.total_cmp(&b.1));
        }
        for c in &mut chains {
            c.links.sort_by(|a, b| a.1.total_cmp(&b.1));
            c.ladder.sort_by(|a, b| a.1.total_cmp(&b.1));
            let rungs = c.ladder.len() as f64;
            for (k, rung) in c.ladder.iter_mut().enumerate() {
                rung.1 = k as f64 / rungs;
            }
            if c.links.is_empty() {
                c.parents.clear();
            }
        }
        Chains(chains, webs, None)
    }

    /// These chains with the lower belly leaning on the pelvis (see [`Lean`]).
    pub(crate) fn leaning(self, lean: Lean) -> Chains {
        Chains(self.0, self.1, Some(lean))
    }

    /// `row`, the weights of a vertex at rest position `p`, with the weights of each
    /// helped joint and its parent's end moved onto their chain. A joint in several
    /// chains (vt1 at the parent's end of both shoulders') splits its weight among them in
    /// proportion to its partner's weight in each, so the routing is continuous over the
    /// surface: where a partner's weight fades to nothing its chain's share does too.
    fn route(&self, row: &Row, p: DVec3) -> Row {
        // Below its floor a joint's weight is its parent's.
        let mut floored: Row = row.clone();
        for c in &self.0 {
            let Some((parent, parent_at, (from, to))) = c.floor else {
                continue;
            };
            let Some(at) = floored.iter().position(|&(j, _)| j == c.joint) else {
                continue;
            };
            let down = (c.bone.1 - c.bone.0).normalize();
            let way = (p - c.bone.0).dot(down) / (parent_at - c.bone.0).dot(down);
            let keep = ((to - way) / (to - from)).clamp(0.0, 1.0);
            if keep < 1.0 {
                let w = floored[at].1;
                floored[at].1 = w * keep;
                add(&mut floored, parent, w * (1.0 - keep));
                floored.retain(|&(_, w)| w > 0.0);
            }
        }
        let row = &floored;
        let weight = |j: u16| weight_of(row, j);
        let end_weight = |c: &Chain| c.parents.iter().map(|&p| weight(p)).sum::<f64>();
        let mut partners: Row = Vec::new();
        for c in &self.0 {
            for &p in &c.parents {
                add(&mut partners, p, weight(c.joint));
            }
            add(&mut partners, c.joint, end_weight(c));
        }
        let partner_total = |j: u16| weight_of(&partners, j);
        // Joints in no chain with a partner keep their weight.
        let mut out = unpartnered(row, &partners);
        for c in &self.0 {
            let (we, wj) = (end_weight(c), weight(c.joint));
            if we <= 0.0 || wj <= 0.0 {
                continue;
            }
            // What each joint of the parent's end brings to this chain.
            let from_parents: Row = c
                .parents
                .iter()
                .map(|&p| (p, weight(p) * wj / partner_total(p)))
                .filter(|&(_, w)| w > 0.0)
                .collect();
            let from_parent: f64 = from_parents.iter().map(|(_, w)| w).sum();
            let from_joint = wj * we / partner_total(c.joint);
            let total = from_parent + from_joint;
            // The joint's share of the pair, placed on the chain's fractions.
            let share = from_joint / total;
            let stops: Vec<(Option<u16>, f64)> = std::iter::once((None, 0.0))
                .chain(c.links.iter().map(|&(slot, f)| (Some(slot), f)))
                .chain(std::iter::once((Some(c.joint), 1.0)))
                .collect();
            let (lo, hi, t) = bracket(&stops, share);
            for (slot, w) in [(lo, total * (1.0 - t)), (hi, total * t)] {
                match slot {
                    Some(slot) => add(&mut out, slot, w),
                    // The chain's start: the parent's end, each joint by what it brought.
                    None => {
                        for &(p, from) in &from_parents {
                            add(&mut out, p, w * from / from_parent);
                        }
                    }
                }
            }
        }
        // The joint's own weight, down the limb: onto the two rungs of the twist ladder
        // that bracket how far along the bone the vertex lies.
        for c in &self.0 {
            if c.ladder.is_empty() {
                continue;
            }
            let Some(at) = out.iter().position(|&(j, _)| j == c.joint) else {
                continue;
            };
            let (_, w) = out.swap_remove(at);
            let (a, b) = c.bone;
            let along = (p - a).dot(b - a) / (b - a).length_squared();
            let (from, to) = c.span;
            let twist = ((along - from) / (to - from)).clamp(0.0, 1.0);
            let stops: Vec<(u16, f64)> = c
                .ladder
                .iter()
                .copied()
                .chain(std::iter::once((c.joint, 1.0)))
                .collect();
            let (lo, hi, t) = bracket(&stops, twist);
            add(&mut out, lo, w * (1.0 - t));
            add(&mut out, hi, w * t);
        }
        // Between two joints (two knuckles): their weights onto the two stops of first,
        // helpers and second that bracket the second's share of the pair, so that the web
        // beside a bent finger turns as a blend of two rotations half the difference
        // apart. A joint in two pairs (the middle finger's knuckle, between the index's
        // and the ring's) splits its weight between them in proportion to its partner's
        // weight in each, as vt1 does between the shoulders' chains, so the routing stays
        // continuous where a partner's weight fades out.
        let w = |j: u16| weight_of(&out, j);
        let mut partners: Row = Vec::new();
        for web in &self.1 {
            let (wa, wb) = (w(web.first), w(web.second));
            if wa > 0.0 && wb > 0.0 {
                add(&mut partners, web.first, wb);
                add(&mut partners, web.second, wa);
            }
        }
        let partner_total = |j: u16| weight_of(&partners, j);
        let mut paired = unpartnered(&out, &partners);
        for web in &self.1 {
            let (wa, wb) = (w(web.first), w(web.second));
            if wa <= 0.0 || wb <= 0.0 {
                continue;
            }
            let a = wa * wb / partner_total(web.first);
            let b = wb * wa / partner_total(web.second);
            let total = a + b;
            let stops: Vec<(u16, f64)> = std::iter::once((web.first, 0.0))
                .chain(web.links.iter().copied())
                .chain(std::iter::once((web.second, 1.0)))
                .collect();
            let (lo, hi, t) = bracket(&stops, b / total);
            add(&mut paired, lo, total * (1.0 - t));
            add(&mut paired, hi, total * t);
        }
        let mut out = paired;
        // The lower belly beside a flexed hip: a hip's helper's share of vl5's weight
        // onto the pelvis.
        if let Some(lean) = &self.2 {
            let by = lean
                .by
                .iter()
                .map(|&h| weight_of(&out, h))
                .fold(0.0, f64::max);
            let w = weight_of(&out, lean.from);
            if by > 0.0 && w > 0.0 {
                let moved = w * by.min(1.0);
                for e in out.iter_mut().filter(|e| e.0 == lean.from) {
                    e.1 -= moved;
                }
                add(&mut out, lean.to, moved);
            }
        }
        out.retain(|&(_, w)| w > 0.0);
        out
    }
}

/// The two neighbouring stops of `stops` (at least two, ascending by position) that
/// bracket position `x`, and how far `x` lies from the first to the second, in [0, 1].
fn bracket<T: Copy>(stops: &[(T, f64)], x: f64) -> (T, T, f64) {
    let k = stops
        .windows(2)
        .position(|s| x <= s[1].1)
        .unwrap_or(stops.len() - 2);
    let ((lo, at_lo), (hi, at_hi)) = (stops[k], stops[k + 1]);
    (lo, hi, ((x - at_lo) / (at_hi - at_lo)).clamp(0.0, 1.0))
}

/// Joint `j`'s weight in `row` (0 if it has none).
fn weight_of(row: &Row, j: u16) -> f64 {
    row.iter().find(|(i, _)| *i == j).map_or(0.0, |(_, w)| *w)
}

/// The joints of `row` with no weight among `partners`, with their weights.
fn unpartnered(row: &Row, partners: &Row) -> Row {
    row.iter()
        .filter(|&&(j, _)| weight_of(partners, j) <= 0.0)
        .copied()
        .collect()
}

/// Adds `w` to joint `j`'s weight in `row`.
fn add(row: &mut Row, j: u16, w: f64) {
    match row.iter_mut().find(|(i, _)| *i == j) {
        Some((_, sum)) => *sum += w,
        None => row.push((j, w)),
    }
}

/// How far a vertex's weights are averaged over the surface.
#[derive(Clone, Copy, Debug)]
struct Smoothing {
    /// Metres around the vertex.
    length: f64,
    /// At most this many mean edge lengths around it.
    most_edges: f64,
}

/// Smooths the weight rows over the surface: each round moves a vertex's row towards
/// the mean of its neighbours' rows by a step chosen so that, after all the rounds, the
/// weights are averaged over about `smoothing[v]` around vertex `v` (the spread of
/// repeated averaging grows as the square root of the rounds times the step, in edge
/// lengths). Rows stay convex combinations of the rows before, so they keep summing to
/// one.
///
/// A step cannot go past the neighbours' mean, so [`SMOOTHING_ROUNDS`] reach at most
/// √150 edges. The vertices that ask for more (the widest of the groin's bands,
/// [`WIDER`]) go on alone for as many more rounds at a whole step as they lack, the
/// others holding the weights they have after [`SMOOTHING_ROUNDS`]: their weights are
/// the same as if no vertex asked for more, and the wide bands reach as far as asked.
fn diffuse(rows: &mut [Row], positions: &[DVec3], indices: &[u32], smoothing: &[Smoothing]) {
    let n = positions.len();
    let mut around: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            around[a as usize].push(b);
        }
    }
    // How many rounds' worth of whole steps each vertex asks for: the square of its
    // smoothing in edge lengths.
    let asked: Vec<f64> = (0..n)
        .map(|v| {
            let edges = &around[v];
            let mean_edge = edges
                .iter()
                .map(|&u| (positions[u as usize] - positions[v]).length())
                .sum::<f64>()
                / edges.len().max(1) as f64;
            let Smoothing { length, most_edges } = smoothing[v];
            let edges = (length / mean_edge.max(1e-9)).min(most_edges);
            edges * edges
        })
        .collect();
    let rounds = SMOOTHING_ROUNDS as f64;
    let step: Vec<f64> = asked.iter().map(|&a| (a / rounds).min(1.0)).collect();
    let mut next: Vec<Row> = rows.to_vec();
    for _ in 0..SMOOTHING_ROUNDS {
        for (v, out) in next.iter_mut().enumerate() {
            average(rows, &around[v], v, step[v], out);
        }
        rows.clone_from_slice(&next);
    }
    // The vertices that asked for more, each going on until it has had what it asked.
    let wide: Vec<usize> = (0..n).filter(|&v| asked[v] > rounds).collect();
    let most = wide.iter().map(|&v| asked[v]).fold(rounds, f64::max);
    for round in SMOOTHING_ROUNDS..most.ceil() as usize {
        for &v in &wide {
            let step = (asked[v] - round as f64).clamp(0.0, 1.0);
            let mut out = std::mem::take(&mut next[v]);
            average(rows, &around[v], v, step, &mut out);
            next[v] = out;
        }
        for &v in &wide {
            rows[v].clone_from(&next[v]);
        }
    }
}

/// Into `out`, vertex `v`'s row of `rows` moved by `step` (0 to 1) towards the mean of
/// its neighbours' (`around`).
fn average(rows: &[Row], around: &[u32], v: usize, step: f64, out: &mut Row) {
    if around.is_empty() {
        return;
    }
    let k = step / around.len() as f64;
    out.clear();
    out.extend(rows[v].iter().map(|&(j, w)| (j, w * (1.0 - step))));
    for &u in around {
        for &(j, w) in &rows[u as usize] {
            match out.iter_mut().find(|(i, _)| *i == j) {
                Some((_, sum)) => *sum += w * k,
                None => out.push((j, w * k)),
            }
        }
    }
    // Far from its joint a weight thins out to nothing: dropping it when it is
    // negligible keeps the rows short (they would gather every joint within
    // sixty rings) and changes no weight by more than a ten-thousandth.
    out.retain(|&(_, w)| w >= NEGLIGIBLE);
}

/// The near weights of a vertex at rest position `p`, (joint, weight) pairs not
/// normalised, the reach of its nearest volume and that volume's joint.
fn near_weights(
    p: DVec3,
    volumes: &[Volume],
    neighbours: &impl Fn(usize, usize) -> bool,
) -> (Vec<(usize, f64)>, f64, usize) {
    let distances: Vec<f64> = volumes
        .iter()
        .map(|v| match v.join {
            // A carved volume moves nothing; the skin it leaves follows the head.
            Join::Carve => f64::INFINITY,
            // Unsigned: a vertex on an eyeball lies inside the head's ellipsoid, and
            // belongs to the eyeball, whose surface it is on.
            _ => v.form.distance(p).abs(),
        })
        .collect();
    let owner = (0..volumes.len())
        .min_by(|&a, &b| distances[a].total_cmp(&distances[b]))
        .expect("a body has volumes");
    let home = volumes[owner].joint;
    let nearest = distances[owner];
    // Each joint's weight is the largest of its volumes' weights.
    let mut per_joint: Vec<(usize, f64)> = Vec::new();
    for (v, &d) in volumes.iter().zip(&distances) {
        if !d.is_finite() || !neighbours(home, v.joint) {
            continue;
        }
        // A smooth step of the distance beyond the nearest volume's: it depends on the
        // vertex's position only (not on which volume owns it), so neighbouring vertices
        // get neighbouring weights and the skin does not crease where ownership changes.
        let x = ((d - nearest) / v.reach).clamp(0.0, 1.0);
        let w = (1.0 - x) * (1.0 - x) * (1.0 + 2.0 * x);
        if w <= 0.0 {
            continue;
        }
        match per_joint.iter_mut().find(|(j, _)| *j == v.joint) {
            Some((_, old)) => *old = old.max(w),
            None => per_joint.push((v.joint, w)),
        }
    }
    (per_joint, volumes[owner].reach, home)
}

/// The four heaviest joints of a row, each less the fifth heaviest's weight or
/// [`TRACE`], whichever is more (so the weights stay continuous where the fifth and the
/// fourth trade places, or a trace fades out), normalised.
fn four_heaviest(row: &Row) -> Influences {
    let mut order = row.clone();
    // Heaviest first; ties by joint index so the order never depends on anything else.
    order.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let floor = order.get(4).map_or(0.0, |&(_, w)| w).max(TRACE);
    let kept: Vec<(u16, f64)> = order
        .iter()
        .take(4)
        .map(|&(j, w)| (j, w - floor))
        .filter(|&(_, w)| w > 0.0)
        .collect();
    // Five or more joints of one weight (a tie of measure zero): keep the first.
    let kept = if kept.is_empty() {
        vec![(order[0].0, 1.0)]
    } else {
        kept
    };
    let total: f64 = kept.iter().map(|(_, w)| w).sum();
    let mut joints = [0u16; 4];
    let mut weights = [0.0f32; 4];
    for (slot, (j, w)) in kept.iter().enumerate() {
        joints[slot] = *j;
        weights[slot] = (*w / total) as f32;
    }
    // Rounding to f32 can leave the sum a hair off one: give the rest to the heaviest.
    let sum: f32 = weights[1..].iter().sum();
    weights[0] = 1.0 - sum;
    (joints, weights)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn four_heaviest_is_continuous_where_the_fourth_and_fifth_trade_places() {
        let row = |fifth: f64| -> Row {
            vec![
                (1, 0.3),
                (2, 0.25),
                (3, 0.2),
                (4, 0.125 + fifth),
                (5, 0.125 - fifth),
            ]
        };
        let (a, b) = (four_heaviest(&row(1e-6)), four_heaviest(&row(-1e-6)));
        let weight = |(joints, weights): Influences, j: u16| {
            joints
                .iter()
                .zip(weights)
                .find(|(&i, _)| i == j)
                .map_or(0.0, |(_, w)| w)
        };
        for j in 1..=5 {
            assert!(
                (weight(a, j) - weight(b, j)).abs() < 1e-4,
                "joint {j}: {a:?} / {b:?}"
            );
        }
        assert!(weight(a, 4) < 1e-4 && weight(b, 5) < 1e-4);
    }

    #[test]
    fn four_heaviest_drops_traces_and_sums_to_one() {
        let (joints, weights) = four_heaviest(&vec![(7, 0.6), (8, 0.37), (9, 0.03)]);
        assert_eq!(joints, [7, 8, 0, 0]);
        assert_eq!(weights[2..], [0.0, 0.0]);
        assert!((weights.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        // The trace floor is subtracted from every weight kept.
        assert!((weights[0] - 0.55 / 0.87).abs() < 1e-6, "{weights:?}");
    }

    /// Chains across joint 2 (parent 1) and joint 3 (parent 1), helpers at a quarter,
    /// half and three quarters in slots 10-12 and 13-15.
    fn chains() -> Chains {
        let helpers: Vec<Helper> = [2, 3]
            .into_iter()
            .flat_map(|joint| [0.25, 0.5, 0.75].map(|swing| across(joint, swing)))
            .collect();
        Chains::new(
            &helpers,
            10,
            1,
            |_| None,
            |_| (DVec3::ZERO, DVec3::NEG_Y),
            |_| TWIST_SPAN,
            |_| None,
        )
    }

    /// A helper across joint `joint` (parent 1) taking `swing` of its swing.
    fn across(joint: usize, swing: f64) -> Helper {
        Helper {
            name: format!("{joint}_{swing}"),
            joint,
            parent: 1,
            swing,
            twist: 0.0,
            axis: DVec3::NEG_Y,
            bind: DQuat::IDENTITY,
            pivot: 0.0,
            deep: 1.0,
            pair: None,
        }
    }

    /// A sliding helper of joint `joint` (parent 1): its whole turn, twist too, about a
    /// pivot 0.05 m from the joint's centre towards the bend.
    fn sliding(joint: usize) -> Helper {
        Helper {
            twist: 1.0,
            pivot: 0.05,
            ..across(joint, 1.0)
        }
    }

    /// Webs between joints 2 and 3 and between 3 and 4 (three knuckles side by side, the
    /// palm joint 1), a helper halfway across each in slots 10 and 11.
    fn webs() -> Chains {
        let web = |first: usize, second: usize| Helper {
            pair: Some(crate::skin::helpers::Pair {
                joint: second,
                bind: DQuat::IDENTITY,
                share: 0.5,
            }),
            ..across(first, 1.0)
        };
        Chains::new(
            &[web(2, 3), web(3, 4)],
            10,
            1,
            |_| None,
            |_| (DVec3::ZERO, DVec3::NEG_Y),
            |_| TWIST_SPAN,
            |_| None,
        )
    }

    #[test]
    fn two_knuckles_share_the_web_through_the_helper_between_them() {
        let webs = webs();
        // The second knuckle's share of the pair, 0.4, lies between the first (0) and
        // the helper (0.5); the palm keeps its weight.
        let row = webs.route(&vec![(1, 0.5), (2, 0.3), (3, 0.2)], DVec3::ZERO);
        assert!((weight_of(&row, 2) - 0.1).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 10) - 0.4).abs() < 1e-12, "{row:?}");
        assert_eq!(weight_of(&row, 3), 0.0);
        assert_eq!(weight_of(&row, 1), 0.5);
        // A knuckle alone, or beside the palm only, keeps its weight.
        assert_eq!(
            webs.route(&vec![(1, 0.4), (2, 0.6)], DVec3::ZERO),
            vec![(1, 0.4), (2, 0.6)]
        );
        // The middle knuckle between two: split by its neighbours' weights, half to each
        // web, and each web's pair halfway: all on the helpers.
        let row = webs.route(&vec![(1, 0.2), (2, 0.2), (3, 0.4), (4, 0.2)], DVec3::ZERO);
        let total: f64 = row.iter().map(|(_, w)| w).sum();
        assert!((total - 1.0).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 10) - 0.4).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 11) - 0.4).abs() < 1e-12, "{row:?}");
        // Continuous where a neighbour's weight fades out, or the pair's split crosses
        // the helper.
        for (a, b) in [
            (
                vec![(1, 0.2), (2, 0.3), (3, 0.5), (4, 1e-9)],
                vec![(1, 0.2 + 1e-9), (2, 0.3), (3, 0.5)],
            ),
            (
                vec![(1, 0.2), (2, 0.4 + 1e-9), (3, 0.4 - 1e-9)],
                vec![(1, 0.2), (2, 0.4 - 1e-9), (3, 0.4 + 1e-9)],
            ),
        ] {
            let (a, b) = (webs.route(&a, DVec3::ZERO), webs.route(&b, DVec3::ZERO));
            for slot in [1, 2, 3, 4, 10, 11] {
                assert!(
                    (weight_of(&a, slot) - weight_of(&b, slot)).abs() < 1e-6,
                    "{a:?} / {b:?}"
                );
            }
        }
    }

    #[test]
    fn a_joints_share_goes_to_the_two_helpers_that_bracket_it() {
        let chains = chains();
        // The joint's share 0.4 lies between the helpers at 0.25 and 0.5.
        let row = chains.route(&vec![(1, 0.6), (2, 0.4), (7, 0.0)], DVec3::ZERO);
        assert!((weight_of(&row, 10) - 0.4).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 11) - 0.6).abs() < 1e-12, "{row:?}");
        assert_eq!(weight_of(&row, 1) + weight_of(&row, 2), 0.0);
        // A parent alone, or a joint alone, keeps its weight.
        assert_eq!(chains.route(&vec![(1, 1.0)], DVec3::ZERO), vec![(1, 1.0)]);
        assert_eq!(
            chains.route(&vec![(2, 0.7), (5, 0.3)], DVec3::ZERO),
            vec![(2, 0.7), (5, 0.3)]
        );
        // Continuous where the share crosses a helper's fraction.
        let (below, above) = (
            chains.route(&vec![(1, 0.5 + 1e-9), (2, 0.5 - 1e-9)], DVec3::ZERO),
            chains.route(&vec![(1, 0.5 - 1e-9), (2, 0.5 + 1e-9)], DVec3::ZERO),
        );
        for slot in [1, 2, 10, 11, 12] {
            assert!((weight_of(&below, slot) - weight_of(&above, slot)).abs() < 1e-6);
        }
    }

    #[test]
    fn a_parent_of_two_helped_joints_splits_its_weight_between_their_chains() {
        // The pelvis between two hips: half of its weight goes with each.
        let row = chains().route(&vec![(1, 0.5), (2, 0.25), (3, 0.25)], DVec3::ZERO);
        let total: f64 = row.iter().map(|(_, w)| w).sum();
        assert!((total - 1.0).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 11) - 0.5).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 14) - 0.5).abs() < 1e-12, "{row:?}");
    }

    #[test]
    fn beside_a_hips_helper_its_share_of_the_lower_spines_weight_goes_to_the_pelvis() {
        // Joint 5 the lower spine, 4 the pelvis, 6 and 7 the hips' helpers (in no chain).
        let chains = chains().leaning(Lean {
            from: 5,
            to: 4,
            by: vec![6, 7],
        });
        let row = chains.route(&vec![(5, 0.5), (4, 0.3), (6, 0.2)], DVec3::ZERO);
        let expect = [(5, 0.4), (4, 0.4), (6, 0.2)];
        for (j, w) in expect {
            assert!((weight_of(&row, j) - w).abs() < 1e-12, "{row:?}");
        }
        // The larger of the two helpers' weights counts.
        let row = chains.route(&vec![(5, 0.5), (4, 0.2), (6, 0.2), (7, 0.1)], DVec3::ZERO);
        assert!((weight_of(&row, 5) - 0.4).abs() < 1e-12, "{row:?}");
        // Continuous: as the helpers' weight fades out, nothing moves.
        let row = chains.route(&vec![(5, 0.5), (4, 0.5 - 1e-9), (6, 1e-9)], DVec3::ZERO);
        assert!((weight_of(&row, 5) - 0.5).abs() < 1e-8, "{row:?}");
        let row = chains.route(&vec![(5, 0.5), (4, 0.5)], DVec3::ZERO);
        assert_eq!(row, vec![(5, 0.5), (4, 0.5)]);
    }

    #[test]
    fn a_chain_with_two_joints_at_its_parent_end_shares_their_weight() {
        // Joint 2's parent is 1, whose parent is 0: both count at the chain's start.
        let helpers: Vec<Helper> = [0.25, 0.5, 0.75].map(|swing| across(2, swing)).to_vec();
        let chains = Chains::new(
            &helpers,
            10,
            2,
            |j| j.checked_sub(1),
            |_| (DVec3::ZERO, DVec3::NEG_Y),
            |_| TWIST_SPAN,
            |_| None,
        );
        // The parent's end holds 0.9 (0.3 from joint 1, 0.6 from joint 0): the joint's
        // share 0.1 lies between the start (the end's two joints) and the first helper.
        let row = chains.route(&vec![(0, 0.6), (1, 0.3), (2, 0.1)], DVec3::ZERO);
        let total: f64 = row.iter().map(|(_, w)| w).sum();
        assert!((total - 1.0).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 10) - 0.4).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 0) - 0.4).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 1) - 0.2).abs() < 1e-12, "{row:?}");
        assert_eq!(weight_of(&row, 2), 0.0);
        // Without the joint, the end's joints keep their weights.
        assert_eq!(
            chains.route(&vec![(0, 0.6), (1, 0.4)], DVec3::ZERO),
            vec![(0, 0.6), (1, 0.4)]
        );
    }

    #[test]
    fn down_the_limb_the_joints_weight_goes_to_the_twist_helpers_by_where_the_vertex_lies() {
        // Joint 2 (parent 1): helpers across it in slots 10-12, along it (the whole swing,
        // none, a quarter, half and three quarters of the twist) in 13-16; its bone runs
        // 1 m down from the origin.
        let mut helpers: Vec<Helper> = [0.25, 0.5, 0.75].map(|swing| across(2, swing)).to_vec();
        helpers.extend([0.0, 0.25, 0.5, 0.75].map(|twist| Helper {
            swing: 1.0,
            twist,
            ..across(2, 1.0)
        }));
        let chains = Chains::new(
            &helpers,
            10,
            1,
            |_| None,
            |_| (DVec3::ZERO, DVec3::NEG_Y),
            |_| TWIST_SPAN,
            |_| None,
        );
        let at = |along: f64| chains.route(&vec![(2, 1.0)], DVec3::new(0.02, -along, 0.0));
        let (from, to) = TWIST_SPAN;
        // Near the joint: the whole swing, no twist; near the child: the joint itself.
        assert_eq!(at(0.5 * from), vec![(13, 1.0)]);
        assert_eq!(at(to + 0.1), vec![(2, 1.0)]);
        // Three eighths of the twist: halfway between the quarter and the half.
        let row = at(from + 0.375 * (to - from));
        assert!((weight_of(&row, 14) - 0.5).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 15) - 0.5).abs() < 1e-12, "{row:?}");
        // Continuous along the bone, and summing to one.
        for k in 0..100 {
            let (a, b) = (at(k as f64 * 0.01), at(k as f64 * 0.01 + 1e-9));
            for slot in [2, 13, 14, 15, 16] {
                assert!((weight_of(&a, slot) - weight_of(&b, slot)).abs() < 1e-6);
            }
            assert!((a.iter().map(|(_, w)| w).sum::<f64>() - 1.0).abs() < 1e-12);
        }
        // Across the joint first: the armpit's share past the last helper across it goes
        // on down the ladder's first rung (near the joint, no twist).
        let row = chains.route(&vec![(1, 0.2), (2, 0.8)], DVec3::ZERO);
        assert!((weight_of(&row, 12) - 0.8).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 13) - 0.2).abs() < 1e-12, "{row:?}");
        assert_eq!(weight_of(&row, 2), 0.0);
    }

    #[test]
    fn a_sliding_helper_takes_its_joints_weight_near_the_joint_and_no_parents() {
        // Joint 2 (parent 1) with one sliding helper (slot 10); its bone runs 1 m down.
        let slide = sliding(2);
        let chains = Chains::new(
            &[slide],
            10,
            2,
            |j| j.checked_sub(1),
            |_| (DVec3::ZERO, DVec3::NEG_Y),
            |_| TWIST_SPAN,
            |_| None,
        );
        let at =
            |along: f64| chains.route(&vec![(1, 0.4), (2, 0.6)], DVec3::new(0.02, -along, 0.0));
        let (from, to) = TWIST_SPAN;
        // The band across the joint keeps its parent's weight; the joint's goes to the
        // helper near the joint, back to the joint down the limb, half and half midway.
        assert_eq!(at(0.5 * from), vec![(1, 0.4), (10, 0.6)]);
        assert_eq!(at(to + 0.1), vec![(1, 0.4), (2, 0.6)]);
        let row = at(0.5 * (from + to));
        assert!((weight_of(&row, 10) - 0.3).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 2) - 0.3).abs() < 1e-12, "{row:?}");
    }

    #[test]
    fn below_its_floor_a_joints_weight_goes_to_its_parent() {
        // Joint 2 (parent 1, 1 m below it) with one sliding helper (slot 10); its bone
        // runs 1 m up; its weight gives way to the parent's from 0.5 to 1.5 of the way
        // down to the parent, which is at rest 1 m down.
        let slide = sliding(2);
        let chains = Chains::new(
            &[slide],
            10,
            1,
            |_| None,
            |j| {
                if j == 2 {
                    (DVec3::ZERO, DVec3::Y)
                } else {
                    (DVec3::NEG_Y, DVec3::ZERO)
                }
            },
            |_| TWIST_SPAN,
            |j| (j == 2).then_some((0.5, 1.5)),
        );
        let at = |down: f64| chains.route(&vec![(1, 0.4), (2, 0.6)], DVec3::new(0.02, -down, 0.0));
        // Above the floor the joint's weight goes to its helper; below, to the parent.
        assert_eq!(at(0.4), vec![(1, 0.4), (10, 0.6)]);
        assert_eq!(at(1.6), vec![(1, 1.0)]);
        let row = at(1.0);
        assert!((weight_of(&row, 1) - 0.7).abs() < 1e-12, "{row:?}");
        assert!((weight_of(&row, 10) - 0.3).abs() < 1e-12, "{row:?}");
        // Continuous, and summing to one.
        for k in 0..200 {
            let (a, b) = (at(k as f64 * 0.01), at(k as f64 * 0.01 + 1e-9));
            for slot in [1, 2, 10] {
                assert!((weight_of(&a, slot) - weight_of(&b, slot)).abs() < 1e-6);
            }
            assert!((a.iter().map(|(_, w)| w).sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }

    /// A strip of `n` squares along x, 1 cm wide, as triangles.
    fn strip(n: usize) -> (Vec<DVec3>, Vec<u32>) {
        let positions = (0..=n)
            .flat_map(|i| [0.0, 0.01].map(|y| DVec3::new(i as f64 * 0.01, y, 0.0)))
            .collect();
        let indices = (0..n as u32)
            .flat_map(|i| {
                let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
                [a, b, c, a, c, d]
            })
            .collect();
        (positions, indices)
    }

    #[test]
    fn vertices_asking_for_more_than_the_rounds_reach_get_it_alone() {
        // A step at x = 0.3 m on a strip of 1 cm edges; the vertices right of it ask for
        // a smoothing of `right`, those left of it for 5 cm.
        let (positions, indices) = strip(60);
        let smooth = |right: f64| -> Vec<Row> {
            let mut rows: Vec<Row> = positions
                .iter()
                .map(|p| vec![(if p.x < 0.3 { 1 } else { 2 }, 1.0)])
                .collect();
            let smoothing: Vec<Smoothing> = positions
                .iter()
                .map(|p| Smoothing {
                    length: if p.x < 0.3 { 0.05 } else { right },
                    most_edges: f64::INFINITY,
                })
                .collect();
            diffuse(&mut rows, &positions, &indices, &smoothing);
            rows
        };
        // Both further than the rounds reach (the mean edge, diagonals included, is
        // longer than 1 cm), the second twice as far as the first.
        let reach = 0.015 * (SMOOTHING_ROUNDS as f64).sqrt();
        let (capped, wider) = (smooth(reach), smooth(2.0 * reach));
        let weight_of_1 = |row: &Row| row.iter().find(|(j, _)| *j == 1).map_or(0.0, |r| r.1);
        for (v, p) in positions.iter().enumerate() {
            if p.x < 0.3 {
                // The others' weights are the same however far the wide side reaches.
                assert_eq!(capped[v], wider[v], "at {p}");
            } else if (0.35..0.5).contains(&p.x) {
                // The wide side's ramp reaches further.
                assert!(
                    weight_of_1(&wider[v]) > weight_of_1(&capped[v]) + 1e-3,
                    "at {p}"
                );
            }
            let sum: f64 = wider[v].iter().map(|(_, w)| w).sum();
            assert!((sum - 1.0).abs() < 5e-3, "{:?}", wider[v]);
        }
    }

    #[test]
    fn diffusion_turns_a_step_into_a_ramp_as_wide_as_asked() {
        let (positions, indices) = strip(60);
        let step = |v: usize| -> Row {
            if positions[v].x < 0.3 {
                vec![(1, 1.0)]
            } else {
                vec![(2, 1.0)]
            }
        };
        let weight_of_2 = |rows: &[Row], v: usize| {
            rows[v]
                .iter()
                .find(|(j, _)| *j == 2)
                .map_or(0.0, |(_, w)| *w)
        };
        for smoothing in [0.02, 0.06] {
            let mut rows: Vec<Row> = (0..positions.len()).map(step).collect();
            let spread = Smoothing {
                length: smoothing,
                most_edges: f64::INFINITY,
            };
            diffuse(
                &mut rows,
                &positions,
                &indices,
                &vec![spread; positions.len()],
            );
            // Each round drops weights under NEGLIGIBLE, so a row far out on the ramp's
            // tail loses a few thousandths over the rounds (normalised afterwards).
            for row in &rows {
                let sum: f64 = row.iter().map(|(_, w)| w).sum();
                assert!((sum - 1.0).abs() < 5e-3, "{row:?}");
            }
            // Along the bottom edge: rising monotonically, no step left, and the ramp
            // (10 % to 90 %) about as wide as the smoothing asked.
            let bottom: Vec<f64> = (0..=60).map(|i| weight_of_2(&rows, 2 * i)).collect();
            assert!(bottom.windows(2).all(|w| w[1] >= w[0] - 1e-9));
            let biggest_jump = bottom.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
            let x = |level: f64| bottom.iter().position(|&w| w >= level).unwrap() as f64 * 0.01;
            let width = x(0.9) - x(0.1);
            assert!(
                width > smoothing && width < 4.0 * smoothing,
                "smoothing {smoothing}: ramp {width} m wide"
            );
            // No steeper than a straight ramp `smoothing` long.
            assert!(biggest_jump < 0.01 / smoothing, "jump {biggest_jump}");
        }
    }
}
