//! Compact outputs: 16-bit rotation outputs, and `EXT_meshopt_compression` views that
//! decode (with meshoptimizer's own decoder and filters) to what the plain file holds.

use rigport_model::quantize::{rotation_from_i16, rotation_to_i16, rotation_to_i8};
use rigport_model::{Compression, TrackTarget};

use super::*;
use crate::test_assets;

fn export(compact: bool, compression: Compression) -> Vec<u8> {
    let options = GltfOptions {
        compact,
        compression,
        ..Default::default()
    };
    to_glb(&test_assets::rig(), &options).expect("export").glb
}

/// The BIN chunk of a GLB.
fn bin(glb: &[u8]) -> &[u8] {
    let len = u32::from_le_bytes(glb[12..16].try_into().expect("4 bytes")) as usize;
    &glb[20 + len + 8..]
}

/// The bytes of view `v` of the plain file `json` / `bin`.
fn view_bytes<'a>(json: &Value, bin: &'a [u8], v: usize) -> &'a [u8] {
    let view = &json["bufferViews"][v];
    let at = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    &bin[at..at + view["byteLength"].as_u64().expect("length") as usize]
}

#[test]
fn rotation_outputs_are_normalized_shorts_rounded_as_the_reducer_measures() {
    let plain = export(false, Compression::None);
    let short = export(true, Compression::None);
    assert!(short.len() < plain.len());
    let asset = test_assets::rig();
    let mut checked = 0;
    for (track, keys) in written_rotation_keys(&short, &asset) {
        let WrittenKeys::Shorts(keys) = keys else {
            panic!("rotation outputs are not SHORT normalized");
        };
        checked += assert_rounded(&keys, track, rotation_to_i16);
    }
    assert!(checked > 0);
}

/// Rotation outputs as written, by width.
enum WrittenKeys {
    Bytes(Vec<[i8; 4]>),
    Shorts(Vec<[i16; 4]>),
    Other,
}

/// The LINEAR and STEP rotation tracks of `asset` with their outputs in `glb`, the tracks
/// written with all their keys (not constant ones, written with two).
fn written_rotation_keys<'a>(
    glb: &[u8],
    asset: &'a rigport_model::Asset,
) -> Vec<(&'a rigport_model::Track, WrittenKeys)> {
    use gltf::animation::util::Rotations;
    let (doc, buffers) = import(glb);
    let mut out = Vec::new();
    for (animation, clip) in doc.animations().zip(&asset.clips) {
        for channel in animation.channels() {
            let node = channel.target().node().index();
            let track = clip.tracks.iter().find(|t| {
                t.target == TrackTarget::Rotation(rigport_model::JointIndex(node as u32))
            });
            let (Some(track), ReadOutputs::Rotations(rotations)) = (
                track.filter(|t| t.interpolation != rigport_model::Interpolation::CubicSpline),
                channel
                    .reader(|b| Some(&buffers[b.index()]))
                    .read_outputs()
                    .expect("outputs"),
            ) else {
                continue;
            };
            let keys = match rotations {
                Rotations::I8(keys) => WrittenKeys::Bytes(keys.collect()),
                Rotations::I16(keys) => WrittenKeys::Shorts(keys.collect()),
                _ => WrittenKeys::Other,
            };
            let count = match &keys {
                WrittenKeys::Bytes(k) => k.len(),
                WrittenKeys::Shorts(k) => k.len(),
                WrittenKeys::Other => 0,
            };
            if count == track.times.len() {
                out.push((track, keys));
            }
        }
    }
    out
}

