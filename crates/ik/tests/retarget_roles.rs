//! Body roles from structure (issue 28): every corpus BVH and ASF/AMC, under its own
//! naming and renamed (cgspeed's original names, Mixamo, Bandai Namco, numbered joints),
//! shows the same roles, which are the roles its own naming convention gives; and onto the
//! Pinocchio `human_model1` rig (no joint names: the structure is the only evidence) the
//! map moves both legs, both arms, the spine and the head.
#![allow(
    clippy::unwrap_used,
    reason = "test code: a failed unwrap is a failed test"
)]

use std::path::{Path, PathBuf};

use rigport_ik::footlock::up_in_model;
use rigport_ik::retarget::maps::{self, Convention};
use rigport_ik::retarget::roles::check_pairs;
use rigport_ik::retarget::{auto_map, find_body, Body, Limb};
use rigport_model::{Asset, JointIndex, Skeleton};

const HUMAN_MODEL1: &str = "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1";

/// The first asset the inputs make, opened as the CLI does.
fn open(paths: &[PathBuf]) -> Asset {
    let inputs = rigport_import::detect::Inputs::new(paths.to_vec());
    let mut opened = rigport_import::detect::open(&inputs).expect("corpus input opens");
    opened.remove(0).1.asset
}

/// The corpus motions MANIFEST.tsv lists: every `.bvh` under `4_bvh`, and every `.asf`
/// under `3_acclaim_asf_amc` with the `.amc` files of its subject beside it (an ASF alone
/// when it has none).
fn motions(corpus: &Path) -> Vec<Vec<PathBuf>> {
    let manifest = std::fs::read_to_string(corpus.join("MANIFEST.tsv")).unwrap();
    let files: Vec<&str> = manifest
        .lines()
        .filter_map(|l| l.split('\t').nth(1))
        .collect();
    let mut out: Vec<Vec<PathBuf>> = files
        .iter()
        .filter(|f| f.starts_with("4_bvh/") && f.ends_with(".bvh"))
        .map(|f| vec![corpus.join(f)])
        .collect();
    for asf in files
        .iter()
        .filter(|f| f.starts_with("3_acclaim_asf_amc/") && f.ends_with(".asf"))
    {
        let (dir, name) = asf.rsplit_once('/').unwrap();
        let subject = name.split(['-', '.']).next().unwrap();
        let amcs: Vec<&&str> = files
            .iter()
            .filter(|f| {
                f.ends_with(".amc")
                    && f.rsplit_once('/')
                        .is_some_and(|(d, n)| d == dir && n.split('_').next() == Some(subject))
            })
            .collect();
        if amcs.is_empty() {
            out.push(vec![corpus.join(asf)]);
        }
        for amc in amcs {
            out.push(vec![corpus.join(asf), corpus.join(amc)]);
        }
    }
    out
}

/// The naming convention that names the most joints of `skeleton`.
fn convention_of(skeleton: &Skeleton) -> &'static Convention {
    maps::CONVENTIONS
        .iter()
        .max_by_key(|c| {
            c.joints
                .iter()
                .filter(|(_, n)| skeleton.find(n).is_some())
                .count()
        })
        .unwrap()
}

/// The namings the renamed copies use, by role; joints without a role are named by the
/// naming's `extra` pattern (`{}`: the joint's index).
struct Naming {
    label: &'static str,
    role: fn(&str) -> Option<String>,
    extra: &'static str,
}

fn side_parts(role: &str) -> Option<(&'static str, &str)> {
    role.strip_prefix("Left")
        .map(|r| ("L", r))
        .or_else(|| role.strip_prefix("Right").map(|r| ("R", r)))
}

