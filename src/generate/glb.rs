//! Writing a [`Model`] as binary glTF 2.0: one skinned mesh, its skeleton nodes, the skin, every
//! clip (with its ground speed in the animation's `extras`) and the base colour texture as an
//! embedded PNG. The output is a pure function of the model, byte for byte, so committed assets
//! can be checked against their generator.
//!
//! [`to_lod_glb`] writes several meshes of one model (its levels of detail) into one file: one
//! node per level, all bound to the one skin, the finest carrying `MSFT_lod` with the others'
//! node indices and `MSFT_screencoverage` in its `extras` (Microsoft's vendor extension; most
//! engines read it through a little code of their own, docs/commands.md says how).

use crate::model::{AlphaMode, ChannelTarget, Clip, Interpolation, Material, Model, SkinnedMesh};
use gltf::json::accessor::{ComponentType, GenericComponentType, Type};
use gltf::json::validation::{Checked::Valid, USize64};
use gltf::json::{self as gj, Index};
use std::borrow::Cow;
use std::collections::BTreeMap;

/// The binary chunk and the buffer views and accessors into it, built up in the order the
/// model is written.
#[derive(Default)]
pub(crate) struct Builder {
    pub(crate) bin: Vec<u8>,
    pub(crate) views: Vec<gj::buffer::View>,
    pub(crate) accessors: Vec<gj::Accessor>,
}

impl Builder {
    pub(crate) fn view(
        &mut self,
        bytes: &[u8],
        target: Option<gj::buffer::Target>,
    ) -> Index<gj::buffer::View> {
        // Every view starts on a 4-byte boundary, as accessors of 4-byte components need.
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let view = gj::buffer::View {
            buffer: Index::new(0),
            byte_length: bytes.len().into(),
            byte_offset: Some(self.bin.len().into()),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: None,
        };
        self.bin.extend_from_slice(bytes);
        Index::push(&mut self.views, view)
    }

    pub(crate) fn accessor(
        &mut self,
        bytes: &[u8],
        target: Option<gj::buffer::Target>,
        component: ComponentType,
        count: usize,
        kind: Type,
        min_max: Option<(Vec<f32>, Vec<f32>)>,
    ) -> Index<gj::Accessor> {
        let view = self.view(bytes, target);
        let (min, max) = match min_max {
            Some((lo, hi)) => (Some(lo.into()), Some(hi.into())),
            None => (None, None),
        };
        let accessor = gj::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: Valid(kind),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        };
        Index::push(&mut self.accessors, accessor)
    }

    pub(crate) fn floats(
        &mut self,
        data: &[f32],
        kind: Type,
        bounds: bool,
        target: Option<gj::buffer::Target>,
    ) -> Index<gj::Accessor> {
        let width = kind.multiplicity();
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
            ComponentType::F32,
            count,
            kind,
            min_max,
        )
    }
}