/// Asserts that each of `keys` is `encode` of `track`'s key, or its negation (sign
/// continuity); the number of keys checked.
fn assert_rounded<T>(
    keys: &[[T; 4]],
    track: &rigport_model::Track,
    encode: fn([f32; 4]) -> [T; 4],
) -> usize
where
    T: Copy + PartialEq + std::fmt::Debug + std::ops::Neg<Output = T>,
{
    for (k, key) in keys.iter().enumerate() {
        let expected = encode(track.key_value(k).try_into().expect("xyzw"));
        let flipped = expected.map(|c| -c);
        assert!(
            *key == expected || *key == flipped,
            "key {k}: {key:?} vs {expected:?}"
        );
    }
    keys.len()
}

/// Without compression, `rotation_bits` under 16 writes a LINEAR or STEP rotation track's
/// keys as 8-bit normalized components (core glTF's one lower precision), each key rounded
/// as the reducer measures it ([`rotation_to_i8`]); the file stays valid and smaller.
#[test]
fn rotation_bits_under_16_write_bytes_in_core_gltf() {
    let asset = test_assets::rig();
    let export = |rotation_bits: Vec<Vec<u8>>| {
        let options = GltfOptions {
            compact: true,
            rotation_bits,
            ..Default::default()
        };
        to_glb(&asset, &options).expect("export").glb
    };
    let eight: Vec<Vec<u8>> = asset
        .clips
        .iter()
        .map(|c| vec![8; c.tracks.len()])
        .collect();
    let bytes = export(eight);
    assert!(bytes.len() < export(Vec::new()).len());
    assert_khronos_valid(&bytes);
    let mut checked = 0;
    for (track, keys) in written_rotation_keys(&bytes, &asset) {
        let WrittenKeys::Bytes(keys) = keys else {
            panic!("rotation outputs are not BYTE normalized");
        };
        checked += assert_rounded(&keys, track, rotation_to_i8);
    }
    assert!(checked > 0);
}

/// Decodes `count` elements of `stride` bytes (4, 8, 12, 16 or 64).
fn decode_bytes(encoded: &[u8], count: usize, stride: usize) -> Vec<u8> {
    fn rows<T: Clone + Default + AsRef<[u32]>>(encoded: &[u8], count: usize) -> Vec<u8> {
        let rows: Vec<T> = ::meshopt::decode_vertex_buffer(encoded, count).expect("decodes");
        rows.iter()
            .flat_map(|r| {
                r.as_ref()
                    .iter()
                    .flat_map(|w| w.to_le_bytes())
                    .collect::<Vec<u8>>()
            })
            .collect()
    }
    match stride {
        4 => rows::<[u32; 1]>(encoded, count),
        8 => rows::<[u32; 2]>(encoded, count),
        12 => rows::<[u32; 3]>(encoded, count),
        16 => rows::<[u32; 4]>(encoded, count),
        64 => {
            let rows: Vec<[u32; 16]> =
                ::meshopt::decode_vertex_buffer(encoded, count).expect("decodes");
            rows.iter()
                .flatten()
                .flat_map(|w| w.to_le_bytes())
                .collect()
        }
        _ => panic!("stride {stride}"),
    }
}

/// The bytes accessor `a` reads from `json` / `bin` (plain views), `count * size`.
fn accessor_bytes(json: &Value, bin: &[u8], a: usize, size: usize) -> Vec<u8> {
    let accessor = &json["accessors"][a];
    let view = accessor["bufferView"].as_u64().expect("view") as usize;
    let at = accessor["byteOffset"].as_u64().unwrap_or(0) as usize;
    let count = accessor["count"].as_u64().expect("count") as usize;
    view_bytes(json, bin, view)[at..at + count * size].to_vec()
}