const NAMINGS: [Naming; 4] = [
    // cgspeed's first release of the CMU database: LeftHip is the upper leg, LeftShoulder
    // the upper arm, LeftCollar the clavicle.
    Naming {
        label: "cgspeed original",
        role: |role| {
            let (side, part) = side_parts(role).unwrap_or(("", role));
            let word = if side == "L" { "Left" } else { "Right" };
            let part = match part {
                "UpperLeg" => "Hip",
                "LowerLeg" => "Knee",
                "Foot" => "Ankle",
                "Toes" => "Toe",
                "Shoulder" => "Collar",
                "UpperArm" => "Shoulder",
                "LowerArm" => "Elbow",
                "Hand" => "Wrist",
                "Spine" => return Some("Abdomen".into()),
                "Spine1" => return Some("Spine".into()),
                other => return Some(other.into()),
            };
            Some(format!("{word}{part}"))
        },
        extra: "Extra{}",
    },
    Naming {
        label: "Mixamo",
        role: |role| {
            let name = match role {
                "Chest" => "Spine2".to_string(),
                r => match side_parts(r) {
                    Some((s, part)) => {
                        let word = if s == "L" { "Left" } else { "Right" };
                        let part = match part {
                            "UpperLeg" => "UpLeg",
                            "LowerLeg" => "Leg",
                            "Toes" => "ToeBase",
                            "UpperArm" => "Arm",
                            "LowerArm" => "ForeArm",
                            p => p,
                        };
                        format!("{word}{part}")
                    }
                    None => r.to_string(),
                },
            };
            Some(format!("mixamorig:{name}"))
        },
        extra: "mixamorig:Extra{}",
    },
    Naming {
        label: "Bandai Namco",
        role: |role| {
            Some(match side_parts(role) {
                Some((s, part)) => format!("{part}_{s}"),
                None => role.to_string(),
            })
        },
        extra: "Extra_{}",
    },
    Naming {
        label: "numbered",
        role: |_| None,
        extra: "j{}",
    },
];

/// `asset` with its joints renamed by `naming`, roles taken from its own convention;
/// end sites named as the BVH importer names them (`<parent>_end`).
fn renamed(asset: &Asset, convention: &Convention, naming: &Naming) -> Asset {
    let old = &asset.skeleton;
    let mut joints = old.joints().to_vec();
    let role_of = |name: &str| {
        convention
            .joints
            .iter()
            .find(|(_, n)| n.eq_ignore_ascii_case(name))
            .map(|(r, _)| *r)
    };
    let mut new_names: Vec<String> = Vec::new();
    for (i, j) in old.joints().iter().enumerate() {
        let end_of = j
            .parent
            .filter(|p| j.name == format!("{}_end", old.joint(*p).name));
        let name = match end_of {
            Some(p) => format!("{}_end", new_names[p.get()]),
            None => role_of(&j.name)
                .and_then(naming.role)
                .unwrap_or_else(|| naming.extra.replace("{}", &i.to_string())),
        };
        new_names.push(name);
    }
    for (j, name) in joints.iter_mut().zip(new_names) {
        j.name = name;
    }
    let mut out = asset.clone();
    out.skeleton = Skeleton::new(joints).unwrap();
    out
}

