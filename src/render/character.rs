//! A character on the GPU: its baked textures and buffers, created once, and the bind group that
//! every character pass uses.

use super::gpu::Gpu;
use super::memory::GpuMemory;
use crate::bake::gpu_data::drawable::{DrawClass, Drawable, LevelKind};
use crate::bake::gpu_data::lod_pack::{LodPack, PackedLevel};
use crate::bake::gpu_data::texels::TexelGrid;
use wgpu::util::DeviceExt;

/// A character's uniform: its shadow ellipse (mirror of `Shadow` in `shaders/shadow.wgsl`),
/// then, for an impostor, its frame (mirror of `ImpostorFrame` in `shaders/impostor.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct CharacterUniform {
    ellipse: [f32; 4],
    sphere: [f32; 4],
    grid: [f32; 4],
    cell: [f32; 4],
    /// A tree impostor's bounds at rest (w of `hi` 1 where they are set).
    lo: [f32; 4],
    hi: [f32; 4],
}

/// A character's shared GPU data: animation texture, materials, blob shadow, and one set of
/// levels of detail per method that has been uploaded.
pub struct GpuCharacter {
    pub name: String,
    /// Bounding sphere over the animation, model space: centre and radius.
    pub sphere: (glam::Vec3, f32),
    /// How it is drawn (see [`DrawKind`](crate::bake::gpu_data::drawable::DrawKind)).
    pub class: DrawClass,
    /// A tree impostor's error, model units, where it shows its nearest view alone (see
    /// [`nearest_view_error`](crate::bake::impostor::nearest_view::nearest_view_error));
    /// 0 for everything else.
    pub nearest_view_error: f32,
    /// What an instance drawn with it shows, for the frame's figures.
    pub level_kind: LevelKind,
    /// Every clip as the instance data carries it.
    pub clip_rows: Vec<[f32; 4]>,
    /// The pose the plain calibration shader draws every set in: the first frame of the
    /// first clip.
    calibration_pose: Vec<glam::Affine3A>,
    anim_view: wgpu::TextureView,
    materials_view: wgpu::TextureView,
    /// The spectra texture of a spectral cloud; one empty texel for everything else (the
    /// shader reads K as a third of its width, so K = 0 there).
    spectra_view: wgpu::TextureView,
    /// An animated impostor's per-view rectangles, one texel a view (see
    /// `AnimatedFrame::rects`); one empty texel for everything else.
    rects_view: wgpu::TextureView,
    shadow_buffer: wgpu::Buffer,
    /// A billboard cloud's billboard outlines: a line-list index buffer over the full-detail
    /// vertices, and its index count.
    pub outlines: Option<(wgpu::Buffer, u32)>,
    /// Indexed by [`crate::scene::LodMethod::index`]; slot 0 (`none`) is always there.
    sets: Vec<Option<GpuLodSet>>,
    /// What the shared data above takes on the GPU (the sets count their own).
    shared_bytes: GpuMemory,
}

/// One method's levels of detail on the GPU, created once (see [`LodPack`]).
pub struct GpuLodSet {
    pub levels: Vec<PackedLevel>,
    pub index_buffer: wgpu::Buffer,
    /// A clump level's triangles by view sector: each sector's range (first index, count)
    /// in the index buffer ([`LodPack::view_subsets`]); empty for everything else.
    pub view_subsets: Vec<[u32; 2]>,
    /// How far its planes turn at wind strength 1, and the margin they were filed into
    /// sectors with ([`LodPack::view_subset_sway`]).
    pub view_subset_sway: f32,
    pub view_subset_margin: f32,
    /// The number of vertices the vertex texture holds, over all levels.
    pub vertex_count: u32,
    /// The same vertices in one fixed pose, for the plain calibration shader (it draws the
    /// same levels with the same indices).
    pub static_vertices: wgpu::Buffer,
    pub bind_group: wgpu::BindGroup,
    /// What the set takes on the GPU.
    pub bytes: GpuMemory,
}