#[test]
fn meshopt_views_decode_to_the_plain_files_data() {
    let plain = export(true, Compression::None);
    let packed = export(true, Compression::Meshopt);
    let (pj, mj) = (glb_json(&plain), glb_json(&packed));
    assert!(
        packed.len() < plain.len(),
        "{} vs {}",
        packed.len(),
        plain.len()
    );
    let name = "EXT_meshopt_compression";
    assert_eq!(mj["extensionsRequired"], serde_json::json!([name]));
    assert_eq!(mj["extensionsUsed"], serde_json::json!([name]));
    assert_eq!(mj["buffers"][1]["extensions"][name]["fallback"], true);
    assert!(mj["buffers"][1].get("uri").is_none());
    let accessors = mj["accessors"].as_array().expect("accessors");
    assert_eq!(
        accessors.len(),
        pj["accessors"].as_array().expect("accessors").len()
    );
    let (plain_bin, packed_bin) = (bin(&plain), bin(&packed));
    let mut filters = std::collections::BTreeSet::new();
    for (a, accessor) in accessors.iter().enumerate() {
        let Some(v) = accessor["bufferView"].as_u64().map(|v| v as usize) else {
            continue; // sparse without a base view
        };
        let view = &mj["bufferViews"][v];
        let Some(ext) = view["extensions"].get(name) else {
            let size = view_bytes(&mj, packed_bin, v).len();
            let count = accessor["count"].as_u64().expect("count") as usize;
            let element = size / count.max(1);
            assert_eq!(
                accessor_bytes(&mj, packed_bin, a, element),
                accessor_bytes(&pj, plain_bin, a, element),
                "accessor {a}"
            );
            continue;
        };
        assert_eq!(view["buffer"], 1);
        let at = ext["byteOffset"].as_u64().unwrap_or(0) as usize;
        let encoded = &packed_bin[at..at + ext["byteLength"].as_u64().expect("len") as usize];
        let count = ext["count"].as_u64().expect("count") as usize;
        let stride = ext["byteStride"].as_u64().expect("stride") as usize;
        if ext["mode"] == "TRIANGLES" {
            // Triangle indices through the index codec, decoded to `stride`-byte indices.
            filters.insert("TRIANGLES".to_owned());
            assert!(ext.get("filter").is_none(), "accessor {a}");
            let expected: Vec<u32> = accessor_bytes(&pj, plain_bin, a, stride)
                .chunks_exact(stride)
                .map(|c| match c {
                    [a, b] => u32::from(u16::from_le_bytes([*a, *b])),
                    _ => u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                })
                .collect();
            let decoded: Vec<u32> = match stride {
                2 => ::meshopt::decode_index_buffer::<u16>(encoded, count)
                    .expect("decodes")
                    .into_iter()
                    .map(u32::from)
                    .collect(),
                4 => ::meshopt::decode_index_buffer::<u32>(encoded, count).expect("decodes"),
                _ => panic!("index stride {stride}"),
            };
            // The codec may rotate a triangle's corners (abc -> bca): the same triangle,
            // the same winding.
            assert_eq!(decoded.len(), expected.len(), "accessor {a}");
            for (t, (d, e)) in decoded
                .chunks_exact(3)
                .zip(expected.chunks_exact(3))
                .enumerate()
            {
                let rotations = [[e[0], e[1], e[2]], [e[1], e[2], e[0]], [e[2], e[0], e[1]]];
                assert!(
                    rotations.iter().any(|r| r[..] == d[..]),
                    "accessor {a} triangle {t}: {d:?} vs {e:?}"
                );
            }
            continue;
        }
        assert_eq!(encoded[0], 0xa0, "vertex codec version 0");
        assert_eq!(ext["mode"], "ATTRIBUTES");
        let filter = ext["filter"].as_str().unwrap_or("NONE");
        filters.insert(filter.to_owned());
        let offset = accessor["byteOffset"].as_u64().unwrap_or(0) as usize;
        let n = accessor["count"].as_u64().expect("count") as usize;
        let expected = accessor_bytes(&pj, plain_bin, a, stride);
        match (filter, stride) {
            ("NONE", _) => {
                let all = decode_bytes(encoded, count, stride);
                assert_eq!(
                    all[offset..offset + n * stride],
                    expected[..],
                    "accessor {a}"
                );
            }
            ("QUATERNION", 8) => {
                let mut rows: Vec<[i16; 4]> =
                    ::meshopt::decode_vertex_buffer(encoded, count).expect("decodes");
                ::meshopt::decode_filter_quat(&mut rows);
                let rows = &rows[offset / 8..offset / 8 + n];
                for (k, (row, plain)) in rows.iter().zip(expected.chunks_exact(8)).enumerate() {
                    let plain: [i16; 4] = std::array::from_fn(|c| {
                        i16::from_le_bytes([plain[2 * c], plain[2 * c + 1]])
                    });
                    let (x, y) = (rotation_from_i16(*row), rotation_from_i16(plain));
                    // The same rotation (up to sign) within the 16-bit grid's steps.
                    let near = |s: f32| {
                        x.iter()
                            .zip(&y)
                            .all(|(p, q)| (p - s * q).abs() <= 2.0 / 32767.0)
                    };
                    assert!(
                        near(1.0) || near(-1.0),
                        "accessor {a} key {k}: {x:?} vs {y:?}"
                    );
                }
            }
            ("EXPONENTIAL", 12) => {
                let mut rows: Vec<[u32; 3]> =
                    ::meshopt::decode_vertex_buffer(encoded, count).expect("decodes");
                ::meshopt::decode_filter_exp(&mut rows);
                let rows = &rows[offset / 12..offset / 12 + n];
                for (row, plain) in rows.iter().flatten().zip(expected.chunks_exact(4)) {
                    let (x, y) = (
                        f32::from_bits(*row),
                        f32::from_le_bytes(plain.try_into().expect("4")),
                    );
                    assert!(
                        (x - y).abs() <= y.abs() / (1 << 19) as f32,
                        "accessor {a}: {x} vs {y}"
                    );
                }
            }
            other => panic!("accessor {a}: unexpected {other:?}"),
        }
    }
    assert!(
        ["QUATERNION", "EXPONENTIAL", "TRIANGLES"]
            .iter()
            .all(|f| filters.contains(*f)),
        "{filters:?}"
    );
    // The inverse bind matrices go through the codec too (64-byte elements) when it makes
    // them smaller; else (the test rig's few) they are stored as they are.
    let ibm = mj["skins"][0]["inverseBindMatrices"]
        .as_u64()
        .expect("skin") as usize;
    let view = mj["accessors"][ibm]["bufferView"].as_u64().expect("view") as usize;
    let ext = &mj["bufferViews"][view]["extensions"][name];
    if ext.is_null() {
        let raw = view_bytes(&mj, packed_bin, view);
        let rows: Vec<[u32; 16]> = raw
            .chunks_exact(64)
            .map(|m| {
                std::array::from_fn(|i| {
                    u32::from_le_bytes(m[4 * i..4 * i + 4].try_into().expect("4"))
                })
            })
            .collect();
        // Vertex codec version 0, the one EXT_meshopt_compression reads.
        let encoded = ::meshopt::encode_vertex_buffer_level(&rows, 2, Some(0)).expect("encodes");
        assert!(
            encoded.len() >= raw.len(),
            "{} < {}",
            encoded.len(),
            raw.len()
        );
    } else {
        assert_eq!(ext["byteStride"], 64);
    }
}

