//! What the renderer draws of one model: its textures, its index list and how it is drawn.

use super::anim_texture::{self, AnimationTexture};
use super::animation_space::AnimationSpaceMesh;
use super::impostor_frames::{AnimatedFrame, ImpostorFrame};
use super::materials::{MaterialLayers, billboard_atlas, lit_atlas_material};
use super::vertex_texture::VertexTexture;
use crate::bake::foliage::billboard::occlusion::CrownDensity;
use crate::bake::gpu_data::spectra::{NO_ROW, SpectraTexture, SpectralMotion};
use crate::model::{Bounds, Model};
use glam::Vec3;

/// Everything the renderer needs to draw one model at one level: a character's mesh, a tree,
/// a billboard cloud or an impostor (all skinned meshes in animation space).
#[derive(Clone, Debug)]
pub struct Drawable {
    pub name: String,
    pub animation: AnimationTexture,
    pub vertices: VertexTexture,
    pub indices: Vec<u32>,
    pub materials: MaterialLayers,
    /// Bounds over the sampled frames of every clip, in scene units, model-local; where the
    /// clips carry the character (root motion), the body's: each pose moved back by its
    /// [`Self::travel`].
    pub bounds: Bounds,
    /// Where the clips carry the character, per clip and frame, the offset of its body from
    /// the rest pose's place (see [`super::root_motion`]); empty where they do not.
    pub travel: Vec<Vec<glam::Vec3>>,
    pub animation_space: AnimationSpaceMesh,
    /// How the renderer draws it: a mesh, foliage or an impostor's quad.
    pub kind: DrawKind,
    /// A spectral cloud's spectra texture (the vertices that read it have their rows in
    /// `animation_space.spectral_rows`).
    pub spectra: Option<SpectraTexture>,
    /// A billboard cloud's billboard outlines as a line list over `indices`' vertices (empty
    /// for everything else): what the viewer's "billboard outlines" draw.
    pub outlines: Vec<u32>,
}

/// How the renderer draws a [`Drawable`]: which pass it belongs to and which family of
/// shaders draws it. Every drawable is a skinned mesh in animation space; what differs is
/// its material (opaque or cut out) and whether its mesh is a card that faces the eye.
#[derive(Clone, Debug, PartialEq)]
pub enum DrawKind {
    /// An opaque mesh, back faces culled: a character's level. The only kind lit through
    /// normal maps, and the only one whose transitions are screen-door dithered (the others
    /// dissolve in their own shaders).
    Mesh,
    /// Cut-out alpha (foliage: a tree's mesh or billboard cloud), drawn two-sided and
    /// alpha-tested in the foliage pass and swayed by the scene's wind. `atlas_lit`: a
    /// billboard cloud whose billboards are lit through their atlas (a normal per texel,
    /// [`crate::bake::foliage::billboard::atlas`]), drawn with the per-pixel foliage shader
    /// where atlas lighting is on.
    Foliage { atlas_lit: bool },
    /// A tree's octahedral impostor, drawn as one quad facing the eye, cut out like foliage
    /// (see [`crate::bake::impostor::octahedral`]).
    TreeImpostor(ImpostorFrame),
    /// A character's animated impostor (its last level), drawn as one quad facing the eye in
    /// the characters' pass, showing the view and frames it stands in (see [`crate::bake::impostor::animated`]).
    CharacterImpostor(AnimatedFrame),
}

crate::choice! {
    own_values;
    /// What an instance drawn at a level shows: the representation `bench` counts instances
    /// by (a finer cut than [`DrawClass`], which only says how it is drawn).
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
    pub enum LevelKind {
        /// A character's mesh (its full detail or a simplified level).
        Mesh => "mesh",
        /// A tree with every leaf.
        Tree => "full tree",
        /// A billboard cloud whose every billboard is drawn (skeleton or spectral).
        Cloud => "cloud",
        /// View-selected clumps: each view draws one billboard of a clump.
        Clumps => "clumps",
        /// A tree's octahedral impostor.
        TreeImpostor => "tree impostor",
        /// A character's animated impostor.
        CharacterImpostor => "character impostor",
        /// A forest patch: one impostor card for the trees of a layout cell
        /// (`bake::foliage::patch`).
        ForestPatch => "forest patch",
    }
}

