//! The plain data every stage shares: a skinned character as imported, before any baking.
//!
//! A [`Model`] is one skinned mesh (all primitives of one glTF skin merged), its skeleton and its
//! animation clips. It is produced by `import` (glTF files) and `generate` (the project's own demo
//! creatures) and consumed by `bake`. Nothing here knows about the GPU.

use glam::{Affine3A, Mat4, Quat, Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

/// A translation / rotation / scale triple, as glTF stores a node's local transform.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trs {
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Trs {
    pub const IDENTITY: Trs = Trs {
        translation: Vec3::ZERO,
        rotation: Quat::IDENTITY,
        scale: Vec3::ONE,
    };

    pub fn matrix(&self) -> Affine3A {
        Affine3A::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// One node of the skeleton hierarchy. Nodes are stored parents first, so a single forward pass
/// computes global transforms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Node {
    pub name: String,
    pub parent: Option<u32>,
    pub rest: Trs,
}

/// The skeleton: the node hierarchy that holds the joints, and the skin's bind data.
///
/// In the notation of Merry et al. §2.1.1, bone `i` has the pose matrix `G_i` (bone space to model
/// space) and the rest-pose matrix `Ĝ_i`; glTF stores `Ĝ_i⁻¹` directly as the inverse bind matrix.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Skeleton {
    /// All joints and their ancestors, parents before children.
    pub nodes: Vec<Node>,
    /// Bone `i` is node `joints[i]`.
    pub joints: Vec<u32>,
    /// `Ĝ_i⁻¹` for every bone.
    pub inverse_bind: Vec<Mat4>,
    /// Applied on top of every bone's global transform: brings the model from its file's units
    /// and placement to the scene's (metres, standing on y = 0, centred on the origin).
    pub root_transform: Affine3A,
}

impl Skeleton {
    pub fn bone_count(&self) -> usize {
        self.joints.len()
    }
}

/// How a channel's keyframes are interpolated (glTF 2.0 §3.11).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

/// Which part of a node's transform a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ChannelTarget {
    Translation,
    Rotation,
    Scale,
}

/// One animated property of one node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Channel {
    pub node: u32,
    pub target: ChannelTarget,
    pub interpolation: Interpolation,
    /// Key times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// One value per key (translation and scale in xyz, rotation as a quaternion xyzw); for
    /// [`Interpolation::CubicSpline`] three per key: in-tangent, value, out-tangent.
    pub values: Vec<Vec4>,
}

/// A named animation clip. Clips loop: time is taken modulo `duration`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Clip {
    pub name: String,
    pub duration: f32,
    pub channels: Vec<Channel>,
    /// Speed at which the character travels over the ground while the clip plays, in scene
    /// units per second (0 for clips played on the spot).
    pub ground_speed: f32,
}

/// One bone's share of a vertex in classic linear blend skinning.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Influence {
    pub bone: u32,
    pub weight: f32,
}

/// An indexed triangle mesh with per-vertex skin influences of any count.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SkinnedMesh {
    /// Rest (bind) positions `v̂`, in the mesh space the inverse bind matrices expect.
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    /// Index into [`Model::materials`] for every vertex.
    pub materials: Vec<u16>,
    /// Influences of vertex `v` are `influences[influence_offsets[v]..influence_offsets[v + 1]]`,
    /// weights positive and summing to one.
    pub influence_offsets: Vec<u32>,
    pub influences: Vec<Influence>,
    pub indices: Vec<u32>,
}

impl SkinnedMesh {
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Whether some triangle covers area in some pose. Two corners at one point with one skin
    /// stay at one point in every pose: a triangle with two such corners never covers a pixel.
    pub fn draws(&self) -> bool {
        let collapsed = |a: u32, b: u32| {
            let (a, b) = (a as usize, b as usize);
            a == b
                || (self.positions[a] == self.positions[b]
                    && self.influences_of(a) == self.influences_of(b))
        };
        self.indices
            .chunks_exact(3)
            .any(|t| !collapsed(t[0], t[1]) && !collapsed(t[1], t[2]) && !collapsed(t[2], t[0]))
    }

    pub fn influences_of(&self, vertex: usize) -> &[Influence] {
        let a = self.influence_offsets[vertex] as usize;
        let b = self.influence_offsets[vertex + 1] as usize;
        &self.influences[a..b]
    }