/// The roles a naming convention gives (CMU ASF, cgspeed BVH, Bandai Namco BVH).
fn named_roles(skeleton: &Skeleton, convention: &Convention) -> Vec<(&'static str, JointIndex)> {
    let mut out: Vec<(&'static str, JointIndex)> = convention
        .joints
        .iter()
        .filter_map(|&(r, n)| skeleton.find(n).map(|j| (r, j)))
        .collect();
    out.sort_by_key(|(r, _)| maps::ROLES.iter().position(|x| x == r));
    out
}

fn body_of(asset: &Asset) -> Body {
    find_body(
        &asset.skeleton,
        up_in_model(&asset.frame),
        asset.clips.first(),
    )
    .expect("a body")
}

#[test]
fn every_corpus_motion_under_every_naming_maps_every_limb_onto_human_model1() {
    let (Some(corpus), Some(model1)) = (
        rigport_testkit::corpus(""),
        rigport_testkit::corpus(HUMAN_MODEL1),
    ) else {
        return;
    };
    let rig = open(&[model1]);
    let rig_up = up_in_model(&rig.frame);
    let rig_body = find_body(&rig.skeleton, rig_up, None).expect("human_model1's body");
    assert_eq!(rig_body.limbs(), Limb::ALL.to_vec(), "{rig_body:?}");
    let motions = motions(&corpus);
    assert!(motions.len() >= 8, "{motions:?}");
    let mut measured = Vec::new();
    for paths in motions {
        let label = paths
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join(" + ");
        let asset = open(&paths);
        let convention = convention_of(&asset.skeleton);
        let body = body_of(&asset);
        assert_eq!(
            body.roles,
            named_roles(&asset.skeleton, convention),
            "{label}: the structure's roles are not the {} names' roles",
            convention.label
        );
        let mut copies = vec![(convention.label, asset.clone())];
        copies.extend(
            NAMINGS
                .iter()
                .map(|n| (n.label, renamed(&asset, convention, n))),
        );
        for (naming, copy) in &copies {
            let found = body_of(copy);
            assert_eq!(found.roles, body.roles, "{label} named {naming}");
            assert_eq!(found.pelvis, body.pelvis, "{label} named {naming}");
            let Some(clip) = copy.clips.first() else {
                // An ASF without a motion (the legs-only CMU 02.asf) has nothing to put on
                // a rig; its roles are checked above.
                measured.push(format!("{label} ({naming}): {:?}", found.limbs()));
                continue;
            };
            let up = up_in_model(&copy.frame);
            let map = auto_map(&copy.skeleton, &rig.skeleton, up, rig_up, Some(clip)).unwrap();
            let pairs: Vec<(JointIndex, JointIndex)> =
                map.pairs.iter().map(|p| (p.source, p.target)).collect();
            let problems = check_pairs(
                &pairs,
                &copy.skeleton,
                &found,
                &rig.skeleton,
                Some(&rig_body),
            );
            assert!(problems.is_empty(), "{label} named {naming}: {problems:?}");
            for limb in Limb::ALL {
                let moved: Vec<&str> = limb
                    .core()
                    .0
                    .iter()
                    .copied()
                    .filter(|r| {
                        let (s, t) = (found.joint(r), rig_body.joint(r));
                        pairs.iter().any(|&p| Some(p.0) == s && Some(p.1) == t)
                    })
                    .collect();
                assert!(
                    !moved.is_empty(),
                    "{label} named {naming}: the {} is not mapped ({})",
                    limb.label(),
                    map.how
                );
            }
            measured.push(format!(
                "{label} ({naming}): {} pairs, all six limbs; {}",
                pairs.len(),
                map.how
            ));
        }
    }
    for line in measured {
        eprintln!("{line}");
    }
}

/// A BVH skeleton as cgspeed's first release of the CMU database names it (18 joints:
/// `LeftHip` the upper leg, `LeftCollar` the clavicle, `LeftShoulder` the upper arm), Y up,
/// facing +z (the character's left at +x), knees bent a little forward, with end sites.
fn cgspeed_bvh() -> String {
    let leg = |side: &str, x: f32| {
        format!(
            "JOINT {side}Hip\n{{\nOFFSET {x} -5 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             JOINT {side}Knee\n{{\nOFFSET 0 -42 2\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             JOINT {side}Ankle\n{{\nOFFSET 0 -40 -2\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             End Site\n{{\nOFFSET 0 -8 14\n}}\n}}\n}}\n}}\n"
        )
    };
    let arm = |side: &str, s: f32| {
        format!(
            "JOINT {side}Collar\n{{\nOFFSET {} 20 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             JOINT {side}Shoulder\n{{\nOFFSET {} 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             JOINT {side}Elbow\n{{\nOFFSET {} 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             JOINT {side}Wrist\n{{\nOFFSET {} 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             End Site\n{{\nOFFSET {} 0 0\n}}\n}}\n}}\n}}\n}}\n",
            3.0 * s,
            15.0 * s,
            28.0 * s,
            25.0 * s,
            18.0 * s
        )
    };
    format!(
        "HIERARCHY\nROOT Hips\n{{\nOFFSET 0 0 0\n\
         CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n\
         {}{}JOINT Chest\n{{\nOFFSET 0 25 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n{}{}\
         JOINT Neck\n{{\nOFFSET 0 24 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
         JOINT Head\n{{\nOFFSET 0 8 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
         End Site\n{{\nOFFSET 0 18 0\n}}\n}}\n}}\n}}\n}}\n\
         MOTION\nFrames: 2\nFrame Time: 0.033333\n{}\n{}\n",
        leg("Left", 9.0),
        leg("Right", -9.0),
        arm("Left", 1.0),
        arm("Right", -1.0),
        vec!["0"; 57].join(" "),
        vec!["0"; 57].join(" ")
    )
}

