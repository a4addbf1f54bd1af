//! Materials, textures, UV sets and names end to end (issue 20): corpus glTF materials and
//! images survive `convert`, an OBJ + `.mtl` + texture made here converts with its
//! texture, a named character hierarchy keeps its node and morph target names, and the
//! Bandai Namco BVHs get no floor-to-hips bone.

use std::path::Path;

use crate::common::*;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Decoded pixels (RGBA8) of an encoded PNG or JPEG.
fn pixels(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    if bytes.starts_with(b"\x89PNG") {
        let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        decoder.set_transformations(png::Transformations::normalize_to_color8());
        let mut reader = decoder.read_info().expect("png header");
        let mut buf = vec![0; reader.output_buffer_size().expect("size")];
        let info = reader.next_frame(&mut buf).expect("png frame");
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    } else {
        use zune_core::bytestream::ZCursor;
        let mut decoder = zune_jpeg::JpegDecoder::new(ZCursor::new(bytes));
        let data = decoder.decode().expect("jpeg");
        let (w, h) = decoder.dimensions().expect("dimensions");
        (w as u32, h as u32, data)
    }
}

/// A glTF file's materials (as JSON) and images (encoded bytes), read with the `gltf`
/// crate; images from buffer views or files beside it.
fn materials_and_images(path: &Path) -> (Vec<serde_json::Value>, Vec<Vec<u8>>) {
    let gltf = gltf::Gltf::open(path).expect("gltf opens");
    let json = serde_json::to_value(gltf.document.as_json()).expect("json");
    let materials = json["materials"].as_array().cloned().unwrap_or_default();
    let mut images = Vec::new();
    for image in gltf.document.images() {
        let bytes = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let blob = gltf.blob.as_ref().expect("GLB BIN chunk");
                blob[view.offset()..view.offset() + view.length()].to_vec()
            }
            gltf::image::Source::Uri { uri, .. } => {
                std::fs::read(path.parent().expect("folder").join(uri)).expect("image file")
            }
        };
        images.push(bytes);
    }
    (materials, images)
}

#[test]
fn corpus_gltf_materials_and_images_survive_convert_to_glb() {
    let dir = scratch();
    let mut checked = 0;
    for rel in GLTF_SAMPLES {
        let Some(src) = corpus(rel) else { continue };
        let (src_materials, src_images) = materials_and_images(&src);
        if src_materials.is_empty() {
            continue;
        }
        for ext in ["glb", "gltf"] {
            let out = dir.path().join(format!("{checked}.{ext}"));
            rigport_ok(&["convert", s(&src), "-o", s(&out), "--quiet"]);
            assert_valid(&out);
            if let Some(v) = validate(&out) {
                let unused_image = v.raw["messages"].as_array().is_some_and(|m| {
                    m.iter().any(|m| {
                        m["code"] == "UNUSED_OBJECT"
                            && m["pointer"]
                                .as_str()
                                .is_some_and(|p| p.starts_with("/images"))
                    })
                });
                assert!(!unused_image, "{rel}: UNUSED_OBJECT for an image");
            }
            let (materials, images) = materials_and_images(&out);
            assert_eq!(
                materials.len(),
                src_materials.len(),
                "{rel}: material count"
            );
            for (a, b) in src_materials.iter().zip(&materials) {
                for key in ["baseColorFactor", "metallicFactor", "roughnessFactor"] {
                    let default = match key {
                        "baseColorFactor" => serde_json::json!([1.0, 1.0, 1.0, 1.0]),
                        _ => serde_json::json!(1.0),
                    };
                    let get = |m: &serde_json::Value| {
                        let v = &m["pbrMetallicRoughness"][key];
                        if v.is_null() {
                            default.clone()
                        } else {
                            v.clone()
                        }
                    };
                    assert_eq!(get(a), get(b), "{rel}: {key}");
                }
                let emissive = |m: &serde_json::Value| {
                    let v = &m["emissiveFactor"];
                    if v.is_null() {
                        serde_json::json!([0.0, 0.0, 0.0])
                    } else {
                        v.clone()
                    }
                };
                assert_eq!(emissive(a), emissive(b), "{rel}: emissiveFactor");
                let textured = |m: &serde_json::Value| {
                    !m["pbrMetallicRoughness"]["baseColorTexture"].is_null()
                };
                assert_eq!(textured(a), textured(b), "{rel}: base colour texture");
            }
            assert_eq!(images.len(), src_images.len(), "{rel}: image count");
            for (a, b) in src_images.iter().zip(&images) {
                let (pa, pb) = (pixels(a), pixels(b));
                assert_eq!((pa.0, pa.1), (pb.0, pb.1), "{rel}: image size");
                assert!(pa.2 == pb.2, "{rel}: image pixels differ");
            }
            checked += 1;
        }
    }
    eprintln!("checked {checked} corpus glTF conversions with materials");
}

