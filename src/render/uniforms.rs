//! CPU mirrors of the WGSL structs: the per-frame uniform block and the per-instance data.

use glam::{Affine3A, Mat4, Vec3, Vec4};

/// Mirror of `Frame` in `shaders/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub camera_pos: [f32; 4],
    pub sun_dir: [f32; 4],
    pub sun_color: [f32; 4],
    pub sky_zenith: [f32; 4],
    pub sky_horizon: [f32; 4],
    pub ground_bounce: [f32; 4],
    pub fog: [f32; 4],
    pub time: [f32; 4],
    /// Debug view of everything, of foliage, and the capture target's size: see `views` in
    /// `Frame`.
    pub views: [u32; 4],
}

/// Light and atmosphere of the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Unit vector towards the sun.
    pub sun_dir: Vec3,
    pub sun_intensity: f32,
    pub sun_color: Vec3,
    pub sky_zenith: Vec3,
    pub sky_horizon: Vec3,
    pub ground_bounce: Vec3,
    /// Fog density per metre beyond `fog_start` metres.
    pub fog_density: f32,
    pub fog_start: f32,
}

impl Default for Lighting {
    fn default() -> Self {
        Lighting {
            sun_dir: Vec3::new(-0.45, 0.75, 0.5).normalize(),
            sun_intensity: 1.0,
            sun_color: Vec3::new(1.0, 0.93, 0.82) * 1.15,
            sky_zenith: Vec3::new(0.20, 0.40, 0.74),
            sky_horizon: Vec3::new(0.70, 0.78, 0.86),
            ground_bounce: Vec3::new(0.22, 0.21, 0.18),
            fog_density: 0.003,
            fog_start: 40.0,
        }
    }
}

/// What one frame looks at: camera and time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameView {
    pub view: Mat4,
    pub proj: Mat4,
    pub eye: Vec3,
    /// Scene time in seconds; instance animation time is `time · speed + offset`.
    pub time: f32,
}

impl FrameView {
    pub fn from_camera(camera: &crate::scene::Camera, aspect: f32, time: f32) -> Self {
        FrameView {
            view: camera.view(),
            proj: camera.proj(aspect),
            eye: camera.eye(),
            time,
        }
    }
}

impl FrameUniforms {
    /// `views`: the debug view of everything and of foliage (as `DebugView::shader_mode`), and
    /// the capture pass's target size (0 elsewhere).
    pub fn new(view: &FrameView, light: &Lighting, views: [u32; 4]) -> Self {
        let vp = view.proj * view.view;
        let v4 = |v: Vec3, w: f32| v.extend(w).to_array();
        FrameUniforms {
            view_proj: vp.to_cols_array_2d(),
            inv_view_proj: vp.inverse().to_cols_array_2d(),
            camera_pos: v4(view.eye, 1.0),
            sun_dir: v4(light.sun_dir, light.sun_intensity),
            sun_color: v4(light.sun_color, 0.0),
            sky_zenith: v4(light.sky_zenith, 0.0),
            sky_horizon: v4(light.sky_horizon, 0.0),
            ground_bounce: v4(light.ground_bounce, 0.0),
            fog: [light.fog_density, light.fog_start, 0.0, 0.0],
            time: [view.time, 0.0, 0.0, 0.0],
            views,
        }
    }
}

/// Mirror of `Instance` in `shaders/skinning.wgsl`: 144 bytes per instance.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuInstance {
    pub rows: [[f32; 4]; 3],
    /// The clip as a frame range: [`crate::bake::gpu_data::anim_texture::AnimationTexture::clip_rows`].
    pub clip: [f32; 4],
    /// Time offset in seconds, playback speed, wind strength (1: the clip as it is), and x of
    /// where its clip has carried it (`Instance::travel`, for its blob shadow).
    pub timing: [f32; 4],
    pub tint: [f32; 4],
    /// Level of detail: transition t (−1 outside transitions), geomorph hops, [`Cover`]
    /// (encoded), level. Written by [`GpuInstance::set_lod`].
    pub lod: [f32; 4],
    /// A cross-fade's second clip as a frame range (as `clip`).
    pub clip2: [f32; 4],
    /// The second clip's time offset and playback speed, and its weight (0: no cross-fade);
    /// z of where its clip has carried it (see `timing`).
    pub fade: [f32; 4],
}

impl GpuInstance {
    pub fn new(
        transform: &Affine3A,
        clip_rows: [f32; 4],
        time_offset: f32,
        speed: f32,
        tint: Vec4,
    ) -> Self {
        let m = transform.matrix3;
        let t = transform.translation;
        GpuInstance {
            rows: [
                [m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x],
                [m.x_axis.y, m.y_axis.y, m.z_axis.y, t.y],
                [m.x_axis.z, m.y_axis.z, m.z_axis.z, t.z],
            ],
            clip: clip_rows,
            timing: [time_offset, speed, 1.0, 0.0],
            tint: tint.to_array(),
            lod: [-1.0, 0.0, 1.0, 0.0],
            clip2: clip_rows,
            fade: [0.0; 4],
        }
    }