/// Layout of group 1: animation texture, vertex texture, material layers, sampler, shadow,
/// spectra texture, an animated impostor's view rectangles, the set's normal maps.
pub fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let data_texture = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    // A filtered texture array the fragment shader samples: materials, normal maps.
    let layers = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("character"),
        entries: &[
            data_texture(0),
            data_texture(1),
            layers(2),
            wgpu::BindGroupLayoutEntry {
                binding: 3,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 4,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            data_texture(5),
            data_texture(6),
            layers(7),
        ],
    })
}

fn data_texture(gpu: &Gpu, label: &str, grid: &TexelGrid) -> wgpu::Texture {
    float_texture(gpu, label, grid.width, grid.height, grid.bytes())
}

/// An `Rgba32Float` texture the vertex shader reads with `textureLoad`.
fn float_texture(gpu: &Gpu, label: &str, width: u32, height: u32, bytes: &[u8]) -> wgpu::Texture {
    gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytes,
    )
}

/// Material layers as an sRGB texture array with their mipmaps.
pub(crate) fn material_texture(
    gpu: &Gpu,
    m: &crate::bake::gpu_data::materials::MaterialLayers,
) -> wgpu::Texture {
    gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some("materials"),
            size: wgpu::Extent3d {
                width: m.width,
                height: m.height,
                depth_or_array_layers: array_layers(gpu, m.layer_count),
            },
            mip_level_count: m.mips.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::MipMajor,
        &array_data(gpu, m.layer_count, &m.mips),
    )
}

/// The layers an array texture of `layers` is made with: as many, except on wgpu's GL backend
/// (WebGL2), which takes a texture of one layer for a plain 2D one and then cannot bind it as
/// an array: there such a texture gets two, the second a copy of the first.
fn array_layers(gpu: &Gpu, layers: u32) -> u32 {
    if layers == 1 && gpu.info.backend == wgpu::Backend::Gl {
        2
    } else {
        layers
    }
}

/// `mips` (each one level of every layer) as the texture of [`array_layers`] takes them.
/// An animated impostor's views texture, a texel a view read by index in the vertex shader
/// (indexing an array in the uniform by a per-instance index took llvmpipe five times as
/// long); after the views, each page's travel where the clips carry the character (root
/// motion: `AnimatedFrame::travel`). One blank texel for everything else.
fn impostor_views(gpu: &Gpu, bake: &Drawable) -> wgpu::Texture {
    match bake.kind.character_impostor() {
        Some(a) if !a.rects.is_empty() => {
            let texels: Vec<[f32; 4]> = (a.rects.iter().copied())
                .chain(a.travel.iter().map(|t| [t[0], t[1], t[2], 0.0]))
                .collect();
            float_texture(
                gpu,
                &format!("{} impostor views", bake.name),
                texels.len() as u32,
                1,
                bytemuck::cast_slice(&texels),
            )
        }
        _ => float_texture(gpu, "no impostor views", 1, 1, &[0; 16]),
    }
}

fn array_data(gpu: &Gpu, layers: u32, mips: &[Vec<u8>]) -> Vec<u8> {
    let copies = (array_layers(gpu, layers) / layers.max(1)) as usize;
    mips.iter().flat_map(|m| m.repeat(copies)).collect()
}

/// A set's normal maps as a linear RGBA8 texture array with their mipmaps; one flat texel
/// for a set without any.
fn normal_map_texture(
    gpu: &Gpu,
    maps: Option<&crate::bake::character::normal_map::NormalMaps>,
) -> wgpu::Texture {
    let (size, layers, mips, bytes) = match maps {
        Some(n) if n.layer_count > 0 => (
            n.size,
            n.layer_count,
            n.mips.len() as u32,
            array_data(gpu, n.layer_count, &n.mips),
        ),
        _ => (1, 1, 1, array_data(gpu, 1, &[vec![128, 128, 255, 0]])),
    };
    gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some("normal maps"),
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: array_layers(gpu, layers),
            },
            mip_level_count: mips,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::MipMajor,
        &bytes,
    )
}

