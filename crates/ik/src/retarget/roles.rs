//! Body roles found from a skeleton's structure: which joints are the legs, the arms, the
//! spine and the head, read from the hierarchy and the geometry of a standing pose. Names
//! are evidence only where the structure cannot tell ([`crate::naming`]): the side of a
//! chain when the pose does not show which way the body faces, end sites and twist joints.
//!
//! 1. **Legs.** The lowest leaf is a foot; the other foot is the lowest leaf whose chain
//!    splits from the first at least a quarter of the body's height above it. Where they
//!    split is the pelvis branch; each leg is the chain from below the branch to its foot.
//! 2. **Sideways.** The horizontal offset between the two legs is the body's side axis;
//!    distances along it from the point midway between the legs' first joints are the
//!    joints' lateral offsets.
//! 3. **Head and arms.** The highest leaf outside the legs is the top of the head. Every
//!    other leaf hangs off the chain from the pelvis branch to it at some joint; the two
//!    branches reaching furthest sideways, one on each side and at least as far out as the
//!    hips, are the arms, each the chain to the leaf furthest from where it hangs.
//! 4. **Positions along a chain.** A leg's hip is the joint its thigh starts from, the
//!    chain's first long way down (so a joint at the pelvis centre, CMU's `lhipjoint`,
//!    cgspeed's `LHipJoint`, Pinocchio's pelvis bone, is not taken for it), then knee,
//!    ankle and toe. The shoulders (upper arms) are the arms' first joints at least 1.25
//!    times as far apart as the hips (with one arm, its first joint as far out as a hip);
//!    the joint before is the collar (clavicle); then elbow and wrist. End sites and twist
//!    joints (by name) are skipped, so a twist joint or an `End Site` never takes a place.
//! 5. **Spine and head.** From the pelvis branch to the joint the arms hang from (the
//!    chest): hips, spine, spine1, chest; from there to the head: neck, neck1, head. Legs
//!    hanging from a pelvis joint below the hips leave that joint out. When the hierarchy
//!    hangs from the shoulders (Pinocchio's human template: the legs' and the head's chains
//!    meet where the arms hang), the torso roles follow the hierarchy from its root down
//!    to the pelvis branch, so a map never reverses it.
//! 6. **Left and right.** The body faces where the toes point from the ankles and the
//!    knees bend (in a stride a foot may point anywhere, a bent knee points forward); the
//!    character's right is `facing x up`. Without either, the chains'
//!    names decide ([`crate::naming::named_side`]); without those, the body is taken to
//!    face +z, the convention of the formats rigport reads.
//!
//! A pose that does not stand (Bandai Namco's BVH lays every bone along +x at rest) shows
//! no legs; [`find_body`] then reads the clip's first frame.

use glam::{Mat4, Vec3};
use rigport_eval::sample::{rest_locals, sample_frames, CompiledClip};
use rigport_eval::LocalToModelJob;
use rigport_model::{Clip, JointIndex, Skeleton};

use crate::naming::{is_end_site, is_twist, named_side, NamedSide};

/// The body roles, in the order reports list them.
pub const ROLES: [&str; 27] = [
    "Hips",
    "Spine",
    "Spine1",
    "Chest",
    "Neck",
    "Neck1",
    "Head",
    "LeftShoulder",
    "LeftUpperArm",
    "LeftLowerArm",
    "LeftHand",
    "RightShoulder",
    "RightUpperArm",
    "RightLowerArm",
    "RightHand",
    "LeftUpperLeg",
    "LeftLowerLeg",
    "LeftFoot",
    "LeftToes",
    "RightUpperLeg",
    "RightLowerLeg",
    "RightFoot",
    "RightToes",
    // Found by no rule here; kept so file maps and conventions can name them.
    "LeftFingers",
    "RightFingers",
    "LeftThumb",
    "RightThumb",
];

/// A part of the body: a group of roles a map must keep together.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Limb {
    /// Hips to chest.
    Spine,
    /// Neck to head.
    Head,
    /// Collar, upper arm, forearm, hand.
    LeftArm,
    /// Collar, upper arm, forearm, hand.
    RightArm,
    /// Upper leg, lower leg, foot, toes.
    LeftLeg,
    /// Upper leg, lower leg, foot, toes.
    RightLeg,
}