/// The `extras` object of a glTF property, from any serialisable value.
pub(crate) fn extras(value: serde_json::Value) -> gj::Extras {
    Some(serde_json::value::to_raw_value(&value).expect("a JSON value serialises"))
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

pub(crate) type Attributes =
    BTreeMap<gj::validation::Checked<gj::mesh::Semantic>, Index<gj::Accessor>>;

/// What a file may carry beyond its model: a tangent-space normal map for some materials
/// (linear RGB, glTF's `normalTexture`; one entry a material, or none at all) and, for each
/// mesh written, a tangent a vertex (glTF's `TANGENT`, xyz unit and w the handedness), written
/// for the primitives whose material has a normal map. A billboard cloud's atlas lighting goes
/// out this way (`lodlab export TREE`).
#[derive(Clone, Debug, Default)]
pub struct Extra {
    pub normal_maps: Vec<Option<crate::model::Rgba8Image>>,
    pub tangents: Vec<Vec<glam::Vec4>>,
}

impl Extra {
    fn normal_map(&self, material: usize) -> Option<&crate::model::Rgba8Image> {
        self.normal_maps.get(material)?.as_ref()
    }
}

/// Positions, normals, texture coordinates and joint/weight sets of the vertices `used`.
/// A mesh whose texture coordinates are all zero has none, and is written without
/// `TEXCOORD_0`, as a file without texture coordinates reads back; a mesh without influences (an
/// unskinned part) has no joint or weight sets.
pub(crate) fn vertex_attributes(b: &mut Builder, mesh: &SkinnedMesh, used: &[usize]) -> Attributes {
    use gj::buffer::Target::ArrayBuffer;
    use gj::mesh::Semantic;
    let gather =
        |f: &dyn Fn(usize) -> Vec<f32>| -> Vec<f32> { used.iter().flat_map(|&v| f(v)).collect() };
    let positions = gather(&|v| mesh.positions[v].to_array().to_vec());
    let normals = gather(&|v| mesh.normals[v].to_array().to_vec());
    let mut attributes = Attributes::new();
    attributes.insert(
        Valid(Semantic::Positions),
        b.floats(&positions, Type::Vec3, true, Some(ArrayBuffer)),
    );
    attributes.insert(
        Valid(Semantic::Normals),
        b.floats(&normals, Type::Vec3, false, Some(ArrayBuffer)),
    );
    if mesh.uvs.iter().any(|&u| u != glam::Vec2::ZERO) {
        let uvs = gather(&|v| mesh.uvs[v].to_array().to_vec());
        attributes.insert(
            Valid(Semantic::TexCoords(0)),
            b.floats(&uvs, Type::Vec2, false, Some(ArrayBuffer)),
        );
    }
    if mesh.influences.is_empty() {
        // An unskinned part: no weight sets.
        return attributes;
    }
    let most = used
        .iter()
        .map(|&v| mesh.influences_of(v).len())
        .max()
        .unwrap_or(1)
        .max(1);
    // Four influences per set; the last set is padded with zero weights on joint 0.
    for set in 0..most.div_ceil(4) {
        let mut joints: Vec<u16> = Vec::with_capacity(used.len() * 4);
        let mut weights: Vec<f32> = Vec::with_capacity(used.len() * 4);
        for &v in used {
            let inf = mesh.influences_of(v);
            for k in 4 * set..4 * set + 4 {
                let (joint, weight) = inf.get(k).map_or((0, 0.0), |i| (i.bone as u16, i.weight));
                joints.push(joint);
                weights.push(weight);
            }
        }
        let j = b.accessor(
            bytemuck::cast_slice(&joints),
            Some(ArrayBuffer),
            ComponentType::U16,
            used.len(),
            Type::Vec4,
            None,
        );
        let w = b.floats(&weights, Type::Vec4, false, Some(ArrayBuffer));
        attributes.insert(Valid(Semantic::Joints(set as u32)), j);
        attributes.insert(Valid(Semantic::Weights(set as u32)), w);
    }
    attributes
}

/// One primitive per material, each with the vertices its triangles use (in order of the
/// vertices), so that an importer merging primitives in order gets the mesh back as it was. A
/// triangle is in the primitive of its first corner's material, the vertex the renderer takes
/// a triangle's material from (its provoking vertex): a simplified mesh can join corners of two
/// materials in one triangle, and such a corner is then written in both primitives. A
/// material no triangle uses gets no primitive.
fn primitives(
    b: &mut Builder,
    mesh: &SkinnedMesh,
    materials: usize,
    extra: &Extra,
    tangents: Option<&[glam::Vec4]>,
) -> Vec<gj::mesh::Primitive> {
    let material_of = |v: u32| mesh.materials.get(v as usize).copied().unwrap_or(0) as usize;
    let mut primitives = Vec::new();
    for material in 0..materials.max(1) {
        let triangles: Vec<&[u32]> = mesh
            .indices
            .chunks_exact(3)
            .filter(|t| material_of(t[0]).min(materials.max(1) - 1) == material)
            .collect();
        if triangles.is_empty() {
            continue;
        }
        let mut in_use = vec![false; mesh.vertex_count()];
        triangles
            .iter()
            .flat_map(|t| t.iter())
            .for_each(|&v| in_use[v as usize] = true);
        let used: Vec<usize> = (0..mesh.vertex_count()).filter(|&v| in_use[v]).collect();
        let mut local = vec![u32::MAX; mesh.vertex_count()];
        for (i, &v) in used.iter().enumerate() {
            local[v] = i as u32;
        }
        let indices: Vec<u32> = triangles
            .iter()
            .flat_map(|t| t.iter().map(|&i| local[i as usize]))
            .collect();
        let mut attributes = vertex_attributes(b, mesh, &used);
        if let Some(tangents) = tangents
            && tangents.len() == mesh.vertex_count()
            && extra.normal_map(material).is_some()
        {
            let t: Vec<f32> = used.iter().flat_map(|&v| tangents[v].to_array()).collect();
            attributes.insert(
                Valid(gj::mesh::Semantic::Tangents),
                b.floats(&t, Type::Vec4, false, Some(gj::buffer::Target::ArrayBuffer)),
            );
        }
        let indices = b.accessor(
            bytemuck::cast_slice(&indices),
            Some(gj::buffer::Target::ElementArrayBuffer),
            ComponentType::U32,
            indices.len(),
            Type::Scalar,
            None,
        );
        primitives.push(gj::mesh::Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: Some(indices),
            material: (materials > 0).then(|| Index::new(material as u32)),
            mode: Valid(gj::mesh::Mode::Triangles),
            targets: None,
        });
    }
    primitives
}