/// `bvh` with its `ROOT`/`JOINT` names renamed by `rename`.
fn rename_bvh(bvh: &str, rename: impl Fn(usize, &str) -> String) -> String {
    let mut k = 0;
    bvh.lines()
        .map(|line| match line.split_once(' ') {
            Some((kw @ ("ROOT" | "JOINT"), name)) => {
                k += 1;
                format!("{kw} {}", rename(k - 1, name))
            }
            _ => line.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn import_bvh(text: &str) -> Asset {
    let path = Path::new("renamed.bvh");
    let bvh = rigport_import::bvh::parse(text, path).unwrap();
    rigport_import::bvh::to_asset("renamed", &bvh)
        .unwrap()
        .asset
}

/// cgspeed's original names, with Mixamo's, Bandai Namco's and numbered ones for them.
const CGSPEED_RENAMED: [(&str, &str, &str, &str); 8] = [
    ("Hip", "UpLeg", "UpperLeg", "thigh"),
    ("Knee", "Leg", "LowerLeg", "calf"),
    ("Ankle", "Foot", "Foot", "foot"),
    ("Collar", "Shoulder", "Shoulder", "clavicle"),
    ("Shoulder", "Arm", "UpperArm", "upperarm"),
    ("Elbow", "ForeArm", "LowerArm", "lowerarm"),
    ("Wrist", "Hand", "Hand", "hand"),
    ("Chest", "Spine2", "Chest", "spine_03"),
];

/// A renaming: joint order index and old name to the new name.
type Rename<'a> = Box<dyn Fn(usize, &str) -> String + 'a>;

#[test]
fn renamed_copies_find_the_same_roles() {
    let original = cgspeed_bvh();
    let asset = import_bvh(&original);
    let body = body_of(&asset);
    let named: Vec<(&str, &str)> = body
        .roles
        .iter()
        .map(|&(r, j)| (r, asset.skeleton.joint(j).name.as_str()))
        .collect();
    let expected = [
        ("Hips", "Hips"),
        ("Chest", "Chest"),
        ("Neck", "Neck"),
        ("Head", "Head"),
        ("LeftShoulder", "LeftCollar"),
        ("LeftUpperArm", "LeftShoulder"),
        ("LeftLowerArm", "LeftElbow"),
        ("LeftHand", "LeftWrist"),
        ("RightShoulder", "RightCollar"),
        ("RightUpperArm", "RightShoulder"),
        ("RightLowerArm", "RightElbow"),
        ("RightHand", "RightWrist"),
        ("LeftUpperLeg", "LeftHip"),
        ("LeftLowerLeg", "LeftKnee"),
        ("LeftFoot", "LeftAnkle"),
        ("RightUpperLeg", "RightHip"),
        ("RightLowerLeg", "RightKnee"),
        ("RightFoot", "RightAnkle"),
    ];
    assert_eq!(named, expected, "{body:?}");
    assert_eq!(body.sides, "geometry");
    // Mixamo (`mixamorig:LeftUpLeg`), Bandai Namco (`UpperLeg_L`), Unreal-like lower case
    // (`thigh_l`) and numbered joints (`j0`..`j17`).
    let part = |name: &str, column: usize| {
        let (side, rest) = name
            .strip_prefix("Left")
            .map(|r| ("Left", r))
            .or_else(|| name.strip_prefix("Right").map(|r| ("Right", r)))
            .unwrap_or(("", name));
        let row = CGSPEED_RENAMED.iter().find(|r| r.0 == rest);
        let new = row.map_or(rest, |r| [r.0, r.1, r.2, r.3][column]);
        (side, new.to_string())
    };
    let namings: [(&str, Rename<'_>); 4] = [
        (
            "Mixamo",
            Box::new(|_, n| {
                let (side, p) = part(n, 1);
                format!("mixamorig:{side}{p}")
            }),
        ),
        (
            "Bandai Namco",
            Box::new(|_, n| match part(n, 2) {
                ("", p) => p,
                (side, p) => format!("{p}_{}", &side[..1]),
            }),
        ),
        (
            "lower case",
            Box::new(|_, n| match part(n, 3) {
                ("", p) => p.to_lowercase(),
                (side, p) => format!("{p}_{}", side[..1].to_lowercase()),
            }),
        ),
        ("numbered", Box::new(|k, _| format!("j{k}"))),
    ];
    for (label, rename) in namings {
        let copy = import_bvh(&rename_bvh(&original, rename));
        let found = body_of(&copy);
        assert_eq!(found.roles, body.roles, "{label}: {found:?}");
        assert_eq!(found.pelvis, body.pelvis, "{label}");
        assert_eq!(found.sides, "geometry", "{label}");
    }
}

#[test]
fn names_tell_the_side_only_when_the_pose_cannot() {
    use rigport_ik::naming::{named_side, NamedSide::*};
    for (name, side) in [
        ("LeftUpLeg", Some(Left)),
        ("mixamorig:RightArm", Some(Right)),
        ("UpperLeg_L", Some(Left)),
        ("thigh_r", Some(Right)),
        ("Bip01 L Thigh", Some(Left)),
        ("LHipJoint", Some(Left)),
        ("RThumb", Some(Right)),
        ("lfemur", Some(Left)),
        ("rclavicle", Some(Right)),
        ("LowerBack", None),
        ("Root", None),
        ("lowerneck", None),
        ("bone_5", None),
        ("j12", None),
    ] {
        assert_eq!(named_side(name), side, "{name}");
    }
    // A straight-legged skeleton without toes shows no facing: the names decide, and a
    // mirrored copy (the `Left` chains at -x) keeps its named sides.
    let straight = cgspeed_bvh()
        .replace("OFFSET 0 -42 2", "OFFSET 0 -42 0")
        .replace("OFFSET 0 -40 -2", "OFFSET 0 -40 0");
    let mirrored = straight
        .replace("OFFSET 9 -5 0", "OFFSET X -5 0")
        .replace("OFFSET -9 -5 0", "OFFSET 9 -5 0")
        .replace("OFFSET X -5 0", "OFFSET -9 -5 0");
    for text in [straight, mirrored] {
        let asset = import_bvh(&text);
        let body = body_of(&asset);
        assert_eq!(body.sides, "names");
        let hip = body.joint("LeftUpperLeg").unwrap();
        assert_eq!(asset.skeleton.joint(hip).name, "LeftHip");
    }
}

#[test]
fn the_demo_character_shows_every_limb() {
    let demo = rigport_demo::build(1).unwrap().asset;
    let body = find_body(&demo.skeleton, rigport_model::glam::Vec3::Y, None).unwrap();
    assert_eq!(body.limbs(), Limb::ALL.to_vec());
    // Its joints sit at the head of the bone each turns and are named after the bone's end
    // (`shin_l` is at the hip): the structure reads them by position, as its convention.
    for (role, name) in [
        ("LeftUpperLeg", "shin_l"),
        ("LeftFoot", "toe_l"),
        ("RightShoulder", "upper_arm_r"),
        ("RightUpperArm", "forearm_r"),
        ("RightHand", "fingertip_r"),
        ("Chest", "chest"),
        ("Head", "head_top"),
    ] {
        let j = body.joint(role).unwrap();
        assert_eq!(demo.skeleton.joint(j).name, name, "{role}");
    }
}

/// Legs hanging from a pelvis joint below the hips, the spine from the hips: the hips are
/// the hips, the pelvis joint takes no role.
#[test]
fn legs_below_a_pelvis_joint() {
    let original = cgspeed_bvh();
    let legs_start = original.find("JOINT LeftHip").unwrap();
    let legs_end = original.find("JOINT Chest").unwrap();
    let wrapped = format!(
        "{}JOINT Pelvis\n{{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n{}}}\n{}",
        &original[..legs_start],
        &original[legs_start..legs_end],
        &original[legs_end..]
    )
    .replace(&vec!["0"; 57].join(" "), &vec!["0"; 60].join(" "));
    let (plain, pelvis) = (import_bvh(&original), import_bvh(&wrapped));
    let names = |a: &Asset| {
        let body = body_of(a);
        body.roles
            .iter()
            .map(|&(r, j)| (r, a.skeleton.joint(j).name.clone()))
            .collect::<Vec<_>>()
    };
    assert_eq!(names(&pelvis), names(&plain));
    let body = body_of(&pelvis);
    assert_eq!(pelvis.skeleton.joint(body.pelvis).name, "Hips");
}

/// The corpus's human rigs without joint names show every limb: Khronos's RiggedFigure and
/// CesiumMan (glTF nodes without names) besides Pinocchio's `human_model1`.
#[test]
fn unnamed_corpus_rigs_show_every_limb() {
    for rig in [
        HUMAN_MODEL1,
        "5_gltf/khronos_samples__nobuyuki83_delfem2/RiggedFigure.glb",
        "5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb",
    ] {
        let Some(path) = rigport_testkit::corpus(rig) else {
            return;
        };
        let asset = open(&[path]);
        let body = find_body(&asset.skeleton, up_in_model(&asset.frame), None)
            .unwrap_or_else(|| panic!("{rig}: no body"));
        assert_eq!(body.limbs(), Limb::ALL.to_vec(), "{rig}: {body:?}");
        assert_eq!(body.sides, "geometry", "{rig}");
        eprintln!("{rig}: {} roles, sides by {}", body.roles.len(), body.sides);
    }
}