impl GpuCharacter {
    /// Uploads the shared data and the full-detail set of `bake`.
    pub fn upload(
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        sampler: &wgpu::Sampler,
        bake: &Drawable,
    ) -> GpuCharacter {
        let anim = data_texture(
            gpu,
            &format!("{} animation", bake.name),
            &bake.animation.grid,
        );
        let spectra_bytes = bake.spectra.as_ref().map_or(0, |s| s.bytes().len() as u64);
        let spectra = match &bake.spectra {
            Some(s) if s.rows > 0 => float_texture(
                gpu,
                &format!("{} spectra", bake.name),
                s.width(),
                s.rows,
                s.bytes(),
            ),
            _ => float_texture(gpu, "no spectra", 1, 1, &[0; 16]),
        };
        let rects = impostor_views(gpu, bake);
        let materials = material_texture(gpu, &bake.materials);
        let material_bytes: usize = bake.materials.mips.iter().map(Vec::len).sum();
        // The blob shadow covers the footprint of the animated bounds.
        let b = bake.bounds;
        let frame = bake.kind.tree_impostor();
        let mut shadow = CharacterUniform {
            ellipse: [
                b.center().x,
                b.center().z,
                (b.size().x * 0.5).max(0.05),
                (b.size().z * 0.5).max(0.05),
            ],
            sphere: frame.map_or([0.0; 4], |f| {
                [f.centre[0], f.centre[1], f.centre[2], f.radius]
            }),
            grid: frame.map_or([0.0; 4], |f| {
                [f.frames as f32, f.rows as f32, f.base, f.height]
            }),
            cell: frame.map_or([0.0; 4], |f| {
                let texels = bake.materials.width as f32 / f.frames.max(1) as f32;
                [1.0 / texels.max(1.0), 0.0, 0.0, 0.0]
            }),
            lo: frame.map_or([0.0; 4], |f| {
                [f.bounds[0][0], f.bounds[0][1], f.bounds[0][2], 0.0]
            }),
            hi: frame.map_or([0.0; 4], |f| {
                [f.bounds[1][0], f.bounds[1][1], f.bounds[1][2], 1.0]
            }),
        };
        if let Some(a) = bake.kind.character_impostor() {
            shadow.sphere = [a.centre[0], a.centre[1], a.centre[2], a.radius];
            let travels = !a.travel.is_empty();
            shadow.grid = [
                a.views as f32,
                a.columns as f32,
                a.rows as f32,
                travels as u32 as f32,
            ];
            shadow.cell = [1.0 / a.cell.max(1) as f32, 0.0, 0.0, 0.0];
        }
        let shadow_buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("shadow"),
                contents: bytemuck::bytes_of(&shadow),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let outlines = (!bake.outlines.is_empty()).then(|| {
            let buffer = gpu
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("billboard outlines"),
                    contents: bytemuck::cast_slice(&bake.outlines),
                    usage: wgpu::BufferUsages::INDEX,
                });
            (buffer, bake.outlines.len() as u32)
        });
        let mut character = GpuCharacter {
            name: bake.name.clone(),
            sphere: (bake.bounds.center(), bake.bounds.diagonal() * 0.5),
            class: bake.kind.class(),
            nearest_view_error: frame
                .map_or(0.0, crate::bake::impostor::nearest_view::nearest_view_error),
            level_kind: bake.level_kind(),
            clip_rows: (0..bake.animation.clips.len())
                .map(|c| bake.animation.clip_rows(c))
                .collect(),
            calibration_pose: bake.animation.sample(0, 0.0),
            anim_view: anim.create_view(&Default::default()),
            materials_view: materials.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            }),
            shadow_buffer,
            spectra_view: spectra.create_view(&Default::default()),
            rects_view: rects.create_view(&Default::default()),
            shared_bytes: GpuMemory {
                animation_textures: (bake.animation.grid.texels.len() * 16) as u64,
                material_textures: material_bytes as u64,
                spectra_textures: spectra_bytes,
                other_buffers: (std::mem::size_of::<CharacterUniform>() + bake.outlines.len() * 4)
                    as u64,
                ..Default::default()
            },
            outlines,
            sets: Vec::new(),
        };
        character.add_set(gpu, layout, sampler, 0, &LodPack::full_detail(bake));
        character
    }

    /// Uploads the levels of one method into `slot`, replacing what was there.
    pub fn add_set(
        &mut self,
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        sampler: &wgpu::Sampler,
        slot: usize,
        pack: &LodPack,
    ) {
        // WebGL2 draws no base vertex: there each level's indices carry it instead.
        let mut levels = pack.levels.clone();
        let mut indices = std::borrow::Cow::Borrowed(&pack.indices[..]);
        if !gpu.draws_base_vertex() {
            let rebased = indices.to_mut();
            for l in &mut levels {
                let range = l.first_index as usize..(l.first_index + l.index_count) as usize;
                for i in &mut rebased[range] {
                    *i += l.base_vertex;
                }
                l.base_vertex = 0;
            }
            // The sectors' triangles are level 0's, with its base vertex.
            let base = pack.levels.first().map_or(0, |l| l.base_vertex);
            for &[first, count] in &pack.view_subsets {
                for i in &mut rebased[first as usize..(first + count) as usize] {
                    *i += base;
                }
            }
        }
        let verts = data_texture(gpu, &format!("{} vertices", self.name), &pack.vertices.grid);
        let index_buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("indices"),
                contents: bytemuck::cast_slice(&indices),
                usage: wgpu::BufferUsages::INDEX,
            });
        let verts_view = verts.create_view(&Default::default());
        let normal_maps = normal_map_texture(gpu, pack.normal_maps.as_ref());
        let normal_view = normal_maps.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let pose_vertices = pack.vertices.static_vertices(&self.calibration_pose);
        let static_vertices = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("static vertices"),
                contents: bytemuck::cast_slice(&pose_vertices),
                usage: wgpu::BufferUsages::VERTEX,
            });
        let bytes = GpuMemory {
            vertex_textures: (pack.vertices.grid.texels.len() * 16) as u64,
            index_buffers: (pack.indices.len() * 4) as u64,
            calibration_vertices: std::mem::size_of_val(pose_vertices.as_slice()) as u64,
            normal_maps: pack.normal_maps.as_ref().map_or(0, |n| n.bytes() as u64),
            ..Default::default()
        };
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&self.name),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&self.anim_view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&verts_view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&self.materials_view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::Sampler(sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: self.shadow_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: wgpu::BindingResource::TextureView(&self.spectra_view),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: wgpu::BindingResource::TextureView(&self.rects_view),
                },
                wgpu::BindGroupEntry {
                    binding: 7,
                    resource: wgpu::BindingResource::TextureView(&normal_view),
                },
            ],
        });
        if self.sets.len() <= slot {
            self.sets.resize_with(slot + 1, || None);
        }
        self.sets[slot] = Some(GpuLodSet {
            levels,
            index_buffer,
            view_subsets: pack.view_subsets.clone(),
            view_subset_sway: pack.view_subset_sway,
            view_subset_margin: pack.view_subset_margin,
            vertex_count: pack.vertices.vertex_count,
            static_vertices,
            bind_group,
            bytes,
        });
    }

    /// What the character holds on the GPU: its shared data and every set.
    pub fn bytes(&self) -> GpuMemory {
        let mut total = self.shared_bytes;
        for set in self.sets.iter().flatten() {
            total += set.bytes;
        }
        total
    }

    /// The set in `slot`, if uploaded.
    pub fn set(&self, slot: usize) -> Option<&GpuLodSet> {
        self.sets.get(slot).and_then(Option::as_ref)
    }

    /// The full-detail set.
    pub fn full(&self) -> &GpuLodSet {
        self.set(0)
            .expect("the full-detail set is uploaded with the character")
    }
}