/// Materials, with each base colour texture embedded as a PNG in the binary chunk.
pub(crate) fn materials(b: &mut Builder, materials: &[Material], root: &mut gj::Root) {
    materials_with(b, materials, &Extra::default(), root);
}

/// [`materials`], each with its normal map from `extra` where it has one.
fn materials_with(b: &mut Builder, materials: &[Material], extra: &Extra, root: &mut gj::Root) {
    for (k, m) in materials.iter().enumerate() {
        let mut pbr = gj::material::PbrMetallicRoughness {
            base_color_factor: gj::material::PbrBaseColorFactor(m.base_color),
            metallic_factor: gj::material::StrengthFactor(0.0),
            roughness_factor: gj::material::StrengthFactor(0.9),
            ..Default::default()
        };
        if let Some(t) = &m.texture {
            let texture = embedded_texture(b, root, t);
            pbr.base_color_texture = Some(gj::texture::Info {
                index: texture,
                tex_coord: 0,
                extensions: None,
                extras: None,
            });
        }
        let alpha_mode = match m.alpha_mode {
            AlphaMode::Opaque => gj::material::AlphaMode::Opaque,
            AlphaMode::Mask => gj::material::AlphaMode::Mask,
            AlphaMode::Blend => gj::material::AlphaMode::Blend,
        };
        let normal_texture = extra
            .normal_map(k)
            .map(|image| gj::material::NormalTexture {
                index: embedded_texture(b, root, image),
                scale: 1.0,
                tex_coord: 0,
                extensions: None,
                extras: None,
            });
        root.push(gj::Material {
            name: Some(m.name.clone()),
            pbr_metallic_roughness: pbr,
            normal_texture,
            alpha_mode: Valid(alpha_mode),
            alpha_cutoff: (m.alpha_mode == AlphaMode::Mask)
                .then_some(gj::material::AlphaCutoff(m.alpha_cutoff)),
            double_sided: m.double_sided,
            ..Default::default()
        });
    }
}

/// `image` embedded as a PNG in the binary chunk, as a texture with the file's one sampler
/// (linear, trilinear mipmaps, repeat; added with the first texture).
pub(crate) fn embedded_texture(
    b: &mut Builder,
    root: &mut gj::Root,
    image: &crate::model::Rgba8Image,
) -> Index<gj::Texture> {
    if root.samplers.is_empty() {
        root.push(gj::texture::Sampler {
            mag_filter: Some(Valid(gj::texture::MagFilter::Linear)),
            min_filter: Some(Valid(gj::texture::MinFilter::LinearMipmapLinear)),
            ..Default::default()
        });
    }
    let view = b.view(&png(image), None);
    let image = root.push(gj::Image {
        buffer_view: Some(view),
        mime_type: Some(gj::image::MimeType("image/png".into())),
        name: None,
        uri: None,
        extensions: None,
        extras: None,
    });
    root.push(gj::Texture {
        name: None,
        sampler: Some(Index::new(0)),
        source: image,
        extensions: None,
        extras: None,
    })
}

