//! Writes the exporter's test assets as `.glb` and `.gltf` + `.bin` into a directory, for
//! checking with Khronos glTF-Validator:
//!
//! ```text
//! cargo run -p rigport-export --example write_samples -- /tmp/rigport-samples
//! ```
//!
//! Prints each file's exporter warnings.

use std::path::PathBuf;

use rigport_export::{write_gltf, GltfOptions};

#[path = "../src/test_assets.rs"]
mod test_assets;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .ok_or("usage: write_samples <output dir>")?,
    );
    std::fs::create_dir_all(&dir)?;
    let cases = [
        ("rig", test_assets::rig(), 4),
        ("rig_max2", test_assets::rig(), 2),
        ("wide_max4", test_assets::wide_rig(), 4),
        ("wide_max8", test_assets::wide_rig(), 8),
        ("two_roots", test_assets::two_roots(), 4),
        ("big_palette", test_assets::big_palette(), 4),
        ("static_props", test_assets::static_props(), 4),
        ("bones_only", test_assets::bones_only(), 4),
    ];
    for (name, asset, max_influences) in cases {
        let opts = GltfOptions {
            max_influences,
            ..Default::default()
        };
        for ext in ["glb", "gltf"] {
            let path = dir.join(format!("{name}.{ext}"));
            let warnings = write_gltf(&asset, &path, &opts)?;
            println!("{}", path.display());
            for w in warnings {
                println!("  warning: {w}");
            }
        }
    }
    Ok(())
}