    /// An empty mesh, ready for vertices to be appended.
    pub fn empty() -> SkinnedMesh {
        SkinnedMesh {
            influence_offsets: vec![0],
            ..Default::default()
        }
    }

    /// Appends vertex `v` of `src` (all its attributes) and returns its index here.
    pub fn copy_vertex_from(&mut self, src: &SkinnedMesh, v: usize) -> u32 {
        self.positions.push(src.positions[v]);
        self.normals.push(src.normals[v]);
        self.uvs.push(src.uvs[v]);
        self.materials.push(src.materials[v]);
        self.influences.extend_from_slice(src.influences_of(v));
        self.influence_offsets.push(self.influences.len() as u32);
        self.positions.len() as u32 - 1
    }

    /// Drops what draws nothing and confuses what comes after: triangles that repeat a vertex,
    /// triangles that repeat another with the same winding (a reversed copy is a back face,
    /// and stays), and vertices no triangle uses, which are renumbered away (their order kept).
    /// Returns how many triangles and vertices went.
    pub fn drop_unused(&mut self) -> (usize, usize) {
        let mut seen = std::collections::HashSet::with_capacity(self.triangle_count());
        let before = self.triangle_count();
        let mut kept = Vec::with_capacity(self.indices.len());
        for t in self.indices.chunks_exact(3) {
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                continue;
            }
            // The same triangle read from its smallest vertex, winding kept.
            let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            if !seen.insert([t[k], t[(k + 1) % 3], t[(k + 2) % 3]]) {
                continue;
            }
            kept.extend_from_slice(t);
        }
        let triangles = before - kept.len() / 3;
        let mut used = vec![false; self.vertex_count()];
        kept.iter().for_each(|&v| used[v as usize] = true);
        let vertices = used.iter().filter(|&&u| !u).count();
        if vertices == 0 {
            self.indices = kept;
            return (triangles, 0);
        }
        let mut compact = SkinnedMesh::empty();
        let mut remap = vec![u32::MAX; self.vertex_count()];
        for v in (0..self.vertex_count()).filter(|&v| used[v]) {
            remap[v] = compact.copy_vertex_from(self, v);
        }
        compact.indices = kept.iter().map(|&v| remap[v as usize]).collect();
        *self = compact;
        (triangles, vertices)
    }

    /// Appends the triangles of `src` that `keep` accepts, in order, with the vertices they use
    /// (each once, in order of first use).
    pub fn copy_triangles_from(&mut self, src: &SkinnedMesh, keep: impl Fn(&[u32]) -> bool) {
        let mut remap = vec![u32::MAX; src.vertex_count()];
        for t in src.indices.chunks_exact(3).filter(|t| keep(t)) {
            for &v in t {
                let v = v as usize;
                if remap[v] == u32::MAX {
                    remap[v] = self.copy_vertex_from(src, v);
                }
                self.indices.push(remap[v]);
            }
        }
    }
}

/// An 8-bit RGBA image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rgba8Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<u8>,
}

/// How a material's alpha is read (glTF's `alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum AlphaMode {
    /// Alpha is ignored: the surface is solid.
    #[default]
    Opaque,
    /// Alpha below the cutoff cuts the surface out (foliage).
    Mask,
    /// Alpha blends the surface over what is behind it. lodlab cuts it out at one half, as a
    /// mask: its crowds and forests are drawn without sorting.
    Blend,
}

/// The part of a glTF material lodlab renders: the base colour, and how its alpha and back
/// faces are taken.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    pub name: String,
    /// Linear RGBA factor, multiplied with the texture.
    pub base_color: [f32; 4],
    /// sRGB-encoded base colour texture.
    pub texture: Option<Rgba8Image>,
    pub alpha_mode: AlphaMode,
    /// glTF's `alphaCutoff`: under [`AlphaMode::Mask`], alpha below it is cut out.
    pub alpha_cutoff: f32,
    /// glTF's `doubleSided`.
    pub double_sided: bool,
    /// What lodlab's renderer takes it for. Only lodlab's own bakes give a material another
    /// role than [`MaterialRole::Surface`]: an imported file's material names mean nothing to
    /// it.
    pub role: MaterialRole,
}

