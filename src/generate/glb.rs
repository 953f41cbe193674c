//! Writing a [`Model`] as binary glTF 2.0: one skinned mesh, its skeleton nodes, the skin, every
//! clip (with its ground speed in the animation's `extras`) and the base colour texture as an
//! embedded PNG. The output is a pure function of the model, byte for byte, so committed assets
//! can be checked against their generator.

use crate::model::{ChannelTarget, Interpolation, Model, SkinnedMesh};
use serde_json::{Value, json};
use std::borrow::Cow;

const FLOAT: u32 = 5126;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    fn accessor(
        &mut self,
        bytes: &[u8],
        target: Option<u32>,
        component: u32,
        count: usize,
        kind: &str,
        min_max: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        let view = self.view(bytes, target);
        let mut a =
            json!({"bufferView": view, "componentType": component, "count": count, "type": kind});
        if let Some((lo, hi)) = min_max {
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn floats(
        &mut self,
        data: &[f32],
        width: usize,
        kind: &str,
        bounds: bool,
        target: Option<u32>,
    ) -> usize {
        let count = data.len() / width;
        let min_max = bounds.then(|| {
            let mut lo = vec![f32::MAX; width];
            let mut hi = vec![f32::MIN; width];
            for row in data.chunks_exact(width) {
                for k in 0..width {
                    lo[k] = lo[k].min(row[k]);
                    hi[k] = hi[k].max(row[k]);
                }
            }
            (lo, hi)
        });
        self.accessor(
            bytemuck::cast_slice(data),
            target,
            FLOAT,
            count,
            kind,
            min_max,
        )
    }
}

fn png(image: &crate::model::Rgba8Image) -> Vec<u8> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new_with_quality(
        &mut out,
        image::codecs::png::CompressionType::Best,
        image::codecs::png::FilterType::Adaptive,
    )
    .write_image(
        &image.pixels,
        image.width,
        image.height,
        image::ExtendedColorType::Rgba8,
    )
    .expect("encoding a PNG into memory cannot fail");
    out
}

/// Positions, normals, texture coordinates and joint/weight sets of the vertices `used`.
/// A mesh whose texture coordinates are all zero has none, and is written without
/// `TEXCOORD_0`, as a file without texture coordinates reads back.
fn vertex_attributes(b: &mut Builder, mesh: &SkinnedMesh, used: &[usize]) -> Value {
    let positions: Vec<f32> = used
        .iter()
        .flat_map(|&v| mesh.positions[v].to_array())
        .collect();
    let normals: Vec<f32> = used
        .iter()
        .flat_map(|&v| mesh.normals[v].to_array())
        .collect();
    let uvs: Vec<f32> = used.iter().flat_map(|&v| mesh.uvs[v].to_array()).collect();
    let pos = b.floats(&positions, 3, "VEC3", true, Some(ARRAY_BUFFER));
    let nrm = b.floats(&normals, 3, "VEC3", false, Some(ARRAY_BUFFER));
    let mut attributes = json!({"POSITION": pos, "NORMAL": nrm});
    if mesh.uvs.iter().any(|&u| u != glam::Vec2::ZERO) {
        let tex = b.floats(&uvs, 2, "VEC2", false, Some(ARRAY_BUFFER));
        attributes["TEXCOORD_0"] = json!(tex);
    }
    let most = used
        .iter()
        .map(|&v| mesh.influences_of(v).len())
        .max()
        .unwrap_or(1)
        .max(1);
    for set in 0..most.div_ceil(4) {
        let mut joints: Vec<u16> = Vec::with_capacity(used.len() * 4);
        let mut weights: Vec<f32> = Vec::with_capacity(used.len() * 4);
        for &v in used {
            let inf = mesh.influences_of(v);
            for k in 4 * set..4 * set + 4 {
                match inf.get(k) {
                    Some(i) => {
                        joints.push(i.bone as u16);
                        weights.push(i.weight);
                    }
                    None => {
                        joints.push(0);
                        weights.push(0.0);
                    }
                }
            }
        }
        let j = b.accessor(
            bytemuck::cast_slice(&joints),
            Some(ARRAY_BUFFER),
            UNSIGNED_SHORT,
            used.len(),
            "VEC4",
            None,
        );
        let w = b.floats(&weights, 4, "VEC4", false, Some(ARRAY_BUFFER));
        attributes[format!("JOINTS_{set}")] = json!(j);
        attributes[format!("WEIGHTS_{set}")] = json!(w);
    }
    attributes
}