/// Writes a 4x4 RGBA PNG: red top half, blue bottom half.
fn write_texture(path: &Path) -> Vec<u8> {
    let mut data = Vec::new();
    for y in 0..4 {
        for _ in 0..4 {
            data.extend_from_slice(if y < 2 {
                &[255, 0, 0, 255]
            } else {
                &[0, 0, 255, 255]
            });
        }
    }
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, 4, 4);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().expect("png header");
        writer.write_image_data(&data).expect("png data");
    }
    std::fs::write(path, &bytes).expect("write png");
    data
}

#[test]
fn obj_with_mtl_and_texture_converts_to_a_textured_glb() {
    let dir = scratch();
    let texels = write_texture(&dir.path().join("skin.png"));
    std::fs::write(
        dir.path().join("quad.mtl"),
        "newmtl skin\nKd 0.8 0.8 0.8\nKs 0 0 0\nNs 10\nmap_Kd skin.png\n",
    )
    .unwrap();
    let obj = dir.path().join("quad.obj");
    std::fs::write(
        &obj,
        "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl skin\nf 1/1 2/2 3/3 4/4\n",
    )
    .unwrap();
    let glb = dir.path().join("quad.glb");
    rigport_ok(&["convert", s(&obj), "-o", s(&glb), "--quiet"]);
    assert_valid(&glb);
    let (materials, images) = materials_and_images(&glb);
    assert_eq!(materials.len(), 1);
    let m = &materials[0];
    assert_eq!(m["name"], "skin");
    assert_eq!(
        m["pbrMetallicRoughness"]["baseColorFactor"],
        serde_json::json!([1.0, 1.0, 1.0, 1.0])
    );
    assert_eq!(m["pbrMetallicRoughness"]["metallicFactor"], 0.0);
    assert!(!m["pbrMetallicRoughness"]["baseColorTexture"].is_null());
    assert_eq!(images.len(), 1);
    assert_eq!(pixels(&images[0]).2, texels, "the texture's pixels");
    let gltf = gltf::Gltf::open(&glb).unwrap();
    let prim = gltf
        .document
        .meshes()
        .next()
        .unwrap()
        .primitives()
        .next()
        .unwrap();
    assert_eq!(prim.material().index(), Some(0));
    assert!(prim.get(&gltf::Semantic::TexCoords(0)).is_some());
    let image = gltf.document.images().next().unwrap();
    assert!(matches!(
        image.source(),
        gltf::image::Source::View {
            mime_type: "image/png",
            ..
        }
    ));

    // three.js (tools/three_eval.mjs, from main) binds the texture to the material's map.
    let three = repo().join("tools/three_eval.mjs");
    let three_ready = three.exists() && repo().join("tools/node_modules/three").exists();
    if require(
        "tools/three_eval.mjs with three installed",
        three_ready.then_some(()),
    )
    .is_some()
    {
        let out = std::process::Command::new("node")
            .arg(&three)
            .arg(&glb)
            .output()
            .expect("node runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
        let map = &report["meshes"][0]["material"]["map"];
        assert_eq!(map["mime_type"], "image/png", "{report:#}");
        assert_eq!(map["texcoord"], 0);
    }

    // `.gltf`: the image is written beside it.
    let split = dir.path().join("out").join("quad.gltf");
    std::fs::create_dir_all(split.parent().unwrap()).unwrap();
    rigport_ok(&["convert", s(&obj), "-o", s(&split), "--quiet"]);
    assert_valid(&split);
    let (_, images) = materials_and_images(&split);
    assert_eq!(pixels(&images[0]).2, texels);

    // The picture shows the texture: red above, blue below.
    let png_out = dir.path().join("quad.png");
    rigport_ok(&[
        "render",
        s(&obj),
        "--size",
        "64x64",
        "-o",
        s(&png_out),
        "--quiet",
    ]);
    let (w, h, rgba) = pixels(&std::fs::read(&png_out).unwrap());
    let at = |x: u32, y: u32| {
        let i = 4 * (y * w + x) as usize;
        [rgba[i], rgba[i + 1], rgba[i + 2]]
    };
    let (top, bottom) = (at(w / 2, h / 3), at(w / 2, 2 * h / 3));
    assert!(top[0] > 100 && top[2] < 40, "top is red: {top:?}");
    assert!(
        bottom[2] > 100 && bottom[0] < 40,
        "bottom is blue: {bottom:?}"
    );
}

/// A character-like glTF: Armature/Hips/Spine/Neck/Head/Face, the face mesh (named
/// `FaceMesh`, on node `Face`) with morph targets `smile` and `blink`.
fn write_named_character(path: &Path) {
    let positions: [f32; 9] = [0.0, 1.6, 0.0, 0.1, 1.6, 0.0, 0.0, 1.7, 0.0];
    let smile: [f32; 9] = [0.0, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let blink: [f32; 9] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -0.01, 0.0];
    let mut bin = Vec::new();
    for v in positions.iter().chain(&smile).chain(&blink) {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let b64 = base64(&bin);
    let node = |name: &str, children: &[u32], t: [f32; 3]| serde_json::json!({"name": name, "children": children, "translation": t});
    let mut nodes = vec![
        node("Armature", &[1], [0.0, 0.0, 0.0]),
        node("Hips", &[2], [0.0, 1.0, 0.0]),
        node("Spine", &[3], [0.0, 0.3, 0.0]),
        node("Neck", &[4], [0.0, 0.2, 0.0]),
        node("Head", &[5], [0.0, 0.1, 0.0]),
    ];
    nodes.push(serde_json::json!({"name": "Face", "mesh": 0}));
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"name": "character", "nodes": [0]}],
        "nodes": nodes,
        "meshes": [{
            "name": "FaceMesh",
            "extras": {"targetNames": ["smile", "blink"]},
            "weights": [0.0, 0.0],
            "primitives": [{
                "attributes": {"POSITION": 0},
                "targets": [{"POSITION": 1}, {"POSITION": 2}]
            }]
        }],
        "buffers": [{"byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{b64}")}],
        "bufferViews": [{"buffer": 0, "byteLength": bin.len()}],
        "accessors": [
            {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 1.6, 0.0], "max": [0.1, 1.7, 0.0]},
            {"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [0.0, 0.01, 0.0]},
            {"bufferView": 0, "byteOffset": 72, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, -0.01, 0.0], "max": [0.0, 0.0, 0.0]}
        ]
    });
    std::fs::write(path, serde_json::to_vec_pretty(&doc).unwrap()).unwrap();
}

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ABC[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The node holding the (only) mesh: its name, its parent chain's names, the mesh's
/// target names.
fn face_of(path: &Path) -> (String, Vec<String>, Vec<String>) {
    let gltf = gltf::Gltf::open(path).unwrap();
    let nodes: Vec<_> = gltf.document.nodes().collect();
    let with_mesh: Vec<_> = nodes.iter().filter(|n| n.mesh().is_some()).collect();
    assert_eq!(with_mesh.len(), 1, "one node holds the mesh");
    let face = with_mesh[0];
    let parent_of = |i: usize| {
        nodes
            .iter()
            .find(|n| n.children().any(|c| c.index() == i))
            .map(|n| n.index())
    };
    let mut chain = Vec::new();
    let mut at = parent_of(face.index());
    while let Some(p) = at {
        chain.push(nodes[p].name().unwrap_or("").to_string());
        at = parent_of(p);
    }
    let mesh = face.mesh().unwrap();
    let extras: serde_json::Value =
        serde_json::from_str(mesh.extras().as_ref().expect("extras").get()).unwrap();
    let targets = extras["targetNames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    (face.name().unwrap_or("").to_string(), chain, targets)
}

#[test]
fn a_deep_named_face_mesh_keeps_its_node_and_target_names() {
    let dir = scratch();
    let src = dir.path().join("character.gltf");
    write_named_character(&src);
    let glb = dir.path().join("character.glb");
    rigport_ok(&["convert", s(&src), "-o", s(&glb), "--quiet"]);
    assert_valid(&glb);
    let (name, chain, targets) = face_of(&glb);
    assert_eq!(name, "Face");
    assert_eq!(chain, ["Head", "Neck", "Spine", "Hips", "Armature"]);
    assert_eq!(targets, ["smile", "blink"]);
    let gltf = gltf::Gltf::open(&glb).unwrap();
    assert_eq!(gltf.document.nodes().count(), 6, "no extra mesh node");
    // Again: a second round trip changes nothing.
    let again = dir.path().join("again.glb");
    rigport_ok(&["convert", s(&glb), "-o", s(&again), "--quiet"]);
    assert_eq!(face_of(&again), face_of(&glb));
    // Through USD and back: the Mesh prim is named after its node, its blend shapes after
    // the morph targets, and both come back.
    let usda = dir.path().join("character.usda");
    rigport_ok(&["convert", s(&glb), "-o", s(&usda), "--quiet"]);
    let back = dir.path().join("back.glb");
    rigport_ok(&["convert", s(&usda), "-o", s(&back), "--quiet"]);
    assert_valid(&back);
    let (name, _, targets) = face_of(&back);
    assert_eq!(name, "Face");
    assert_eq!(
        targets,
        ["smile", "blink"],
        "morph target names through .usda"
    );
}

#[test]
fn bandai_bvh_bone_mesh_has_no_floor_to_hips_bone() {
    let Some(bvh) = corpus("4_bvh/bandai_namco_ds1/dataset-1_walk_normal_002.bvh") else {
        return;
    };
    let dir = scratch();
    let glb = dir.path().join("walk.glb");
    rigport_ok(&["convert", s(&bvh), "-o", s(&glb), "--quiet"]);
    assert_valid(&glb);
    let gltf = gltf::Gltf::open(&glb).unwrap();
    let skin = gltf.document.skins().next().expect("bone mesh skin");
    let palette: Vec<&str> = skin.joints().map(|j| j.name().unwrap_or("")).collect();
    // joint_Root's only child is Hips, whose translation is animated: no bone, so the
    // root drives no vertex and is not in the palette.
    assert!(!palette.contains(&"joint_Root"), "{palette:?}");
    assert!(palette.contains(&"Hips"));
    let png_out = dir.path().join("walk.png");
    rigport_ok(&[
        "render",
        s(&bvh),
        "--size",
        "64x64",
        "-o",
        s(&png_out),
        "--quiet",
    ]);
}

#[test]
fn gltf_to_usda_to_glb_keeps_base_colour_and_textures() {
    let Some(py) = crate::usd::python() else {
        return;
    };
    let dir = scratch();
    let mut checked = 0;
    for rel in GLTF_SAMPLES {
        let Some(src) = corpus(rel) else { continue };
        let (src_materials, src_images) = materials_and_images(&src);
        if src_materials.is_empty() {
            continue;
        }
        let usda = dir.path().join(format!("m{checked}.usda"));
        rigport_ok(&["convert", s(&src), "-o", s(&usda), "--quiet"]);
        let (ok, text) = crate::usd::check_usd(&py, &usda, None);
        assert!(ok, "{rel}: {text}");
        let usda_text = std::fs::read_to_string(&usda).unwrap();
        assert!(
            usda_text.contains("info:id = \"UsdPreviewSurface\""),
            "{rel}"
        );
        assert!(usda_text.contains("rel material:binding"), "{rel}");
        let back = dir.path().join(format!("m{checked}.glb"));
        rigport_ok(&["convert", s(&usda), "-o", s(&back), "--quiet"]);
        assert_valid(&back);
        let (materials, images) = materials_and_images(&back);
        assert_eq!(materials.len(), src_materials.len(), "{rel}");
        for (a, b) in src_materials.iter().zip(&materials) {
            let base = |m: &serde_json::Value| {
                let v = &m["pbrMetallicRoughness"]["baseColorFactor"];
                if v.is_null() {
                    serde_json::json!([1.0, 1.0, 1.0, 1.0])
                } else {
                    v.clone()
                }
            };
            assert_eq!(base(a), base(b), "{rel}: baseColorFactor");
            let textured =
                |m: &serde_json::Value| !m["pbrMetallicRoughness"]["baseColorTexture"].is_null();
            assert_eq!(textured(a), textured(b), "{rel}: base colour texture");
        }
        assert_eq!(images.len(), src_images.len(), "{rel}: images");
        for (a, b) in src_images.iter().zip(&images) {
            assert!(pixels(a) == pixels(b), "{rel}: pixels differ");
        }
        checked += 1;
    }
    eprintln!("checked {checked} glTF -> USD -> glTF material round trips");
}

#[test]
fn a_named_face_mesh_keeps_its_name_through_usda() {
    let dir = scratch();
    let src = dir.path().join("character.gltf");
    write_named_character(&src);
    let usda = dir.path().join("character.usda");
    rigport_ok(&["convert", s(&src), "-o", s(&usda), "--quiet"]);
    let text = std::fs::read_to_string(&usda).unwrap();
    assert!(text.contains("def Mesh \"Face\""), "{text}");
    if let Some(py) = crate::usd::python() {
        let (ok, out) = crate::usd::check_usd(&py, &usda, None);
        assert!(ok, "{out}");
    }
    let back = dir.path().join("back.glb");
    rigport_ok(&["convert", s(&usda), "-o", s(&back), "--quiet"]);
    assert_valid(&back);
    let gltf = gltf::Gltf::open(&back).unwrap();
    let holder = gltf
        .document
        .nodes()
        .find(|n| n.mesh().is_some())
        .expect("a mesh node");
    assert_eq!(holder.name(), Some("Face"));
}