/// What a material is to the renderer besides a surface: the roles a billboard cloud's bake
/// gives its atlas and the atlas's lighting (see `bake::gpu_data::materials`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum MaterialRole {
    /// A surface drawn with its colour and alpha.
    #[default]
    Surface,
    /// A billboard cloud's atlas: its triangles are the billboards, two to a quad.
    BillboardAtlas,
    /// The material after a cloud's atlas, holding its lighting: per texel, the normal the
    /// leaf drawn there is lit by. No triangle uses it.
    BillboardLighting,
}

impl Material {
    /// A solid, one-sided material (glTF's defaults).
    pub fn opaque(name: &str, base_color: [f32; 4], texture: Option<Rgba8Image>) -> Material {
        Material {
            name: name.into(),
            base_color,
            texture,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            double_sided: false,
            role: MaterialRole::Surface,
        }
    }

    /// The same material in `role`.
    pub fn with_role(self, role: MaterialRole) -> Material {
        Material { role, ..self }
    }

    /// Whether its alpha cuts its shape out anywhere: a mask (or a blend, which lodlab draws
    /// as a mask at one half) whose factor or texture has alpha below the cutoff. Opaque
    /// materials never do, whatever their texture's alpha.
    pub fn cuts_out(&self) -> bool {
        let cutoff = match self.alpha_mode {
            AlphaMode::Opaque => return false,
            AlphaMode::Mask => self.alpha_cutoff,
            AlphaMode::Blend => 0.5,
        };
        let a = self.base_color[3];
        a < cutoff
            || self.texture.as_ref().is_some_and(|t| {
                t.pixels
                    .chunks_exact(4)
                    .any(|px| px[3] as f32 / 255.0 * a < cutoff)
            })
    }

    /// A two-sided material whose alpha cuts its shape out at one half (leaves, billboards).
    pub fn cut_out(name: &str, base_color: [f32; 4], texture: Option<Rgba8Image>) -> Material {
        Material {
            alpha_mode: AlphaMode::Mask,
            double_sided: true,
            ..Material::opaque(name, base_color, texture)
        }
    }
}

/// A skinned, animated character.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model {
    pub name: String,
    pub mesh: SkinnedMesh,
    pub skeleton: Skeleton,
    pub clips: Vec<Clip>,
    pub materials: Vec<Material>,
}

impl Model {
    /// Bytes its mesh and textures hold (what a memory report counts; keys, curves and
    /// names are small beside them).
    pub fn heap_bytes(&self) -> u64 {
        let m = &self.mesh;
        let mesh = std::mem::size_of_val(m.positions.as_slice())
            + std::mem::size_of_val(m.normals.as_slice())
            + std::mem::size_of_val(m.uvs.as_slice())
            + std::mem::size_of_val(m.materials.as_slice())
            + std::mem::size_of_val(m.influence_offsets.as_slice())
            + std::mem::size_of_val(m.influences.as_slice())
            + std::mem::size_of_val(m.indices.as_slice());
        let textures: usize = self
            .materials
            .iter()
            .filter_map(|t| t.texture.as_ref())
            .map(|t| t.pixels.len())
            .sum();
        (mesh + textures) as u64
    }

    /// The same model with its vertices and its triangles each listed in another order (a
    /// fixed shuffle per `seed`) and every triangle's corners rotated by a shuffled amount:
    /// the same surface and skin as another exporter might write them. What a method makes of
    /// it must be what it makes of `self` (issue: comparisons with error bars).
    pub fn relisted(&self, seed: u64) -> Model {
        let mut rng = fastrand::Rng::with_seed(seed);
        let src = &self.mesh;
        let mut order: Vec<usize> = (0..src.vertex_count()).collect();
        rng.shuffle(&mut order);
        let mut new_index = vec![0u32; order.len()];
        let mut mesh = SkinnedMesh::empty();
        for &v in &order {
            new_index[v] = mesh.copy_vertex_from(src, v);
        }
        let mut triangles: Vec<&[u32]> = src.indices.chunks_exact(3).collect();
        rng.shuffle(&mut triangles);
        mesh.indices = triangles
            .into_iter()
            .flat_map(|t| {
                let k = rng.usize(0..3);
                [t[k], t[(k + 1) % 3], t[(k + 2) % 3]].map(|v| new_index[v as usize])
            })
            .collect();
        Model {
            mesh,
            ..self.clone()
        }
    }
}

/// Axis-aligned bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: Vec3,
    pub max: Vec3,
}