impl Limb {
    /// Every limb, in report order.
    pub const ALL: [Limb; 6] = [
        Limb::Spine,
        Limb::Head,
        Limb::LeftArm,
        Limb::RightArm,
        Limb::LeftLeg,
        Limb::RightLeg,
    ];

    /// The limb's name in messages (`"left leg"`).
    pub fn label(self) -> &'static str {
        match self {
            Limb::Spine => "spine",
            Limb::Head => "head",
            Limb::LeftArm => "left arm",
            Limb::RightArm => "right arm",
            Limb::LeftLeg => "left leg",
            Limb::RightLeg => "right leg",
        }
    }

    /// The limb a role belongs to; `None` for the finger roles.
    pub fn of(role: &str) -> Option<Limb> {
        Some(match role {
            "Hips" | "Spine" | "Spine1" | "Chest" => Limb::Spine,
            "Neck" | "Neck1" | "Head" => Limb::Head,
            "LeftShoulder" | "LeftUpperArm" | "LeftLowerArm" | "LeftHand" => Limb::LeftArm,
            "RightShoulder" | "RightUpperArm" | "RightLowerArm" | "RightHand" => Limb::RightArm,
            "LeftUpperLeg" | "LeftLowerLeg" | "LeftFoot" | "LeftToes" => Limb::LeftLeg,
            "RightUpperLeg" | "RightLowerLeg" | "RightFoot" | "RightToes" => Limb::RightLeg,
            _ => return None,
        })
    }

    /// The roles a map must drive for the limb to move, when the source has them: both
    /// segments of a leg or an arm (a hand, foot or collar alone does not move the limb);
    /// for the spine and the head, any one of their roles (`all` is false).
    pub fn core(self) -> (&'static [&'static str], bool) {
        match self {
            Limb::Spine => (&["Hips", "Spine", "Spine1", "Chest"], false),
            Limb::Head => (&["Neck", "Neck1", "Head"], false),
            Limb::LeftArm => (&["LeftUpperArm", "LeftLowerArm"], true),
            Limb::RightArm => (&["RightUpperArm", "RightLowerArm"], true),
            Limb::LeftLeg => (&["LeftUpperLeg", "LeftLowerLeg"], true),
            Limb::RightLeg => (&["RightUpperLeg", "RightLowerLeg"], true),
        }
    }
}

/// The body roles of one skeleton.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// `(role, joint)`, in [`ROLES`] order; a role appears at most once.
    pub roles: Vec<(&'static str, JointIndex)>,
    /// The joint at the pelvis, where the hips' position is measured.
    pub pelvis: JointIndex,
    /// The pose the roles were read from: `"rest pose"` or `"first frame"`.
    pub pose: &'static str,
    /// How left was told from right: `"geometry"` (the toes or knees show the facing) or
    /// `"names"`, or `"assumed facing +z"`.
    pub sides: &'static str,
}

impl Body {
    /// The joint playing `role`.
    pub fn joint(&self, role: &str) -> Option<JointIndex> {
        self.roles.iter().find(|(r, _)| *r == role).map(|(_, j)| *j)
    }

    /// The role `joint` plays.
    pub fn role_of(&self, joint: JointIndex) -> Option<&'static str> {
        self.roles
            .iter()
            .find(|(_, j)| *j == joint)
            .map(|(r, _)| *r)
    }

    /// The limbs with at least one role, in [`Limb::ALL`] order.
    pub fn limbs(&self) -> Vec<Limb> {
        Limb::ALL
            .into_iter()
            .filter(|l| self.roles.iter().any(|(r, _)| Limb::of(r) == Some(*l)))
            .collect()
    }
}

/// The body of `skeleton` (see the module docs): read from its rest pose, or, when that
/// does not stand and `clip` is given, from the clip's first frame. `up` is the model-space
/// up direction. `None` when neither pose shows two legs.
pub fn find_body(skeleton: &Skeleton, up: Vec3, clip: Option<&Clip>) -> Option<Body> {
    let up = up.normalize_or(Vec3::Y);
    let rest = skeleton.model_rest_matrices();
    if let Some(body) = body_in_pose(skeleton, &rest, up, "rest pose") {
        return Some(body);
    }
    let first = first_frame(skeleton, clip?)?;
    body_in_pose(skeleton, &first, up, "first frame")
}