/// A view the codec would not make smaller (few key times, few matrices) is written as it
/// is, not through the extension; the file's other views are compressed.
#[test]
fn views_the_codec_would_grow_are_written_plainly() {
    let packed = export(true, Compression::Meshopt);
    let json = glb_json(&packed);
    let name = "EXT_meshopt_compression";
    let views = json["bufferViews"].as_array().expect("views");
    let (compressed, plain): (Vec<_>, Vec<_>) =
        views.iter().partition(|v| !v["extensions"][name].is_null());
    assert!(!compressed.is_empty() && !plain.is_empty(), "{views:?}");
    for v in &compressed {
        let ext = &v["extensions"][name];
        // Unfiltered views only where the codec shrank them.
        if ext.get("filter").is_none() && ext["mode"] == "ATTRIBUTES" {
            assert!(ext["byteLength"].as_u64() < v["byteLength"].as_u64(), "{v}");
        }
    }
    for v in &plain {
        assert_eq!(v["buffer"], 0, "{v}");
    }
}

/// Weights that are exactly `k / 255` (here: every vertex on one joint, as a bone mesh) are
/// normalized bytes in a compact export, read back as the same weights; other weights stay
/// floats.
#[test]
fn exact_weights_are_normalized_bytes_in_compact_exports() {
    let mut asset = test_assets::rig();
    let weights_of = |glb: &[u8]| -> (u64, Vec<[f32; 4]>) {
        let json = glb_json(glb);
        let accessor = json["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"]
            .as_u64()
            .expect("WEIGHTS_0");
        let (doc, buffers) = import(glb);
        let primitive = doc
            .meshes()
            .next()
            .expect("mesh")
            .primitives()
            .next()
            .expect("primitive");
        let reader = primitive.reader(|b| Some(&buffers[b.index()]));
        let weights = reader
            .read_weights(0)
            .expect("weights")
            .into_f32()
            .collect();
        (
            json["accessors"][accessor as usize]["componentType"]
                .as_u64()
                .expect("type"),
            weights,
        )
    };
    let options = |compact| GltfOptions {
        compact,
        ..Default::default()
    };
    // The rig's blended weights are not all k/255: floats either way.
    let blended = to_glb(&asset, &options(true)).expect("export").glb;
    assert_eq!(weights_of(&blended).0, 5126);
    // Every vertex on its nearest palette joint with weight 1.
    let rows: Vec<Vec<rigport_model::Influence>> = asset.skins[0]
        .influences
        .rows()
        .map(|row| {
            let top = row.iter().max_by(|a, b| a.weight.total_cmp(&b.weight));
            top.map(|t| {
                vec![rigport_model::Influence {
                    joint: t.joint,
                    weight: 1.0,
                }]
            })
            .unwrap_or_default()
        })
        .collect();
    asset.skins[0].influences = rigport_model::Influences::from_rows(rows);
    let plain = weights_of(&to_glb(&asset, &options(false)).expect("export").glb);
    let compact = weights_of(&to_glb(&asset, &options(true)).expect("export").glb);
    assert_eq!((plain.0, compact.0), (5126, 5121));
    assert_eq!(plain.1, compact.1);
}