/// The skeleton's nodes (rest transforms and children), a node for each of `meshes` meshes
/// (bound to the skin), the skin and the scene whose roots are the skeleton's roots and the
/// first mesh's node (every mesh's node where `all_in_scene`). Returns the meshes' nodes.
fn skeleton(
    b: &mut Builder,
    model: &Model,
    root: &mut gj::Root,
    meshes: usize,
    all_in_scene: bool,
) -> Vec<Index<gj::Node>> {
    let skel = &model.skeleton;
    let mut nodes: Vec<gj::Node> = skel
        .nodes
        .iter()
        .map(|n| gj::Node {
            name: Some(n.name.clone()),
            translation: (n.rest.translation != glam::Vec3::ZERO)
                .then(|| n.rest.translation.to_array()),
            rotation: (n.rest.rotation != glam::Quat::IDENTITY)
                .then(|| gj::scene::UnitQuaternion(n.rest.rotation.to_array())),
            scale: (n.rest.scale != glam::Vec3::ONE).then(|| n.rest.scale.to_array()),
            ..Default::default()
        })
        .collect();
    for (i, n) in skel.nodes.iter().enumerate() {
        if let Some(p) = n.parent {
            nodes[p as usize]
                .children
                .get_or_insert_with(Vec::new)
                .push(Index::new(i as u32));
        }
    }
    let mesh_nodes: Vec<Index<gj::Node>> = (0..meshes)
        .map(|k| {
            Index::push(
                &mut nodes,
                gj::Node {
                    name: Some(if meshes == 1 {
                        model.name.clone()
                    } else {
                        format!("{}_LOD{k}", model.name)
                    }),
                    mesh: Some(Index::new(k as u32)),
                    skin: Some(Index::new(0)),
                    ..Default::default()
                },
            )
        })
        .collect();
    let mut roots: Vec<Index<gj::Node>> = (0..skel.nodes.len())
        .filter(|&i| skel.nodes[i].parent.is_none())
        .map(|i| Index::new(i as u32))
        .collect();
    // glTF asks the joints for one common root, and the skin's `skeleton` to be it (or above
    // it). A skeleton of several trees (a part riding on a node of its own beside the
    // armature) gets one, which moves nothing.
    if roots.len() > 1 {
        let common = Index::push(
            &mut nodes,
            gj::Node {
                name: Some("skeleton".into()),
                children: Some(roots.clone()),
                ..Default::default()
            },
        );
        roots = vec![common];
    }
    let shown = if all_in_scene { meshes } else { 1 };
    roots.extend(mesh_nodes.iter().take(shown).copied());
    // glTF lists a node once a skin. A node that is two bones (bound two ways by two skins
    // of the file read, which the import could not merge) keeps its first; each other bone on
    // it gets a child node of its own, untransformed, which moves as the node does.
    let mut seen = std::collections::HashSet::new();
    let mut joints: Vec<Index<gj::Node>> = Vec::with_capacity(skel.joints.len());
    for (bone, &j) in skel.joints.iter().enumerate() {
        if seen.insert(j) {
            joints.push(Index::new(j));
            continue;
        }
        let twin = Index::push(
            &mut nodes,
            gj::Node {
                name: Some(format!("{}_bone{bone}", skel.nodes[j as usize].name)),
                ..Default::default()
            },
        );
        nodes[j as usize]
            .children
            .get_or_insert_with(Vec::new)
            .push(twin);
        joints.push(twin);
    }
    root.nodes = nodes;

    let ibm: Vec<f32> = skel
        .inverse_bind
        .iter()
        .flat_map(|m| m.to_cols_array())
        .collect();
    let ibm = b.floats(&ibm, Type::Mat4, false, None);
    root.push(gj::Skin {
        extensions: None,
        extras: None,
        inverse_bind_matrices: Some(ibm),
        joints,
        name: None,
        skeleton: Some(roots[0]),
    });
    root.scene = Some(root.push(gj::Scene {
        extensions: None,
        extras: None,
        name: None,
        nodes: roots,
    }));
    mesh_nodes
}

/// Every clip, with its ground speed in the animation's `extras`; a channel's node is the
/// file's node of that index.
pub(crate) fn animations(b: &mut Builder, clips: &[Clip]) -> Vec<gj::Animation> {
    use gj::animation::{Channel, Property, Sampler, Target};
    let mut animations = Vec::new();
    for clip in clips {
        let mut channels = Vec::new();
        let mut samplers = Vec::new();
        for ch in &clip.channels {
            let input = b.floats(&ch.times, Type::Scalar, true, None);
            let (kind, path) = match ch.target {
                ChannelTarget::Translation => (Type::Vec3, Property::Translation),
                ChannelTarget::Rotation => (Type::Vec4, Property::Rotation),
                ChannelTarget::Scale => (Type::Vec3, Property::Scale),
            };
            let width = kind.multiplicity();
            let values: Vec<f32> = ch
                .values
                .iter()
                .flat_map(|v| v.to_array()[..width].to_vec())
                .collect();
            let output = b.floats(&values, kind, false, None);
            let interpolation = match ch.interpolation {
                Interpolation::Step => gj::animation::Interpolation::Step,
                Interpolation::Linear => gj::animation::Interpolation::Linear,
                Interpolation::CubicSpline => gj::animation::Interpolation::CubicSpline,
            };
            let sampler = Index::push(
                &mut samplers,
                Sampler {
                    extensions: None,
                    extras: None,
                    input,
                    interpolation: Valid(interpolation),
                    output,
                },
            );
            channels.push(Channel {
                sampler,
                target: Target {
                    extensions: None,
                    extras: None,
                    node: Index::new(ch.node),
                    path: Valid(path),
                },
                extensions: None,
                extras: None,
            });
        }
        animations.push(gj::Animation {
            extensions: None,
            extras: extras(serde_json::json!({ "ground_speed": clip.ground_speed })),
            channels,
            name: Some(clip.name.clone()),
            samplers,
        });
    }
    animations
}