/// Model matrices of the clip's first key time.
fn first_frame(skeleton: &Skeleton, clip: &Clip) -> Option<Vec<Mat4>> {
    let compiled = CompiledClip::new(clip, skeleton).ok()?;
    let t = *compiled.key_times().first()?;
    let local = sample_frames(&compiled, &rest_locals(skeleton), &[t]).ok()?;
    let parents: Vec<Option<JointIndex>> = skeleton.parents().collect();
    let mut model = vec![Mat4::IDENTITY; parents.len()];
    LocalToModelJob {
        parents: &parents,
        local: &local,
        root_model: Mat4::IDENTITY,
        model: &mut model,
    }
    .run()
    .ok()?;
    Some(model)
}

/// The hierarchy and the pose, with the walks the rules need.
struct Tree<'a> {
    skeleton: &'a Skeleton,
    pos: Vec<Vec3>,
    up: Vec3,
    children: Vec<Vec<usize>>,
}

impl Tree<'_> {
    fn parent(&self, j: usize) -> Option<usize> {
        self.skeleton
            .joint(JointIndex(j as u32))
            .parent
            .map(JointIndex::get)
    }

    fn height(&self, j: usize) -> f32 {
        self.pos[j].dot(self.up)
    }

    fn name(&self, j: usize) -> &str {
        &self.skeleton.joint(JointIndex(j as u32)).name
    }

    /// `j` and its ancestors, `j` first.
    fn to_root(&self, j: usize) -> Vec<usize> {
        let mut out = vec![j];
        while let Some(p) = out.last().and_then(|&c| self.parent(c)) {
            out.push(p);
        }
        out
    }

    fn lca(&self, a: usize, b: usize) -> Option<usize> {
        let above_a = self.to_root(a);
        self.to_root(b).into_iter().find(|j| above_a.contains(j))
    }

    /// The joints from `from` (exclusive) down to its descendant `to` (inclusive).
    fn down(&self, from: usize, to: usize) -> Vec<usize> {
        let mut path: Vec<usize> = self
            .to_root(to)
            .into_iter()
            .take_while(|&j| j != from)
            .collect();
        path.reverse();
        path
    }

    fn is_below(&self, j: usize, ancestor: usize) -> bool {
        self.to_root(j).contains(&ancestor)
    }

    /// The joints of a chain that can take a place in it: no end sites or twist joints.
    fn places(&self, chain: &[usize]) -> Vec<usize> {
        chain
            .iter()
            .copied()
            .filter(|&j| !is_end_site(self.name(j)) && !is_twist(self.name(j)))
            .collect()
    }

    fn horizontal(&self, v: Vec3) -> Vec3 {
        v - v.dot(self.up) * self.up
    }
}