/// `KHR_mesh_quantization`: a skinned mesh's positions as 16-bit integers that its inverse
/// bind matrices decode. Every vertex in every palette joint's bind frame (inverse bind
/// matrix times position, as a skinning reader computes it) is within the grid's bound of
/// the float file's; normals are normalized bytes; the extension is required; the file is
/// smaller and valid.
#[test]
fn quantized_skinned_mesh_decodes_within_the_grid_bound() {
    let asset = rig_without_morphs();
    let export = |quantize_mesh| {
        let options = GltfOptions {
            compact: true,
            quantize_mesh,
            ..Default::default()
        };
        to_glb(&asset, &options).expect("export").glb
    };
    let (plain, quantized) = (export(false), export(true));
    assert!(quantized.len() < plain.len());
    assert_khronos_valid(&quantized);
    let (pj, qj) = (glb_json(&plain), glb_json(&quantized));
    let required = qj["extensionsRequired"].as_array().expect("required");
    assert!(required.iter().any(|e| e == "KHR_mesh_quantization"));
    // Element `k` of accessor `a` as `n` little-endian values read by `read`.
    let element = |json: &Value, glb: &[u8], a: u64, k: usize, n: usize, size: usize| {
        let accessor = &json["accessors"][a as usize];
        let view = &json["bufferViews"][accessor["bufferView"].as_u64().expect("view") as usize];
        let stride = view["byteStride"].as_u64().map_or(n * size, |s| s as usize);
        let at = view["byteOffset"].as_u64().unwrap_or(0) as usize
            + accessor["byteOffset"].as_u64().unwrap_or(0) as usize
            + k * stride;
        bin(glb)[at..at + n * size].to_vec()
    };
    let floats = |bytes: Vec<u8>| -> Vec<f32> {
        bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().expect("4")))
            .collect()
    };
    let attribute = |json: &Value, name: &str| {
        json["meshes"][0]["primitives"][0]["attributes"][name]
            .as_u64()
            .expect("attribute")
    };
    let (p_plain, p_quant) = (attribute(&pj, "POSITION"), attribute(&qj, "POSITION"));
    let normals = &qj["accessors"][attribute(&qj, "NORMAL") as usize];
    assert_eq!(
        (
            normals["componentType"].as_u64(),
            normals["normalized"].as_bool()
        ),
        (Some(5120), Some(true))
    );
    assert_eq!(qj["accessors"][p_quant as usize]["componentType"], 5122);
    let count = pj["accessors"][p_plain as usize]["count"]
        .as_u64()
        .expect("count") as usize;
    let positions: Vec<Vec3> = (0..count)
        .map(|k| Vec3::from_slice(&floats(element(&pj, &plain, p_plain, k, 3, 4))))
        .collect();
    let grid = rigport_model::quantize::PositionGrid::new(&positions).expect("finite");
    let ibm = |json: &Value, glb: &[u8], j: usize| {
        let a = json["skins"][0]["inverseBindMatrices"]
            .as_u64()
            .expect("ibm");
        Mat4::from_cols_slice(&floats(element(json, glb, a, j, 16, 4)))
    };
    let joints = pj["skins"][0]["joints"].as_array().expect("joints").len();
    let mut worst = 0.0f32;
    for (k, p) in positions.iter().enumerate() {
        let q = element(&qj, &quantized, p_quant, k, 3, 2);
        let q: Vec<f32> = q
            .chunks_exact(2)
            .map(|c| f32::from(i16::from_le_bytes([c[0], c[1]])))
            .collect();
        for j in 0..joints {
            let expected = ibm(&pj, &plain, j).transform_point3(*p);
            let decoded = ibm(&qj, &quantized, j).transform_point3(Vec3::from_slice(&q));
            worst = worst.max(decoded.distance(expected));
        }
    }
    assert!(worst <= grid.max_error(), "{worst} > {}", grid.max_error());
    assert!(worst > 0.0, "rounded, not exact");
}

