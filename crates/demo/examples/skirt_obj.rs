//! Writes the demo's skirt ([`rigport_demo::skirt::demo_skirt`], 12 rings of 48 vertices,
//! the first ring at the waist; `rigport demo` simulates it into skirt.glb) as an OBJ, for `rigport cloth demo.glb --garment skirt.obj
//! --pin-above 0.99`.
//!
//! `cargo run -p rigport-demo --example skirt_obj -- skirt.obj`

use std::fmt::Write as _;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: skirt_obj OUT.obj")?;
    let demo = rigport_demo::build(1)?;
    let (skirt, _) = rigport_demo::skirt::demo_skirt(&demo.asset);
    let mut text = String::from("# rigport demo skirt (rigport_demo::skirt)\n");
    for p in &skirt.positions {
        writeln!(text, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for t in &skirt.triangles {
        writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    std::fs::write(&path, text)?;
    Ok(())
}
