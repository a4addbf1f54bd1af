use std::path::Path;

use rigport_testkit::corpus;

use super::*;
use crate::pinocchio::{self, parse_attachment, parse_skeleton};

const PINOCCHIO: [(&str, &str, &str); 4] = [
    (
        "1_pinocchio/edinburgh_cav_arma2__gpfvic_CAV1/arma2.obj",
        "1_pinocchio/edinburgh_cav_arma2__gpfvic_CAV1/skeleton2.out",
        "1_pinocchio/edinburgh_cav_arma2__gpfvic_CAV1/attachment2.out",
    ),
    (
        "1_pinocchio/berkeley_cs184__icheung_Keepon/keepon/keepon.obj",
        "1_pinocchio/berkeley_cs184__icheung_Keepon/keepon/skeleton.out",
        "1_pinocchio/berkeley_cs184__icheung_Keepon/keepon/attachment.out",
    ),
    (
        "1_pinocchio/berkeley_cs184__icheung_Keepon/armadillo/Armadillo.obj",
        "1_pinocchio/berkeley_cs184__icheung_Keepon/armadillo/skeleton.out",
        "1_pinocchio/berkeley_cs184__icheung_Keepon/armadillo/attachment.out",
    ),
    (
        "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/Model1.obj",
        "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/skeleton.out",
        "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/attachment.out",
    ),
];

fn share(asset: &Asset) -> f64 {
    near_share(asset, &asset.skins[0]).expect("weighted vertices")
}

/// Every corpus rig whose weights were made for its mesh measures near, and no suspect
/// warning comes with it.
#[test]
fn weights_made_for_their_mesh_are_near_their_bones() {
    for (obj, skel, att) in PINOCCHIO {
        let (Some(obj), Some(skel), Some(att)) = (corpus(obj), corpus(skel), corpus(att)) else {
            return;
        };
        let imported = pinocchio::import(&obj, &skel, &att).unwrap();
        let s = share(&imported.asset);
        eprintln!("{}: {:.1}% near", obj.display(), s * 100.0);
        assert!(s >= 0.8, "{}: {s}", obj.display());
        assert!(
            !imported
                .warnings
                .iter()
                .any(|w| matches!(w, Warning::Suspect { .. })),
            "{}",
            obj.display()
        );
    }
    for folder in ["tydia/armadillo", "tydia/hand"] {
        let Some(dir) = corpus(&format!("2_csci520_ik_skinning/{folder}")) else {
            return;
        };
        let rig = crate::csci520::import_folder(&dir).unwrap();
        let s = share(&rig.imported.asset);
        eprintln!("{folder}: {:.1}% near", s * 100.0);
        assert!(s >= 0.8, "{folder}: {s}");
    }
}

/// The Armadillo mesh and skeleton with the human scan's weights (both Pinocchio human
/// skeletons of 17 bones; the scan's rows cut to the Armadillo's 8988 vertices): the
/// import succeeds, and warns that the weights may belong to another mesh.
#[test]
fn another_meshs_weights_are_suspect() {
    let armadillo = "1_pinocchio/berkeley_cs184__icheung_Keepon/armadillo";
    let human = "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1";
    let (Some(obj), Some(skel), Some(att)) = (
        corpus(&format!("{armadillo}/Armadillo.obj")),
        corpus(&format!("{armadillo}/skeleton.out")),
        corpus(&format!("{human}/attachment.out")),
    ) else {
        return;
    };
    let mesh = crate::obj::import(&obj).unwrap().asset.meshes.remove(0);
    let rows = mesh.source_vertex_count();
    let text = std::fs::read_to_string(&att).unwrap();
    let cut: String = text.lines().take(rows).map(|l| format!("{l}\n")).collect();
    let skeleton = parse_skeleton(&std::fs::read_to_string(&skel).unwrap(), &skel).unwrap();
    let joints = skeleton.positions.len();
    let weights = parse_attachment(&cut, Path::new("human_attachment.out"), joints, rows)
        .unwrap()
        .0;
    let imported =
        pinocchio::assemble_attachment("mixed", mesh, &skeleton, None, &weights).unwrap();
    let s = share(&imported.asset);
    eprintln!(
        "Armadillo with the human scan's weights: {:.1}% near",
        s * 100.0
    );
    assert!(s < MIN_NEAR_SHARE, "{s}");
    let suspect: Vec<_> = imported
        .warnings
        .iter()
        .filter(|w| matches!(w, Warning::Suspect { .. }))
        .collect();
    assert_eq!(suspect.len(), 1, "{:?}", imported.warnings);
    assert_eq!(suspect[0].code(), "W005");
    assert!(suspect[0]
        .to_string()
        .contains("may belong to another mesh"));
}