impl LevelKind {
    pub const COUNT: usize = LevelKind::ALL.len();
}

/// [`DrawKind`] without its data: what the renderer keeps of it and picks pipelines by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DrawClass {
    Mesh,
    Foliage,
    AtlasLitFoliage,
    TreeImpostor,
    CharacterImpostor,
}

impl DrawKind {
    pub fn class(&self) -> DrawClass {
        match self {
            DrawKind::Mesh => DrawClass::Mesh,
            DrawKind::Foliage { atlas_lit: false } => DrawClass::Foliage,
            DrawKind::Foliage { atlas_lit: true } => DrawClass::AtlasLitFoliage,
            DrawKind::TreeImpostor(_) => DrawClass::TreeImpostor,
            DrawKind::CharacterImpostor(_) => DrawClass::CharacterImpostor,
        }
    }

    /// See [`DrawClass::is_tree`].
    pub fn is_tree(&self) -> bool {
        self.class().is_tree()
    }

    pub fn tree_impostor(&self) -> Option<&ImpostorFrame> {
        match self {
            DrawKind::TreeImpostor(f) => Some(f),
            _ => None,
        }
    }

    pub fn character_impostor(&self) -> Option<&AnimatedFrame> {
        match self {
            DrawKind::CharacterImpostor(f) => Some(f),
            _ => None,
        }
    }
}

/// Whether `model` is drawn as foliage: a billboard cloud, or a tree
/// ([`crate::bake::foliage::classify`]); a character's cut-out parts are a mesh's (see
/// `LodPack`'s cut-out triangles).
fn is_foliage(model: &Model) -> bool {
    billboard_atlas(&model.materials).is_some() || crate::bake::foliage::classify::is_tree(model)
}

impl DrawClass {
    /// A tree (its mesh, a billboard cloud or its impostor): drawn in the foliage pass,
    /// swayed by the scene's wind, placed by a scene's tree layout.
    pub fn is_tree(self) -> bool {
        matches!(
            self,
            DrawClass::Foliage | DrawClass::AtlasLitFoliage | DrawClass::TreeImpostor
        )
    }

    /// An impostor: one quad facing the eye, made by its own shaders from four corners
    /// (so never drawn as a mesh, faded or in wireframe).
    pub fn faces_eye(self) -> bool {
        matches!(self, DrawClass::TreeImpostor | DrawClass::CharacterImpostor)
    }
}

impl Drawable {
    /// What it shows: a billboard cloud is foliage with billboard outlines, a clump level one
    /// whose billboards have view windows.
    pub fn level_kind(&self) -> LevelKind {
        match self.kind {
            DrawKind::Mesh => LevelKind::Mesh,
            DrawKind::TreeImpostor(_) => LevelKind::TreeImpostor,
            DrawKind::CharacterImpostor(_) => LevelKind::CharacterImpostor,
            DrawKind::Foliage { .. } if self.outlines.is_empty() => LevelKind::Tree,
            DrawKind::Foliage { .. } if self.animation_space.view_windows.is_empty() => {
                LevelKind::Cloud
            }
            DrawKind::Foliage { .. } => LevelKind::Clumps,
        }
    }

    /// Bytes its textures, meshes and index lists hold on the CPU.
    pub fn heap_bytes(&self) -> u64 {
        let am = &self.animation_space;
        let mesh = std::mem::size_of_val(am.offsets.as_slice())
            + std::mem::size_of_val(am.influences.as_slice())
            + std::mem::size_of_val(am.uvs.as_slice())
            + std::mem::size_of_val(am.materials.as_slice())
            + std::mem::size_of_val(am.indices.as_slice())
            + std::mem::size_of_val(am.spectral_rows.as_slice())
            + std::mem::size_of_val(am.crown_occlusion.as_slice())
            + std::mem::size_of_val(am.view_windows.as_slice());
        let textures = self.animation.grid.texels.len() * 16
            + self.vertices.grid.texels.len() * 16
            + self.materials.mips.iter().map(Vec::len).sum::<usize>()
            + self.spectra.as_ref().map_or(0, |s| s.bytes().len());
        (mesh + textures + 4 * (self.indices.len() + self.outlines.len())) as u64
    }