/// The body read from one pose (model matrices, one per joint); `None` when the pose
/// shows no two legs (see the module docs).
pub fn body_in_pose(
    skeleton: &Skeleton,
    model: &[Mat4],
    up: Vec3,
    pose: &'static str,
) -> Option<Body> {
    let n = skeleton.len();
    if n < 4 || model.len() != n {
        return None;
    }
    let mut children = vec![Vec::new(); n];
    for (j, joint) in skeleton.joints().iter().enumerate() {
        if let Some(p) = joint.parent {
            children.get_mut(p.get())?.push(j);
        }
    }
    let tree = Tree {
        skeleton,
        pos: model.iter().map(|m| m.w_axis.truncate()).collect(),
        up,
        children,
    };
    let (lo, hi) = (0..n).fold((f32::MAX, f32::MIN), |(lo, hi), j| {
        (lo.min(tree.height(j)), hi.max(tree.height(j)))
    });
    let height = hi - lo;
    if height.is_nan() || height <= 0.0 {
        return None;
    }
    let mut leaves: Vec<usize> = (0..n).filter(|&j| tree.children[j].is_empty()).collect();
    leaves.sort_by(|&a, &b| tree.height(a).total_cmp(&tree.height(b)));

    // 1. Legs.
    let foot_a = *leaves.first()?;
    let (foot_b, branch) = leaves[1..].iter().find_map(|&l| {
        let x = tree.lca(foot_a, l)?;
        (tree.height(x) - tree.height(foot_a) >= 0.25 * height).then_some((l, x))
    })?;
    let leg_a = tree.down(branch, foot_a);
    let leg_b = tree.down(branch, foot_b);
    let (first_a, first_b) = (*leg_a.first()?, *leg_b.first()?);

    // 2. Sideways: positive towards leg A; first between the legs' joints on average, then
    // between the hips (a stride in a clip's first frame moves the feet, not the hips).
    let mean =
        |chain: &[usize]| chain.iter().map(|&j| tree.pos[j]).sum::<Vec3>() / chain.len() as f32;
    let axis = tree
        .horizontal(mean(&leg_a) - mean(&leg_b))
        .normalize_or_zero();
    let origin = 0.5 * (tree.pos[first_a] + tree.pos[first_b]);
    let lateral = |j: usize| (tree.pos[j] - origin).dot(axis);

    // The hip starts the thigh, the first long way down (an eighth of the height; a thigh
    // is about a quarter, a pelvis bone to the hip joint well under a tenth), else the
    // first joint half as far out as the leg's furthest.
    let leg_places = |chain: &[usize]| -> Vec<usize> {
        let places = tree.places(chain);
        let hip = places
            .windows(2)
            .position(|w| tree.height(w[0]) - tree.height(w[1]) >= 0.125 * height)
            .or_else(|| {
                let far = places
                    .iter()
                    .map(|&j| lateral(j).abs())
                    .fold(0.0f32, f32::max);
                places.iter().position(|&j| lateral(j).abs() >= 0.5 * far)
            })
            .unwrap_or(0);
        places[hip..].iter().copied().take(4).collect()
    };
    let (legs_a, legs_b) = (leg_places(&leg_a), leg_places(&leg_b));
    if legs_a.len() < 2 || legs_b.len() < 2 {
        return None;
    }
    let (hip_a, hip_b) = (tree.pos[legs_a[0]], tree.pos[legs_b[0]]);
    let side_axis = match tree.horizontal(hip_a - hip_b).normalize_or_zero() {
        v if v.dot(axis) > 0.0 => v,
        _ => axis,
    };
    let origin = 0.5 * (hip_a + hip_b);
    let lateral = |j: usize| (tree.pos[j] - origin).dot(side_axis);
    let hip_width = 0.5 * (lateral(legs_a[0]).abs() + lateral(legs_b[0]).abs());

    // 3. Head and arms.
    let in_legs = |j: usize| tree.is_below(j, first_a) || tree.is_below(j, first_b);
    let head_top = leaves
        .iter()
        .rev()
        .copied()
        .find(|&l| !in_legs(l) && l != branch);
    let top = head_top.and_then(|h| tree.lca(branch, h));
    // The chain from the pelvis branch to the head: up to where they meet, then down.
    let spine: Vec<usize> = match (head_top, top) {
        (Some(h), Some(t)) => {
            let mut up_part: Vec<usize> = tree
                .to_root(branch)
                .into_iter()
                .take_while(|&j| j != t)
                .collect();
            up_part.push(t);
            up_part.extend(tree.down(t, h));
            up_part
        }
        _ => vec![branch],
    };
    let mut arms: Vec<(usize, Vec<usize>)> = Vec::new(); // (hangs from, chain)
    for &leaf in &leaves {
        if in_legs(leaf) || spine.contains(&leaf) {
            continue;
        }
        let path = tree.to_root(leaf);
        let Some(k) = path.iter().position(|j| spine.contains(j)) else {
            continue;
        };
        if k == 0 {
            continue;
        }
        let (attach, start) = (path[k], path[k - 1]);
        let far = |j: usize| tree.pos[j].distance(tree.pos[attach]);
        match arms.iter_mut().find(|(_, c)| c.first() == Some(&start)) {
            Some((_, chain)) => {
                let end = *chain.last().unwrap_or(&start);
                if far(leaf) > far(end) {
                    *chain = tree.down(attach, leaf);
                }
            }
            None => arms.push((attach, tree.down(attach, leaf))),
        }
    }
    let reach = |chain: &[usize]| {
        chain
            .iter()
            .map(|&j| lateral(j))
            .fold(0.0f32, |a, l| if l.abs() > a.abs() { l } else { a })
    };
    let pick = |sign: f32| {
        arms.iter()
            .filter(|(_, c)| reach(c) * sign >= hip_width.max(1e-3 * height))
            .max_by(|a, b| (reach(&a.1) * sign).total_cmp(&(reach(&b.1) * sign)))
            .cloned()
    };
    let (arm_a, arm_b) = (pick(1.0), pick(-1.0));
    // The shoulders: the first places of the two arms at least 1.25 times as far apart as
    // the hips (shoulders are about twice as wide as the hip joints, the collars' roots
    // nearer than the hips; the girdle is rigid, so this holds in any pose); with one arm,
    // its first place at least as far out as a hip.
    let shoulder_at = {
        let places = |arm: &Option<(usize, Vec<usize>)>| arm.as_ref().map(|(_, c)| tree.places(c));
        match (places(&arm_a), places(&arm_b)) {
            (Some(a), Some(b)) => {
                let hips = hip_a.distance(hip_b);
                a.iter()
                    .zip(&b)
                    .position(|(&x, &y)| tree.pos[x].distance(tree.pos[y]) >= 1.25 * hips)
            }
            _ => None,
        }
    };
    let arm_places = |chain: &[usize]| -> Vec<Option<usize>> {
        let places = tree.places(chain);
        let out = |w: f32| places.iter().position(|&j| lateral(j).abs() >= w);
        let shoulder = shoulder_at
            .or_else(|| out(hip_width))
            .or_else(|| out(0.6 * hip_width))
            .unwrap_or(usize::from(places.len() >= 3));
        let at = |i: Option<usize>| i.and_then(|i| places.get(i).copied());
        vec![
            at(shoulder.checked_sub(1)),
            at(Some(shoulder)),
            at(Some(shoulder + 1)),
            at(Some(shoulder + 2)),
        ]
    };

    // 5. Spine and head.
    let mut roles: Vec<(&'static str, usize)> = Vec::new();
    let chest = match (&arm_a, &arm_b) {
        (Some((a, _)), Some((b, _))) => {
            let (ia, ib) = (
                spine.iter().position(|j| j == a),
                spine.iter().position(|j| j == b),
            );
            Some(if ia <= ib { *a } else { *b })
        }
        (Some((a, _)), None) | (None, Some((a, _))) => Some(*a),
        (None, None) => None,
    };
    let top = top.unwrap_or(branch);
    // The legs may hang from a pelvis joint below the hips (`Hips -> Pelvis -> LeftUpLeg`,
    // the spine from `Hips`): then the top is the hips. When the top is where the arms hang
    // (or below it), the hierarchy hangs from the shoulders; without arms, when the top is
    // well above the pelvis.
    let hangs = match chest {
        Some(c) => tree.is_below(top, c),
        None => tree.height(top) - tree.height(branch) >= 0.15 * height,
    };
    let pelvis = if !hangs {
        // Hips, the joints up to the chest, the chest, then the neck and head.
        let spine: Vec<usize> = match head_top {
            Some(h) if top != branch => std::iter::once(top).chain(tree.down(top, h)).collect(),
            _ => spine.clone(),
        };
        let hips = spine[0];
        roles.push(("Hips", hips));
        let ci = chest.and_then(|c| spine.iter().position(|&j| j == c));
        let (between, head_part) = match ci {
            Some(ci) => (&spine[1..ci], &spine[ci + 1..]),
            None => (&spine[..0], &spine[1..]),
        };
        for (role, &j) in ["Spine", "Spine1"].iter().zip(tree.places(between).iter()) {
            roles.push((role, j));
        }
        if let Some(c) = chest.filter(|&c| c != hips) {
            roles.push(("Chest", c));
        }
        head_roles(&tree.places(head_part), &mut roles);
        hips
    } else {
        // The hierarchy hangs from above the pelvis: its root is the hips, the joints down
        // to the pelvis branch the spine, the branch the chest.
        roles.push(("Hips", top));
        let down = tree.down(top, branch);
        let inner = tree.places(&down[..down.len().saturating_sub(1)]);
        for (role, &j) in ["Spine", "Spine1"].iter().zip(inner.iter()) {
            roles.push((role, j));
        }
        roles.push(("Chest", branch));
        let from = chest.filter(|c| tree.is_below(*c, top)).unwrap_or(top);
        if let Some(h) = head_top.filter(|&h| tree.is_below(h, from)) {
            head_roles(&tree.places(&tree.down(from, h)), &mut roles);
        }
        first_a
    };

    // 6. Left and right.
    let (a_is_left, sides) = sides(
        &tree,
        [&legs_a, &legs_b],
        side_axis,
        height,
        [&leg_a, &leg_b],
    );
    for (legs, arm, is_left) in [(&legs_a, &arm_a, a_is_left), (&legs_b, &arm_b, !a_is_left)] {
        let side = if is_left { "Left" } else { "Right" };
        for (part, &j) in ["UpperLeg", "LowerLeg", "Foot", "Toes"]
            .iter()
            .zip(legs.iter())
        {
            roles.push((role_name(side, part)?, j));
        }
        if let Some((_, chain)) = arm {
            let parts = ["Shoulder", "UpperArm", "LowerArm", "Hand"];
            for (part, j) in parts.iter().zip(arm_places(chain)) {
                if let Some(j) = j {
                    roles.push((role_name(side, part)?, j));
                }
            }
        }
    }
    let mut roles: Vec<(&'static str, JointIndex)> = roles
        .into_iter()
        .map(|(r, j)| (r, JointIndex(j as u32)))
        .collect();
    roles.sort_by_key(|(r, _)| ROLES.iter().position(|x| x == r));
    roles.dedup_by_key(|(r, _)| *r);
    Some(Body {
        roles,
        pelvis: JointIndex(pelvis as u32),
        pose,
        sides,
    })
}

/// Neck, neck1 and head along the joints from the chest to the top of the head: one
/// joint is the neck (Pinocchio's head bone spans both); two are neck and head; more give
/// neck, neck1 and, last, the head.
fn head_roles(chain: &[usize], roles: &mut Vec<(&'static str, usize)>) {
    match chain {
        [] => {}
        [neck] => roles.push(("Neck", *neck)),
        [neck, rest @ ..] => {
            roles.push(("Neck", *neck));
            if rest.len() >= 2 {
                roles.push(("Neck1", rest[0]));
            }
            if let Some(head) = rest.last() {
                roles.push(("Head", *head));
            }
        }
    }
}

/// The role `side` + `part` (`"Left"`, `"UpperLeg"`), as one of [`ROLES`].
fn role_name(side: &str, part: &str) -> Option<&'static str> {
    ROLES
        .iter()
        .find(|r| r.strip_prefix(side) == Some(part))
        .copied()
}

/// Whether leg A is the left one, and how that was told (rule 6 of the module docs).
/// `legs` holds each leg's places (hip, knee, ankle, toe), `chains` each leg's joints.
fn sides(
    tree: &Tree<'_>,
    legs: [&[usize]; 2],
    side_axis: Vec3,
    height: f32,
    chains: [&[usize]; 2],
) -> (bool, &'static str) {
    // Each foot votes with the unit direction its toes point; each knee with how far it
    // bends forward, a tenth of the leg counting as much as a foot (a standing leg is
    // straight and its foot decides; in a stride a foot may point anywhere, a knee bends
    // forward).
    let mut facing = Vec3::ZERO;
    for leg in legs {
        if let [hip, knee, ankle, rest @ ..] = leg {
            let at = |j: &usize| tree.pos[*j];
            if let Some(toe) = rest.first() {
                let toes = tree.horizontal(at(toe) - at(ankle));
                if toes.length() > 1e-3 * height {
                    facing += toes.normalize();
                }
            }
            let length = at(hip).distance(at(knee)) + at(knee).distance(at(ankle));
            let bend = tree.horizontal(at(knee) - 0.5 * (at(hip) + at(ankle)));
            facing += bend / (0.1 * length).max(f32::MIN_POSITIVE);
        }
    }
    if facing.length() > 1e-3 && side_axis != Vec3::ZERO {
        let right = facing.normalize().cross(tree.up);
        return (side_axis.dot(right) < 0.0, "geometry");
    }
    let vote = |chain: &[usize]| {
        chain
            .iter()
            .map(|&j| match named_side(tree.name(j)) {
                Some(NamedSide::Left) => 1,
                Some(NamedSide::Right) => -1,
                None => 0,
            })
            .sum::<i32>()
    };
    let v = vote(chains[0]) - vote(chains[1]);
    if v != 0 {
        return (v > 0, "names");
    }
    let z = tree.horizontal(Vec3::Z).normalize_or(Vec3::X);
    (side_axis.dot(z.cross(tree.up)) < 0.0, "assumed facing +z")
}

/// What makes a joint map partial (see [`check_pairs`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MapProblem {
    /// A limb of the source whose core joints ([`Limb::core`]) drive no target joint.
    Unmapped {
        /// The limb.
        limb: Limb,
        /// The source joints of its core roles that drive nothing.
        joints: Vec<String>,
    },
    /// A source joint of one limb drives a target joint of another (the spine and the head
    /// count as one: where the chest ends and the neck starts is not anatomy).
    WrongLimb {
        /// The source joint.
        source: String,
        /// Its limb.
        source_limb: Limb,
        /// The target joint.
        target: String,
        /// Its limb.
        target_limb: Limb,
    },
}

impl std::fmt::Display for MapProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MapProblem::Unmapped { limb, joints } => write!(
                f,
                "the source's {} ({}) drives no target joint",
                limb.label(),
                joints.join(", ")
            ),
            MapProblem::WrongLimb {
                source,
                source_limb,
                target,
                target_limb,
            } => write!(
                f,
                "{source:?} of the source's {} drives {target:?} of the target's {}",
                source_limb.label(),
                target_limb.label()
            ),
        }
    }
}

