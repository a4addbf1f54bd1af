//! The speed of automatic weights (bone heat) on a Pinocchio mesh and skeleton, for
//! BENCHMARKS.md beside Blender's (`benches/bone_heat.sh` runs both):
//!
//! ```text
//! cargo run --release -p rigport-deform --example bone_heat -- MESH.obj SKELETON.out \
//!     [--split N] [--runs R] [--write-obj OUT.obj]
//! ```
//!
//! - `--split N`: cut every triangle into N² (each edge in N, shared by its faces) before
//!   weighting, to make a bigger mesh of the same shape: human_model1's 13,336 vertices
//!   become 120,008 with N = 3. The new vertices lie on the old faces (no smoothing).
//! - `--runs R`: weight R times (default 1); prints each run's wall time and the best.
//! - `--write-obj OUT.obj`: writes the (split) mesh, for Blender's turn on the same one.
//!
//! The bones are rigport's and Pinocchio's: one per joint after the root, from its
//! parent's position to its own. Only `bone_heat` is timed, not reading the files.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rigport_deform::weights::{bone_heat, Bone, HeatOptions};
use rigport_model::glam::Vec3;

/// Cuts each triangle into `n * n`: edge points shared through a map keyed by the edge's
/// ends, one grid of interior points per face.
fn split(positions: &[Vec3], triangles: &[[u32; 3]], n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut points = positions.to_vec();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    let mut out = Vec::with_capacity(triangles.len() * (n * n) as usize);
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        // Grid point (i, j): a + (i / n)(b - a) + (j / n)(c - a), i + j <= n.
        let mut grid = vec![0u32; ((n + 1) * (n + 2) / 2) as usize];
        let at = |i: u32, j: u32| (i * (n + 1) - i * (i.saturating_sub(1)) / 2 + j) as usize;
        // Row i holds n + 1 - i points; the last row's one point ends the grid.
        debug_assert_eq!(at(n, 0) + 1, grid.len());
        for i in 0..=n {
            for j in 0..=n - i {
                let corner = match (i, j) {
                    (0, 0) => Some(t[0]),
                    (i, 0) if i == n => Some(t[1]),
                    (0, j) if j == n => Some(t[2]),
                    _ => None,
                };
                // Which edge the point is on, as (from, to, steps from `from`).
                let edge = match (i, j) {
                    _ if corner.is_some() => None,
                    (i, 0) => Some((t[0], t[1], i)),
                    (0, j) => Some((t[0], t[2], j)),
                    (i, j) if i + j == n => Some((t[1], t[2], j)),
                    _ => None,
                };
                grid[at(i, j)] = match (corner, edge) {
                    (Some(v), _) => v,
                    (None, Some((from, to, step))) => {
                        let key = (from.min(to), from.max(to));
                        let first = *edges.entry(key).or_insert_with(|| {
                            let first = points.len() as u32;
                            let (lo, hi) = (positions[key.0 as usize], positions[key.1 as usize]);
                            points.extend((1..n).map(|s| lo + (hi - lo) * (s as f32 / n as f32)));
                            first
                        });
                        let s = if from < to { step } else { n - step };
                        first + s - 1
                    }
                    (None, None) => {
                        let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                        points.push(a + (b - a) * u + (c - a) * v);
                        points.len() as u32 - 1
                    }
                };
            }
        }
        for i in 0..n {
            for j in 0..n - i {
                out.push([grid[at(i, j)], grid[at(i + 1, j)], grid[at(i, j + 1)]]);
                if i + j + 1 < n {
                    out.push([
                        grid[at(i + 1, j)],
                        grid[at(i + 1, j + 1)],
                        grid[at(i, j + 1)],
                    ]);
                }
            }
        }
    }
    (points, out)
}

fn write_obj(path: &Path, positions: &[Vec3], triangles: &[[u32; 3]]) {
    let mut text = String::new();
    for p in positions {
        let _ = writeln!(text, "v {} {} {}", p.x, p.y, p.z);
    }
    for t in triangles {
        let _ = writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(path, text).expect("writes the OBJ");
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "bone_heat MESH.obj SKELETON.out [--split N] [--runs R] [--write-obj OUT.obj]";
    let (mut files, mut n, mut runs, mut obj_out) = (Vec::new(), 1u32, 1usize, None);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().expect(usage).clone();
        match a.as_str() {
            "--split" => n = value().parse().expect("--split N"),
            "--runs" => runs = value().parse().expect("--runs R"),
            "--write-obj" => obj_out = Some(PathBuf::from(value())),
            _ => files.push(PathBuf::from(a)),
        }
    }
    let [mesh_path, skeleton_path] = files.as_slice() else {
        panic!("{usage}");
    };
    let bytes = std::fs::read(mesh_path).expect("reads the mesh");
    let (mesh, _) = rigport_import::obj::parse(&bytes, mesh_path).expect("an OBJ");
    let text = std::fs::read_to_string(skeleton_path).expect("reads the skeleton");
    let pin = rigport_import::pinocchio::parse_skeleton(&text, skeleton_path).expect("skeleton");
    let bones: Vec<Bone> = (1..pin.positions.len())
        .map(|k| Bone {
            head: pin.positions[pin.parents[k].expect("a parent")],
            tail: pin.positions[k],
        })
        .collect();
    let (positions, triangles) = if n > 1 {
        split(&mesh.positions, &mesh.triangles, n)
    } else {
        (mesh.positions.clone(), mesh.triangles.clone())
    };
    if let Some(path) = &obj_out {
        write_obj(path, &positions, &triangles);
    }
    let mut best = f64::INFINITY;
    for run in 0..runs {
        let start = Instant::now();
        let heat = bone_heat(
            &positions,
            &triangles,
            &bones,
            &HeatOptions::default(),
            &|_, _| {},
        )
        .expect("weights");
        let seconds = start.elapsed().as_secs_f64();
        best = best.min(seconds);
        let sums_to_one = heat
            .rows
            .iter()
            .all(|r| (r.iter().map(|&(_, w)| w).sum::<f32>() - 1.0).abs() < 1e-4);
        println!(
            "run {run}: {} vertices, {} triangles, {} bones: {seconds:.3} s (rows sum to 1: \
             {sums_to_one}; repairs {:?})",
            positions.len(),
            triangles.len(),
            bones.len(),
            heat.repairs
        );
    }
    println!(
        "best of {runs}: {best:.3} s on {} threads",
        rayon::current_num_threads()
    );
}
