//! Acceptance 5: the demo needs no input and its output validates clean.

use crate::common::*;

#[test]
fn demo_writes_a_valid_skinned_glb() {
    let dir = scratch();
    let out = dir.path().join("demo-out");
    let stderr = rigport_ok(&["demo", "-o", out.to_str().unwrap()]);
    let glb = out.join("demo.glb");
    assert!(glb.exists(), "no demo.glb; stderr:\n{stderr}");
    assert_valid(&glb);
    let scene = crate::gltf_read::read(&glb);
    assert_eq!(scene.skins.len(), 1);
    assert!(
        scene.skins[0].positions.len() > 2000,
        "{} vertices",
        scene.skins[0].positions.len()
    );
    assert!(scene.skins[0].joints.len() >= 15);
    // Deterministic: a second run writes the same bytes.
    let again = dir.path().join("again");
    rigport_ok(&["demo", "--quiet", "-o", again.to_str().unwrap()]);
    assert_eq!(
        std::fs::read(&glb).unwrap(),
        std::fs::read(again.join("demo.glb")).unwrap()
    );
}