    pub fn new(model: &Model) -> Result<Self, String> {
        Self::with_motion(model, None)
    }

    /// [`Self::new`] for a level whose billboards also move by `motion` (a spectral cloud).
    /// A tree (a model with leaves, not billboards) is darkened inside its crown (see
    /// [`crate::bake::foliage::billboard::occlusion`]).
    pub fn with_motion(model: &Model, motion: Option<&SpectralMotion>) -> Result<Self, String> {
        let billboards = billboard_atlas(&model.materials).is_some();
        let tree = !billboards && crate::bake::foliage::classify::is_tree(model);
        let crown = tree.then(|| CrownDensity::of(model)).flatten();
        let occlusion = crown.map_or_else(Vec::new, |c| c.occlusions(&model.mesh.positions));
        Self::build(model, motion, true, &occlusion, &[], billboards || tree)
    }

    /// [`Self::with_motion`] for a level of a tree, every vertex darkened by the crown by
    /// `occlusion` (one per vertex of `model`, see [`crate::bake::foliage::billboard::occlusion`]; empty: none), and
    /// its billboards drawn within their `view_windows` (one per vertex, see
    /// [`billboard::clumps`](crate::bake::foliage::billboard::clumps); empty: from every view).
    pub fn tree_level(
        model: &Model,
        motion: Option<&SpectralMotion>,
        occlusion: &[f32],
        view_windows: &[f32],
    ) -> Result<Self, String> {
        if !view_windows.is_empty() && view_windows.len() != model.mesh.vertex_count() {
            return Err("view windows do not fit the model's vertices".into());
        }
        Self::build(
            model,
            motion,
            true,
            occlusion,
            view_windows,
            is_foliage(model),
        )
    }

    /// [`Self::new`] with the vertices in the model's order, not reordered for the GPU's
    /// caches: for a mesh whose shader finds vertices by index (an impostor's quad).
    pub fn in_order(model: &Model) -> Result<Self, String> {
        Self::build(model, None, false, &[], &[], is_foliage(model))
    }

    fn build(
        model: &Model,
        motion: Option<&SpectralMotion>,
        optimize: bool,
        occlusion: &[f32],
        view_windows: &[f32],
        foliage: bool,
    ) -> Result<Self, String> {
        let mut am = AnimationSpaceMesh::from_skinned(&model.mesh, &model.skeleton);
        if let Some(m) = motion {
            if m.vertex_rows.len() != am.vertex_count()
                || m.vertex_rows
                    .iter()
                    .any(|&r| r != NO_ROW && r >= m.spectra.rows)
            {
                return Err("spectral motion does not fit the model's vertices".into());
            }
            am.spectral_rows = m.vertex_rows.clone();
        }
        if !occlusion.is_empty() {
            if occlusion.len() != am.vertex_count() {
                return Err("crown occlusion does not fit the model's vertices".into());
            }
            am.crown_occlusion = occlusion.iter().map(|o| o.clamp(0.0, 1.0)).collect();
        }
        if view_windows.iter().any(|&w| w != 0.0) {
            am.view_windows = view_windows.to_vec();
        }
        let am = if optimize { am.optimized_for_gpu() } else { am };
        let animation = AnimationTexture::bake(model, anim_texture::DEFAULT_RATE);
        // A cloud's billboards lit through their atlas point at "layer 0" (see
        // `vertex_texture`): the lighting is the material layer after the atlas's.
        let atlas = lit_atlas_material(&model.materials);
        let lit_layers: Vec<Option<u32>> = (0..model.materials.len())
            .map(|m| (Some(m) == atlas).then_some(0))
            .collect();
        let vertices = VertexTexture::pack(
            &[&am],
            &[],
            if atlas.is_some() {
                std::slice::from_ref(&lit_layers)
            } else {
                &[]
            },
        )?;
        let materials = MaterialLayers::bake(&model.materials);

        // Bounds over a few frames of every clip: enough for framing, shadows and culling.
        let (bounds, travel) = super::root_motion::bounds_and_travel(&am, &animation)
            .ok_or("model has no vertices")?;

        Ok(Drawable {
            name: model.name.clone(),
            animation,
            vertices,
            indices: am.indices.clone(),
            materials,
            bounds,
            travel,
            // See `is_foliage`.
            kind: if foliage {
                DrawKind::Foliage {
                    atlas_lit: atlas.is_some(),
                }
            } else {
                DrawKind::Mesh
            },
            outlines: billboard_atlas(&model.materials).map_or_else(Vec::new, |b| {
                billboard_outlines(&am.indices, &am.materials, b as u16)
            }),
            animation_space: am,
            spectra: motion.map(|m| m.spectra.clone()),
        })
    }