/// CUBICSPLINE rotation outputs in compact exports: 16-bit normalized components (each
/// rounded as it is, tangents too) when every component fits `[-1, 1]`, floats when a
/// tangent (units per second) does not.
#[test]
fn cubic_rotations_are_shorts_only_when_every_tangent_fits() {
    let output_type = |tangent: f32| {
        let mut asset = test_assets::rig();
        let track = rigport_model::Track {
            target: TrackTarget::Rotation(rigport_model::JointIndex(1)),
            interpolation: rigport_model::Interpolation::CubicSpline,
            times: vec![0.0, 1.0],
            values: vec![
                0.0, 0.0, 0.0, 0.0, /**/ 0.0, 0.0, 0.0, 1.0, /**/ 0.0, tangent, 0.0,
                0.0, //
                0.0, tangent, 0.0, 0.0, /**/ 0.0, 0.6, 0.0, 0.8, /**/ 0.0, 0.0, 0.0, 0.0,
            ],
        };
        asset.clips = vec![rigport_model::Clip {
            name: "cubic".into(),
            tracks: vec![track],
        }];
        let options = GltfOptions {
            compact: true,
            ..Default::default()
        };
        let glb = to_glb(&asset, &options).expect("export").glb;
        assert_khronos_valid(&glb);
        let json = glb_json(&glb);
        let output = json["animations"][0]["samplers"][0]["output"]
            .as_u64()
            .expect("output");
        let accessor = &json["accessors"][output as usize];
        let short = (
            accessor["componentType"].as_u64(),
            accessor["normalized"].as_bool(),
        );
        (short, accessor_bytes(&json, bin(&glb), output as usize, 8))
    };
    let ((component, normalized), bytes) = output_type(0.7);
    assert_eq!((component, normalized), (Some(5122), Some(true)));
    // Key 0's out-tangent y: 0.7 rounded on its own (22937 / 32767).
    assert_eq!(
        i16::from_le_bytes([bytes[8 * 2 + 2], bytes[8 * 2 + 3]]),
        22937
    );
    let ((component, _), _) = output_type(1.5);
    assert_eq!(component, Some(5126));
}