/// Encodes `model` as a `.glb` file.
pub fn to_glb(model: &Model) -> Vec<u8> {
    let mut b = Builder::default();
    let mesh = &model.mesh;
    let skel = &model.skeleton;

    // One primitive per material, each with the vertices it uses (in order), so that an
    // importer merging primitives in order gets the mesh back as it was.
    let mut primitives = Vec::new();
    for material in 0..model.materials.len().max(1) {
        let used: Vec<usize> = (0..mesh.vertex_count())
            .filter(|&v| mesh.materials.get(v).copied().unwrap_or(0) as usize == material)
            .collect();
        if used.is_empty() {
            continue;
        }
        let mut local = vec![u32::MAX; mesh.vertex_count()];
        for (i, &v) in used.iter().enumerate() {
            local[v] = i as u32;
        }
        let indices: Vec<u32> = mesh
            .indices
            .chunks_exact(3)
            .filter(|t| local[t[0] as usize] != u32::MAX)
            .flat_map(|t| t.iter().map(|&i| local[i as usize]))
            .collect();
        let attributes = vertex_attributes(&mut b, mesh, &used);
        let indices = b.accessor(
            bytemuck::cast_slice(&indices),
            Some(ELEMENT_ARRAY_BUFFER),
            UNSIGNED_INT,
            indices.len(),
            "SCALAR",
            None,
        );
        primitives
            .push(json!({"attributes": attributes, "indices": indices, "material": material}));
    }

    // Materials and textures.
    let mut images = Vec::new();
    let mut textures = Vec::new();
    let mut materials = Vec::new();
    for m in &model.materials {
        let mut pbr =
            json!({"baseColorFactor": m.base_color, "metallicFactor": 0.0, "roughnessFactor": 0.9});
        if let Some(t) = &m.texture {
            let view = b.view(&png(t), None);
            images.push(json!({"bufferView": view, "mimeType": "image/png"}));
            textures.push(json!({"source": images.len() - 1, "sampler": 0}));
            pbr["baseColorTexture"] = json!({"index": textures.len() - 1});
        }
        materials.push(json!({"name": m.name, "pbrMetallicRoughness": pbr}));
    }

    // Skeleton nodes, then the mesh node.
    let mut nodes: Vec<Value> = skel
        .nodes
        .iter()
        .map(|n| {
            let mut v = json!({"name": n.name});
            if n.rest.translation != glam::Vec3::ZERO {
                v["translation"] = json!(n.rest.translation.to_array());
            }
            if n.rest.rotation != glam::Quat::IDENTITY {
                v["rotation"] = json!(n.rest.rotation.to_array());
            }
            if n.rest.scale != glam::Vec3::ONE {
                v["scale"] = json!(n.rest.scale.to_array());
            }
            v
        })
        .collect();
    for (i, n) in skel.nodes.iter().enumerate() {
        if let Some(p) = n.parent {
            let children = nodes[p as usize]
                .as_object_mut()
                .expect("object")
                .entry("children")
                .or_insert_with(|| json!([]));
            children.as_array_mut().expect("array").push(json!(i));
        }
    }
    let mesh_node = nodes.len();
    nodes.push(json!({"name": model.name, "mesh": 0, "skin": 0}));
    let mut roots: Vec<usize> = (0..skel.nodes.len())
        .filter(|&i| skel.nodes[i].parent.is_none())
        .collect();
    roots.push(mesh_node);

    let ibm: Vec<f32> = skel
        .inverse_bind
        .iter()
        .flat_map(|m| m.to_cols_array())
        .collect();
    let ibm = b.floats(&ibm, 16, "MAT4", false, None);
    let skin = json!({"joints": skel.joints, "inverseBindMatrices": ibm, "skeleton": roots[0]});

    // Clips.
    let mut animations = Vec::new();
    for clip in &model.clips {
        let mut channels = Vec::new();
        let mut samplers = Vec::new();
        for ch in &clip.channels {
            let input = b.floats(&ch.times, 1, "SCALAR", true, None);
            let (kind, width) = match ch.target {
                ChannelTarget::Rotation => ("VEC4", 4),
                _ => ("VEC3", 3),
            };
            let values: Vec<f32> = ch
                .values
                .iter()
                .flat_map(|v| v.to_array()[..width].to_vec())
                .collect();
            let output = b.floats(&values, width, kind, false, None);
            let interpolation = match ch.interpolation {
                Interpolation::Step => "STEP",
                Interpolation::Linear => "LINEAR",
                Interpolation::CubicSpline => "CUBICSPLINE",
            };
            samplers
                .push(json!({"input": input, "output": output, "interpolation": interpolation}));
            let path = match ch.target {
                ChannelTarget::Translation => "translation",
                ChannelTarget::Rotation => "rotation",
                ChannelTarget::Scale => "scale",
            };
            channels.push(
                json!({"sampler": samplers.len() - 1, "target": {"node": ch.node, "path": path}}),
            );
        }
        animations.push(json!({
            "name": clip.name,
            "channels": channels,
            "samplers": samplers,
            "extras": {"ground_speed": clip.ground_speed},
        }));
    }

    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "lodlab gen-assets"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [{"name": model.name, "primitives": primitives}],
        "materials": materials,
        "skins": [skin],
        "animations": animations,
    });
    if !images.is_empty() {
        doc["images"] = json!(images);
        doc["textures"] = json!(textures);
        // Linear filtering with trilinear mipmaps, repeat wrapping.
        doc["samplers"] = json!([{"magFilter": 9729, "minFilter": 9987}]);
    }
    while !b.bin.len().is_multiple_of(4) {
        b.bin.push(0);
    }
    doc["accessors"] = json!(b.accessors);
    doc["bufferViews"] = json!(b.views);
    doc["buffers"] = json!([{"byteLength": b.bin.len()}]);

    let mut json_bytes = serde_json::to_vec(&doc).expect("serialising JSON into memory");
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: (12 + 8 + json_bytes.len() + 8 + b.bin.len()) as u32,
        },
        json: Cow::Owned(json_bytes),
        bin: Some(Cow::Owned(b.bin)),
    };
    glb.to_vec().expect("writing a GLB into memory")
}