    /// Where the body of an instance is `time` seconds into clip `clip`, against the rest
    /// pose's place: zero unless the clips carry the character (see [`Self::travel`]).
    pub fn travel_at(&self, clip: usize, time: f32) -> glam::Vec3 {
        self.animation
            .clips
            .get(clip)
            .map_or(glam::Vec3::ZERO, |c| {
                super::root_motion::travel_at(&self.travel, clip, c.frame_count, c.duration, time)
            })
    }

    /// [`Self::travel_at`] for a bake's time within the clip: the clip's length is its last
    /// frame, not its first again (see [`super::root_motion::travel_within`]).
    pub fn travel_within(&self, clip: usize, time: f32) -> glam::Vec3 {
        self.animation
            .clips
            .get(clip)
            .map_or(glam::Vec3::ZERO, |c| {
                let (frames, duration) = (c.frame_count, c.duration);
                super::root_motion::travel_within(&self.travel, clip, frames, duration, time)
            })
    }

    /// The CPU reference of the vertex shader's skinning (`skin_vertex` in
    /// `shaders/skinning.wgsl`): positions and normals at `time` seconds into `clip`, the
    /// motion scaled by the wind strength `wind`, spectral offsets included:
    /// `v = Σ G_i (p_i + w_i · Δ(τ))`.
    pub fn evaluate(&self, clip: usize, time: f32, wind: f32) -> (Vec<Vec3>, Vec<Vec3>) {
        let g = self.animation.sample_with(clip, time, wind);
        let am = &self.animation_space;
        let Some(spectra) = &self.spectra else {
            return am.evaluate(&g);
        };
        let tau = self.animation.loop_time(clip, time);
        let mut moved = am.clone();
        for v in 0..am.vertex_count() {
            let row = am.spectral_rows.get(v).copied().unwrap_or(NO_ROW);
            if row == NO_ROW {
                continue;
            }
            let d = spectra.offset(row, tau, wind);
            let (a, b) = (am.offsets[v] as usize, am.offsets[v + 1] as usize);
            for inf in &mut moved.influences[a..b] {
                inf.p += (d * inf.p.w).extend(0.0);
            }
        }
        moved.evaluate(&g)
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    pub fn clip_names(&self) -> Vec<String> {
        self.animation
            .clips
            .iter()
            .map(|c| c.name.clone())
            .collect()
    }
}

/// The outlines of the billboards among `indices`, as a line list: every edge of a triangle of
/// material `billboard` (`materials` per vertex) that no other such triangle shares. A
/// billboard's two triangles share its diagonal, so what is left is its four sides. Billboards
/// share no vertices, so their outlines never merge.
pub fn billboard_outlines(indices: &[u32], materials: &[u16], billboard: u16) -> Vec<u32> {
    let mut edges: std::collections::HashMap<(u32, u32), u32> = Default::default();
    for t in indices.chunks_exact(3) {
        if materials.get(t[0] as usize) != Some(&billboard) {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut lines: Vec<(u32, u32)> = edges
        .into_iter()
        .filter(|&(_, n)| n == 1)
        .map(|(e, _)| e)
        .collect();
    // In a fixed order, whatever the hash map's.
    lines.sort_unstable();
    lines.into_iter().flat_map(|(a, b)| [a, b]).collect()
}