    /// Cross-fades towards clip `clip_rows` (played at `scene time · speed + time_offset`) by
    /// `weight` (0: this instance's own clip alone, 1: the other alone).
    pub fn with_fade(
        mut self,
        clip_rows: [f32; 4],
        time_offset: f32,
        speed: f32,
        weight: f32,
    ) -> Self {
        self.clip2 = clip_rows;
        self.fade = [time_offset, speed, weight.clamp(0.0, 1.0), 0.0];
        self
    }

    /// Draws level `level` (its debug colour), `hops` levels of geomorph beyond it, at `t`
    /// into its transition (None: in none), covering `cover` of its pixels.
    pub fn set_lod(&mut self, level: usize, hops: usize, t: Option<f32>, cover: Cover) {
        self.lod = [t.unwrap_or(-1.0), hops as f32, cover.encode(), level as f32];
    }

    /// Locations 7–9 belong to the plain calibration shader's own vertex buffer.
    pub const ATTRIBUTES: [wgpu::VertexAttribute; 9] = wgpu::vertex_attr_array![
        0 => Float32x4, 1 => Float32x4, 2 => Float32x4, 3 => Float32x4, 4 => Float32x4,
        5 => Float32x4, 6 => Float32x4, 10 => Float32x4, 11 => Float32x4
    ];

    pub fn layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<GpuInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &Self::ATTRIBUTES,
        }
    }
}

/// How much of an instance's level is drawn: the third number of [`GpuInstance::lod`], which
/// the shaders read as an opacity or as a screen-door coverage by the pipeline that draws
/// it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cover {
    /// Every pixel, opaque.
    Whole,
    /// Every pixel at this opacity: the faded level of an alpha blend, which only the
    /// transitions pass's blended pipelines draw.
    Opacity(f32),
    /// The pixels whose screen-door threshold lies below this share: the incoming half of a
    /// dissolve or of a dithered cross-fade.
    Incoming(f32),
    /// The pixels an `Incoming` half of the same share leaves: the outgoing half.
    Outgoing(f32),
}

impl Cover {
    /// As the shaders read it (`screened_out_at` in `shaders/character.wgsl`): a coverage
    /// c ≥ 0 keeps the pixels whose threshold lies below c, and c < 0 those at or above
    /// −c − 1; so `Whole` (1) keeps every pixel and the two halves of a share are
    /// complementary. The blended pipelines read an opacity in [0, 1] as it is.
    pub fn encode(self) -> f32 {
        match self {
            Cover::Whole => 1.0,
            Cover::Opacity(a) => a.clamp(0.0, 1.0),
            Cover::Incoming(p) => p.clamp(0.0, 1.0),
            Cover::Outgoing(p) => -1.0 - p.clamp(0.0, 1.0),
        }
    }
}

/// Vertex layout of [`crate::bake::gpu_data::vertex_texture::StaticVertex`] for the plain calibration shader.
pub const STATIC_VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 3] =
    wgpu::vertex_attr_array![7 => Float32x3, 8 => Float32x3, 9 => Float32x2];

pub fn static_vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<crate::bake::gpu_data::vertex_texture::StaticVertex>()
            as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &STATIC_VERTEX_ATTRIBUTES,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_match_wgsl() {
        // Two matrices and nine vec4s (the last, `views`, of u32s), as `Frame` in common.wgsl.
        assert_eq!(std::mem::size_of::<FrameUniforms>(), 2 * 64 + 9 * 16);
        assert_eq!(std::mem::size_of::<GpuInstance>(), 144);
    }

    /// The shaders' screen-door rule on encoded covers: the two halves of every share cover
    /// each pixel exactly once, and `Whole` every pixel.
    #[test]
    fn halves_of_a_cover_are_complementary() {
        let out = |x: f32, c: f32| if c < 0.0 { x < -c - 1.0 } else { x >= c };
        for share in [0.0, 0.3, 0.5, 1.0] {
            for x in [0.0, 0.1, 0.29, 0.3, 0.7, 0.999] {
                let kept = [Cover::Incoming(share), Cover::Outgoing(share)]
                    .iter()
                    .filter(|c| !out(x, c.encode()))
                    .count();
                assert_eq!(kept, 1, "share {share}, threshold {x}");
                assert!(!out(x, Cover::Whole.encode()));
            }
        }
    }

    #[test]
    fn instance_rows_transform_like_the_affine() {
        let a = Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_y(0.7),
            Vec3::new(1.0, 2.0, 3.0),
        );
        let i = GpuInstance::new(&a, [0.0; 4], 0.0, 1.0, Vec4::ONE);
        let p = Vec3::new(0.3, -0.2, 0.9);
        let r = |k: usize| Vec4::from(i.rows[k]).dot(p.extend(1.0));
        let q = Vec3::new(r(0), r(1), r(2));
        assert!((q - a.transform_point3(p)).length() < 1e-6);
    }
}
