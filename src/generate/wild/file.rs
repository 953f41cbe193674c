//! A glTF document laid out the way other tools lay theirs out, for the test models whose
//! properties live in the file rather than in the mesh: several meshes and skins, unskinned
//! parts on nodes of their own, a scaled and turned armature node above the joints, morph
//! targets, clips without a mesh. [`super::super::glb`] writes one skinned [`crate::model::Model`]
//! as lodlab itself would; this writes what a [`Document`] spells out, node by node.

use crate::generate::glb::{self, Builder};
use crate::model::{Clip, Material, SkinnedMesh, Trs};
use glam::{Mat4, Vec3};
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked::Valid;
use gltf::json::{self as gj, Index};

/// One node: its place in the hierarchy, its rest transform, and what it carries.
#[derive(Clone, Debug)]
pub struct DocNode {
    pub name: String,
    pub parent: Option<usize>,
    pub rest: Trs,
    pub mesh: Option<usize>,
    pub skin: Option<usize>,
}

/// One primitive: its vertices with influences on the joints of its node's skin (by their
/// place in the skin's list), its triangles (written as given, degenerate ones included), its
/// material, and its morph targets (a position offset for every vertex, each target).
#[derive(Clone, Debug)]
pub struct DocPrimitive {
    pub mesh: SkinnedMesh,
    pub material: Option<usize>,
    pub targets: Vec<Vec<Vec3>>,
}

#[derive(Clone, Debug)]
pub struct DocMesh {
    pub name: String,
    pub primitives: Vec<DocPrimitive>,
}

/// A skin: its joints (nodes) and their inverse bind matrices.
#[derive(Clone, Debug)]
pub struct DocSkin {
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<Mat4>,
}

/// A whole file. Clips' channels name nodes of this document.
#[derive(Clone, Debug, Default)]
pub struct Document {
    pub generator: String,
    pub nodes: Vec<DocNode>,
    pub meshes: Vec<DocMesh>,
    pub skins: Vec<DocSkin>,
    pub materials: Vec<Material>,
    /// Tangent-space normal maps (glTF's `normalTexture`), by material: lodlab's own
    /// [`Material`] has none, as its renderer lights leaves and billboards without them.
    pub normal_maps: Vec<(usize, crate::model::Rgba8Image)>,
    pub clips: Vec<Clip>,
}

impl Document {
    /// Adds a node and returns its index.
    pub fn node(&mut self, name: &str, parent: Option<usize>, rest: Trs) -> usize {
        self.nodes.push(DocNode {
            name: name.to_string(),
            parent,
            rest,
            mesh: None,
            skin: None,
        });
        self.nodes.len() - 1
    }

    /// Node `n`'s transform in the scene, at rest.
    pub fn world(&self, n: usize) -> Mat4 {
        let node = &self.nodes[n];
        let local = Mat4::from(node.rest.matrix());
        match node.parent {
            Some(p) => self.world(p) * local,
            None => local,
        }
    }

    /// The `.glb` bytes: a pure function of the document, byte for byte.
    pub fn to_glb(&self) -> Vec<u8> {
        let mut b = Builder::default();
        let mut root = gj::Root {
            asset: gj::Asset {
                generator: Some(self.generator.clone()),
                ..Default::default()
            },
            ..Default::default()
        };
        for m in &self.meshes {
            let primitives = m.primitives.iter().map(|p| primitive(&mut b, p)).collect();
            let targets = m
                .primitives
                .iter()
                .map(|p| p.targets.len())
                .max()
                .unwrap_or(0);
            root.push(gj::Mesh {
                extensions: None,
                extras: None,
                name: Some(m.name.clone()),
                primitives,
                weights: (targets > 0).then(|| vec![0.0; targets]),
            });
        }
        glb::materials(&mut b, &self.materials, &mut root);
        for (m, image) in &self.normal_maps {
            let index = glb::embedded_texture(&mut b, &mut root, image);
            root.materials[*m].normal_texture = Some(gj::material::NormalTexture {
                index,
                scale: 1.0,
                tex_coord: 0,
                extensions: None,
                extras: None,
            });
        }
        let mut nodes: Vec<gj::Node> = self
            .nodes
            .iter()
            .map(|n| gj::Node {
                name: Some(n.name.clone()),
                translation: (n.rest.translation != Vec3::ZERO)
                    .then(|| n.rest.translation.to_array()),
                rotation: (n.rest.rotation != glam::Quat::IDENTITY)
                    .then(|| gj::scene::UnitQuaternion(n.rest.rotation.to_array())),
                scale: (n.rest.scale != Vec3::ONE).then(|| n.rest.scale.to_array()),
                mesh: n.mesh.map(|m| Index::new(m as u32)),
                skin: n.skin.map(|s| Index::new(s as u32)),
                ..Default::default()
            })
            .collect();
        for (i, n) in self.nodes.iter().enumerate() {
            if let Some(p) = n.parent {
                nodes[p]
                    .children
                    .get_or_insert_with(Vec::new)
                    .push(Index::new(i as u32));
            }
        }
        root.nodes = nodes;
        for s in &self.skins {
            let ibm: Vec<f32> = s
                .inverse_bind
                .iter()
                .flat_map(|m| m.to_cols_array())
                .collect();
            let ibm = b.floats(&ibm, Type::Mat4, false, None);
            root.push(gj::Skin {
                extensions: None,
                extras: None,
                inverse_bind_matrices: Some(ibm),
                joints: s.joints.iter().map(|&j| Index::new(j as u32)).collect(),
                name: None,
                skeleton: None,
            });
        }
        let roots = (0..self.nodes.len())
            .filter(|&i| self.nodes[i].parent.is_none())
            .map(|i| Index::new(i as u32))
            .collect();
        root.scene = Some(root.push(gj::Scene {
            extensions: None,
            extras: None,
            name: None,
            nodes: roots,
        }));
        root.animations = glb::animations(&mut b, &self.clips);
        while !b.bin.len().is_multiple_of(4) {
            b.bin.push(0);
        }
        root.accessors = b.accessors;
        root.buffer_views = b.views;
        if !b.bin.is_empty() {
            root.push(gj::Buffer {
                byte_length: b.bin.len().into(),
                name: None,
                uri: None,
                extensions: None,
                extras: None,
            });
        }
        let json = gj::serialize::to_vec(&root).expect("serialising JSON into memory");
        glb::glb_bytes(json, b.bin)
    }
}

/// One primitive's accessors: every vertex of its mesh, its indices as given, its targets.
fn primitive(b: &mut Builder, p: &DocPrimitive) -> gj::mesh::Primitive {
    let all: Vec<usize> = (0..p.mesh.vertex_count()).collect();
    let attributes = glb::vertex_attributes(b, &p.mesh, &all);
    let indices = b.accessor(
        bytemuck::cast_slice(&p.mesh.indices),
        Some(gj::buffer::Target::ElementArrayBuffer),
        ComponentType::U32,
        p.mesh.indices.len(),
        Type::Scalar,
        None,
    );
    let targets = (!p.targets.is_empty()).then(|| {
        p.targets
            .iter()
            .map(|t| {
                let d: Vec<f32> = t.iter().flat_map(|v| v.to_array()).collect();
                gj::mesh::MorphTarget {
                    positions: Some(b.floats(&d, Type::Vec3, true, None)),
                    normals: None,
                    tangents: None,
                }
            })
            .collect()
    });
    gj::mesh::Primitive {
        attributes,
        extensions: None,
        extras: None,
        indices: Some(indices),
        material: p.material.map(|m| Index::new(m as u32)),
        mode: Valid(gj::mesh::Mode::Triangles),
        targets,
    }
}
