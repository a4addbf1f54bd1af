//! Issue 15, messages: errors name their file and place, once, with one wording per problem
//! class, and the same asset is refused the same way by every command.

use crate::common::*;

#[test]
fn no_input_is_a_usage_error() {
    let dir = scratch();
    let out = dir.path().join("out.glb");
    for args in [
        vec!["convert", "-o", out.to_str().unwrap()],
        vec!["inspect"],
        vec!["eval", "--out", "x.npz"],
    ] {
        let r = rigport(&args);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains("<INPUTS>"), "{stderr}");
    }
    assert!(!out.exists());
}