/// Encodes `model` as a `.glb` file.
pub fn to_glb(model: &Model) -> Vec<u8> {
    to_glb_with(model, &Extra::default(), "lodlab gen-assets")
}

/// [`to_glb`] with what `extra` adds (its tangents, if any, those of the model's mesh).
pub fn to_glb_with(model: &Model, extra: &Extra, generator: &str) -> Vec<u8> {
    let (root, bin) = document(model, &[&model.mesh], generator, true, extra);
    let json = gj::serialize::to_vec(&root).expect("serialising JSON into memory");
    glb_bytes(json, bin)
}

/// Encodes `model` with `levels` (finest first, each a mesh of its skeleton and materials) in
/// place of its mesh, as one `.glb`: the finest level's node carries `MSFT_lod`, naming the
/// others' nodes, and `MSFT_screencoverage` (`coverage`, one value a level: the share of the
/// screen's area below which the next level takes over, the last one the share below which
/// nothing is drawn). A reader without the extension shows the finest level.
pub fn to_lod_glb(
    model: &Model,
    levels: &[&SkinnedMesh],
    coverage: &[f32],
    generator: &str,
) -> Vec<u8> {
    to_lod_glb_with(model, levels, coverage, generator, &Extra::default())
}

/// [`to_lod_glb`] with what `extra` adds (its tangents, if any, a list for each level).
pub fn to_lod_glb_with(
    model: &Model,
    levels: &[&SkinnedMesh],
    coverage: &[f32],
    generator: &str,
    extra: &Extra,
) -> Vec<u8> {
    assert_eq!(levels.len(), coverage.len(), "a coverage value per level");
    let (root, bin) = document(model, levels, generator, false, extra);
    let mut json = serde_json::to_value(&root).expect("a glTF document is JSON");
    let finest = skeleton_nodes(model);
    let ids: Vec<usize> = (1..levels.len()).map(|k| finest + k).collect();
    let node = &mut json["nodes"][finest];
    node["extensions"] = serde_json::json!({ "MSFT_lod": { "ids": ids } });
    node["extras"] = serde_json::json!({ "MSFT_screencoverage": coverage });
    json["extensionsUsed"] = serde_json::json!(["MSFT_lod"]);
    let json = serde_json::to_vec(&json).expect("serialising JSON into memory");
    glb_bytes(json, bin)
}

/// A file holding `model`'s skeleton, materials and clips and the meshes `meshes` as its
/// meshes 0, 1, …, and its binary chunk.
fn document(
    model: &Model,
    meshes: &[&SkinnedMesh],
    generator: &str,
    all_in_scene: bool,
    extra: &Extra,
) -> (gj::Root, Vec<u8>) {
    let mut b = Builder::default();
    let mut root = gj::Root {
        asset: gj::Asset {
            generator: Some(generator.into()),
            ..Default::default()
        },
        ..Default::default()
    };
    for (k, mesh) in meshes.iter().enumerate() {
        let tangents = extra.tangents.get(k).map(Vec::as_slice);
        let primitives = primitives(&mut b, mesh, model.materials.len(), extra, tangents);
        root.push(gj::Mesh {
            extensions: None,
            extras: None,
            name: Some(if meshes.len() == 1 {
                model.name.clone()
            } else {
                format!("{}_LOD{k}", model.name)
            }),
            primitives,
            weights: None,
        });
    }
    materials_with(&mut b, &model.materials, extra, &mut root);
    skeleton(&mut b, model, &mut root, meshes.len(), all_in_scene);
    root.animations = animations(&mut b, &model.clips);
    while !b.bin.len().is_multiple_of(4) {
        b.bin.push(0);
    }
    root.accessors = b.accessors;
    root.buffer_views = b.views;
    root.push(gj::Buffer {
        byte_length: b.bin.len().into(),
        name: None,
        uri: None,
        extensions: None,
        extras: None,
    });

    (root, b.bin)
}

/// The node index of the first mesh's node: the skeleton's nodes come first.
fn skeleton_nodes(model: &Model) -> usize {
    model.skeleton.nodes.len()
}

/// A GLB container of `json_bytes` and the binary chunk `bin`.
pub(crate) fn glb_bytes(mut json_bytes: Vec<u8>, bin: Vec<u8>) -> Vec<u8> {
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: (12 + 8 + json_bytes.len() + 8 + bin.len()) as u32,
        },
        json: Cow::Owned(json_bytes),
        bin: Some(Cow::Owned(bin)),
    };
    glb.to_vec().expect("writing a GLB into memory")
}