impl Bounds {
    pub fn of(points: impl IntoIterator<Item = Vec3>) -> Option<Bounds> {
        let mut it = points.into_iter();
        let first = it.next()?;
        let mut b = Bounds {
            min: first,
            max: first,
        };
        for p in it {
            b.min = b.min.min(p);
            b.max = b.max.max(p);
        }
        Some(b)
    }

    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    pub fn diagonal(&self) -> f32 {
        self.size().length()
    }
}

/// Whether `m` keeps every direction (an inverse worth taking), whatever its scale: its
/// determinant against the product of its axes' lengths, the volume it would have with them
/// at right angles. An absolute bound takes a small scale for flatness: gltfpack's quantised
/// files skin their positions through matrices that scale by about 1/16,000 (determinant about
/// 10⁻¹² on a character, 10⁻¹⁰ on a sapling).
pub fn keeps_every_direction(m: &Mat4) -> bool {
    let axes =
        m.x_axis.truncate().length() * m.y_axis.truncate().length() * m.z_axis.truncate().length();
    m.is_finite() && axes > 0.0 && m.determinant().abs() > 1e-6 * axes
}

/// An sRGB-encoded byte in linear light.
pub(crate) fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear light to an sRGB-encoded byte (rounded to the nearest), as the formula
/// [`srgb_encode`] gives it, bit for bit: the number of byte boundaries at or below `c`, found
/// by binary search among the smallest floats that encode to each byte. Mipmapping a texture
/// calls this for every texel of every level; a `powf` each was most of loading a forest's
/// atlases.
pub(crate) fn linear_to_srgb(c: f32) -> u8 {
    static BOUNDS: std::sync::LazyLock<[f32; 255]> = std::sync::LazyLock::new(|| {
        std::array::from_fn(|k| {
            // The formula rises with c: bisect over the bit patterns of floats in [0, 1],
            // which order as the floats do.
            let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if srgb_encode(f32::from_bits(mid)) > k as u8 {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            f32::from_bits(lo)
        })
    });
    BOUNDS.partition_point(|&b| b <= c) as u8
}

/// The sRGB encoding of linear light, rounded to a byte.
fn srgb_encode(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_matrix_is_invertible_at_any_scale_and_not_when_flat() {
        let turned = Mat4::from_rotation_y(0.7) * Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
        assert!(keeps_every_direction(&turned));
        // gltfpack's dequantisation of a 6.5 m tree in 14 bits, and of a character's skin.
        assert!(keeps_every_direction(
            &(turned * Mat4::from_scale(Vec3::splat(4e-4)))
        ));
        assert!(keeps_every_direction(
            &(turned * Mat4::from_scale(Vec3::splat(9e-5)))
        ));
        assert!(!keeps_every_direction(
            &(turned * Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)))
        ));
        let sheared_flat = Mat4::from_cols(
            glam::Vec4::new(1.0, 0.0, 0.0, 0.0),
            glam::Vec4::new(1.0, 1e-9, 0.0, 0.0),
            glam::Vec4::Z,
            glam::Vec4::W,
        );
        assert!(!keeps_every_direction(&sheared_flat));
        assert!(!keeps_every_direction(&Mat4::ZERO));
    }

    /// The encoding by binary search is the formula's, bit for bit, and round-trips every
    /// byte.
    #[test]
    fn srgb_encoding_matches_the_formula() {
        let n = 1_000_000;
        for i in 0..=n {
            let c = i as f32 / n as f32;
            assert_eq!(linear_to_srgb(c), srgb_encode(c), "{c}");
        }
        for k in 0..255u32 {
            // Around every boundary, to the float.
            let s = (k as f32 + 0.5) / 255.0;
            let c = if s <= 0.04045 {
                s / 12.92
            } else {
                ((s + 0.055) / 1.055).powf(2.4)
            };
            for d in -64i32..=64 {
                let x = f32::from_bits((c.to_bits() as i32 + d) as u32);
                assert_eq!(linear_to_srgb(x), srgb_encode(x), "{x}");
            }
        }
        for b in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(b)), b);
        }
        assert_eq!(linear_to_srgb(-1.0), 0);
        assert_eq!(linear_to_srgb(2.0), 255);
        assert_eq!(linear_to_srgb(f32::NAN), srgb_encode(f32::NAN));
    }
}
