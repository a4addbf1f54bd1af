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