/// Whether `(source, target)` joint pairs move every limb of the source's body and keep
/// each limb on a limb of the same role in the target's body (when the target's body is
/// known). Returns every problem, limbs in [`Limb::ALL`] order, then pairs in order.
pub fn check_pairs(
    pairs: &[(JointIndex, JointIndex)],
    source: &Skeleton,
    source_body: &Body,
    target: &Skeleton,
    target_body: Option<&Body>,
) -> Vec<MapProblem> {
    let name = |s: &Skeleton, j: JointIndex| {
        s.joints()
            .get(j.get())
            .map_or_else(|| format!("#{}", j.get()), |x| x.name.clone())
    };
    let drives = |j: JointIndex| pairs.iter().any(|(s, _)| *s == j);
    let mut out = Vec::new();
    for limb in source_body.limbs() {
        let (core, all) = limb.core();
        let joints: Vec<JointIndex> = core.iter().filter_map(|r| source_body.joint(r)).collect();
        if joints.is_empty() {
            continue;
        }
        let idle: Vec<JointIndex> = joints.iter().copied().filter(|&j| !drives(j)).collect();
        if (all && !idle.is_empty()) || (!all && idle.len() == joints.len()) {
            out.push(MapProblem::Unmapped {
                limb,
                joints: idle.iter().map(|&j| name(source, j)).collect(),
            });
        }
    }
    let Some(target_body) = target_body else {
        return out;
    };
    let torso = |l: Limb| if l == Limb::Head { Limb::Spine } else { l };
    for &(s, t) in pairs {
        let (Some(ls), Some(lt)) = (
            source_body.role_of(s).and_then(Limb::of),
            target_body.role_of(t).and_then(Limb::of),
        ) else {
            continue;
        };
        if torso(ls) != torso(lt) {
            out.push(MapProblem::WrongLimb {
                source: name(source, s),
                source_limb: ls,
                target: name(target, t),
                target_limb: lt,
            });
        }
    }
    out
}