/// The bits per component of every key of the `QUATERNION` views of a meshopt export (the
/// filter stores them in each key's fourth component: `2^(bits-1) - 1`, its two low bits
/// the index of the largest component).
fn quaternion_bits(glb: &[u8]) -> Vec<u32> {
    let json = glb_json(glb);
    let packed = bin(glb);
    let mut bits = Vec::new();
    for view in json["bufferViews"].as_array().expect("views") {
        let ext = &view["extensions"]["EXT_meshopt_compression"];
        if ext["filter"] != "QUATERNION" {
            continue;
        }
        let at = ext["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = ext["byteLength"].as_u64().expect("length") as usize;
        let count = ext["count"].as_u64().expect("count") as usize;
        let rows: Vec<[i16; 4]> =
            ::meshopt::decode_vertex_buffer(&packed[at..at + len], count).expect("decodes");
        bits.extend(rows.iter().map(|r| (i32::from(r[3]) | 3).ilog2() + 2));
    }
    bits
}

/// `rotation_bits` sets the filter's precision per track, as the reducer measured it;
/// without it every key has 16 bits.
#[test]
fn meshopt_rotations_are_written_at_the_bits_of_their_track() {
    let asset = test_assets::rig();
    let export = |rotation_bits: Vec<Vec<u8>>| {
        let options = GltfOptions {
            compact: true,
            compression: Compression::Meshopt,
            rotation_bits,
            ..Default::default()
        };
        to_glb(&asset, &options).expect("export").glb
    };
    let default = quaternion_bits(&export(Vec::new()));
    assert!(
        !default.is_empty() && default.iter().all(|&b| b == 16),
        "{default:?}"
    );
    let ten: Vec<Vec<u8>> = asset
        .clips
        .iter()
        .map(|c| vec![10; c.tracks.len()])
        .collect();
    let packed = export(ten);
    let bits = quaternion_bits(&packed);
    assert_eq!(bits.len(), default.len());
    assert!(bits.iter().all(|&b| b == 10), "{bits:?}");
    // Fewer bits, fewer bytes.
    assert!(packed.len() < export(Vec::new()).len());
}

/// With meshopt, a quantized mesh's normals go through the `OCTAHEDRAL` filter (8 bits, as
/// gltfpack writes them) and decode to unit vectors within a few degrees of the mesh's;
/// without it they are 8-bit components, each rounded.
#[test]
fn meshopt_normals_are_octahedral_and_decode_near_the_mesh_normals() {
    let asset = rig_without_morphs();
    let glb = to_glb(
        &asset,
        &GltfOptions {
            compact: true,
            quantize_mesh: true,
            compression: Compression::Meshopt,
            ..Default::default()
        },
    )
    .expect("export")
    .glb;
    assert_khronos_valid(&glb);
    let json = glb_json(&glb);
    let accessor = json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"]
        .as_u64()
        .expect("normals") as usize;
    let acc = &json["accessors"][accessor];
    assert_eq!(
        (acc["componentType"].as_u64(), acc["normalized"].as_bool()),
        (Some(5120), Some(true))
    );
    let view = acc["bufferView"].as_u64().expect("view") as usize;
    let ext = &json["bufferViews"][view]["extensions"]["EXT_meshopt_compression"];
    assert_eq!(
        (ext["filter"].as_str(), ext["byteStride"].as_u64()),
        (Some("OCTAHEDRAL"), Some(4))
    );
    let bin = bin(&glb);
    let at = ext["byteOffset"].as_u64().unwrap_or(0) as usize;
    let encoded = &bin[at..at + ext["byteLength"].as_u64().expect("len") as usize];
    let count = ext["count"].as_u64().expect("count") as usize;
    let mut rows: Vec<[i8; 4]> = ::meshopt::decode_vertex_buffer(encoded, count).expect("decodes");
    ::meshopt::decode_filter_oct(&mut rows);
    let mesh = &asset.meshes[0];
    let normals = mesh
        .normals
        .clone()
        .unwrap_or_else(|| mesh.compute_normals());
    assert_eq!(rows.len(), normals.len());
    for (row, n) in rows.iter().zip(&normals) {
        let read = glam::Vec3::new(row[0] as f32, row[1] as f32, row[2] as f32) / 127.0;
        // 8-bit octahedral: within about 1.5 degrees (cos 0.9995).
        assert!(
            read.normalize().dot(n.normalize()) > 0.9995,
            "{read} vs {n}"
        );
    }
}

/// The test rig without its morph targets (and their weight tracks): the writer quantizes
/// skinned meshes without morph targets.
fn rig_without_morphs() -> rigport_model::Asset {
    let mut asset = test_assets::rig();
    asset.meshes[0].morph_targets.clear();
    asset.meshes[0].morph_weights.clear();
    for clip in &mut asset.clips {
        clip.tracks
            .retain(|t| !matches!(t.target, TrackTarget::MorphWeights(m) if m.get() == 0));
    }
    asset
}

/// A compact export writes whole numbers as integers (`0`, not `0.0`), the same numbers
/// the plain export writes: every node's transform reads back equal.
#[test]
fn compact_json_writes_whole_numbers_as_integers() {
    let (plain, compact) = (
        export(false, Compression::None),
        export(true, Compression::None),
    );
    let text = |glb: &[u8]| {
        let len = u32::from_le_bytes(glb[12..16].try_into().expect("4 bytes")) as usize;
        String::from_utf8(glb[20..20 + len].to_vec()).expect("utf-8")
    };
    // Number tokens outside strings that are whole floats (`12.0`, `-0.0`).
    let whole_floats = |t: &str| -> usize {
        let (mut count, mut in_string, mut escaped, mut token) = (0, false, false, String::new());
        for c in t.chars() {
            if in_string {
                (escaped, in_string) = (c == '\\' && !escaped, c != '"' || escaped);
                continue;
            }
            if c.is_ascii_digit() || matches!(c, '-' | '.' | 'e' | 'E' | '+') {
                token.push(c);
                continue;
            }
            let digits = token.trim_start_matches('-');
            if let Some(whole) = digits.strip_suffix(".0") {
                count +=
                    usize::from(!whole.is_empty() && whole.bytes().all(|b| b.is_ascii_digit()));
            }
            token.clear();
            in_string = c == '"';
        }
        count
    };
    assert!(
        whole_floats(&text(&plain)) > 0,
        "the plain export has whole floats"
    );
    assert_eq!(whole_floats(&text(&compact)), 0);
    let (pj, cj) = (glb_json(&plain), glb_json(&compact));
    let numbers = |v: &Value| -> Vec<f64> {
        v.as_array()
            .map(|a| a.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default()
    };
    let nodes = pj["nodes"].as_array().expect("nodes");
    for (n, node) in nodes.iter().enumerate() {
        for key in ["translation", "rotation", "scale"] {
            assert_eq!(
                numbers(&node[key]),
                numbers(&cj["nodes"][n][key]),
                "node {n} {key}"
            );
        }
    }
}
