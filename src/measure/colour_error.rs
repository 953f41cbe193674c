//! The colour error of a tree's level against the full tree (Bennett-Therkildsen, Carlsen &
//! Schmid's thesis "Animated Billboard Clouds for Foliage Simplification" (2007) §5.1.3), measured
//! by drawing both in worlds of their own.

use crate::bake::foliage::billboard::chain::CloudLevel;
use crate::bake::gpu_data::drawable::Drawable;
use crate::model::Model;
use crate::render::Gpu;
use crate::render::targets::{OFFSCREEN_FORMAT, Offscreen};
use crate::runtime::spec::Loaded;
use crate::runtime::world::World;
use anyhow::Result;

/// Views and frames of the colour metric (thesis §5.1.3): five views evenly round the tree at
/// ground level, at five times over the loop.
pub const METRIC_VIEWS: usize = 5;
pub const METRIC_FRAMES: usize = 5;

/// The colour error of `lod` against `original` (thesis §5.1.3): binary masks of where the
/// foliage (the original's leaves, the level's billboards; wood left out) covers the image, at
/// `size`, from [`METRIC_VIEWS`] views round it at ground level and [`METRIC_FRAMES`] times of
/// its loop; of the pixels either mask covers, the share on which they disagree, over all of
/// them. 0 for identical trees, 1 for trees that cover no pixel in common.
///
/// The thesis divides the disagreeing pixels by the original's covered pixels alone
/// (`E = Σ|o − s| / P_f`), which exceeds 1 wherever a level covers more than twice what the
/// tree does (a palm's thin fronds drawn small, their cloud or impostor a solid blot), and
/// drops such figures as "no fidelity". Dividing by the pixels either covers (the Jaccard
/// distance of the two masks) bounds it by 1, and for a level close to the tree it is the
/// thesis's figure to within the few pixels the level adds.
pub fn colour_error(gpu: &Gpu, original: &Model, lod: &CloudLevel, size: [u32; 2]) -> Result<f32> {
    colour_error_over(gpu, original, lod, size, METRIC_FRAMES)
}

/// [`colour_error`] at `frames` times of the loop (1: the thesis's static colour metric).
pub fn colour_error_over(
    gpu: &Gpu,
    original: &Model,
    lod: &CloudLevel,
    size: [u32; 2],
    frames: usize,
) -> Result<f32> {
    Ok(foliage_disagreement(gpu, original, lod, &[(size, FRAMING)], frames)?[0])
}

/// A level's colour errors where it comes in: see [`at_switch`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwitchErrors {
    /// [`colour_error`]: at the metric's size, seen [`FRAMING`] heights off.
    pub close: f32,
    /// At the metric's size, seen from as far off as a tree `height_px` high stands (see
    /// [`framing`]), the field of view narrowed to fill the picture alike: the level's shapes
    /// as they stand where it comes in (nearly orthographic for a distant level), looked at as
    /// closely as the thesis's 800×600 pictures. A level is never seen from nearer than
    /// that, so the perspective of a close view is not held against it; its atlas, sized for
    /// where it comes in, is magnified as much, so its blur is.
    pub from_switch: f32,
    /// With the tree drawn `height_px` pixels high, seen from as far off: the level at its
    /// switch size, as a viewer sees it.
    pub at_switch: f32,
}

/// The colour errors of `lod` against `original` at `size`, and where the tree is drawn
/// `height_px` pixels high (see [`SwitchErrors`]), all from one pair of worlds.
pub fn at_switch(
    gpu: &Gpu,
    original: &Model,
    lod: &CloudLevel,
    size: [u32; 2],
    height_px: f32,
) -> Result<SwitchErrors> {
    let (small, distance) = framing(height_px);
    let e = foliage_disagreement(
        gpu,
        original,
        lod,
        &[(size, FRAMING), (size, distance), (small, distance)],
        METRIC_FRAMES,
    )?;
    Ok(SwitchErrors {
        close: e[0],
        from_switch: e[1],
        at_switch: e[2],
    })
}

/// The colour error of `lod` against `original` for every `(size, distance)` of `pictures`.
fn foliage_disagreement(
    gpu: &Gpu,
    original: &Model,
    lod: &CloudLevel,
    pictures: &[([u32; 2], f32)],
    frames: usize,
) -> Result<Vec<f32>> {
    // Masks only: the original's leaves are baked without the crown's occlusion, which would
    // darken them and cost a crown's worth of rays a measurement.
    let (leaves, bake) = CloudLevel::full(original)
        .foliage_bake()
        .map_err(anyhow::Error::msg)?;
    let mut a = metric_world(gpu, Loaded::forest_of_bake(&leaves, bake, 1))?;
    let (lod_foliage, lod_bake) = lod.foliage_bake().map_err(anyhow::Error::msg)?;
    let mut b = metric_world(gpu, Loaded::forest_of_bake(&lod_foliage, lod_bake, 1))?;
    pictures
        .iter()
        .map(|&(size, distance)| {
            disagreement(gpu, &mut a, &mut b, original, size, frames, distance)
        })
        .collect()
}

/// The colour error of `level` against the whole of `tree`, wood and all, both drawn about
/// `height_px` pixels high: how a level is judged at the size where it comes in. Levels of
/// any kind, impostors included, compare alike.
pub fn whole_tree_error(
    gpu: &Gpu,
    tree: &Model,
    level: &CloudLevel,
    height_px: f32,
) -> Result<f32> {
    use crate::bake::gpu_products::MeasureColour;
    let bake = level
        .bake()
        .map_err(|e| anyhow::anyhow!("{}: {e}", level.model.name))?;
    let errors = GpuColourError::new(gpu).colour_errors(tree, &level.model, bake, &[height_px])?;
    Ok(errors[0])
}

/// The screen height [`whole_tree_error`] places a tree on, pixels.
const SCREEN_PX: f32 = 720.0;

/// [`whole_tree_error`] as the chain's bake asks for it, many times over for one tree: the
/// full tree's world is made once, and the level's world once, its character replaced level
/// by level (making a world builds every pipeline, most of a measurement's cost on a CPU).
pub struct GpuColourError<'g> {
    gpu: &'g Gpu,
    worlds: std::sync::Mutex<Option<Measuring>>,
}

/// The worlds of the tree being measured: its name, the full tree's and the level's.
struct Measuring {
    tree: String,
    original: World,
    level: World,
}

impl<'g> GpuColourError<'g> {
    pub fn new(gpu: &'g Gpu) -> Self {
        GpuColourError {
            gpu,
            worlds: std::sync::Mutex::new(None),
        }
    }
}

impl GpuColourError<'_> {
    /// How many times over `level` (drawn as `bake`, `height_px` high, from the metric's
    /// views) shades the pixels it covers: its foliage pass's fragments over the pixels that
    /// pass covers drawn alone, summed over the views. None where the adapter cannot count
    /// fragments.
    pub fn fragments_per_covered_pixel(
        &self,
        tree: &Model,
        level: &Model,
        bake: Drawable,
        height_px: f32,
    ) -> Result<Option<f64>> {
        use crate::render::timer::{FrameTimer, Pass};
        let gpu = self.gpu;
        let Some(mut timer) = FrameTimer::new(gpu) else {
            return Ok(None);
        };
        let mut worlds = self.worlds(tree, level, bake)?;
        let m = worlds.as_mut().expect("just made");
        let bounds = m.original.bakes[0].bounds;
        let (size, distance) = framing(height_px);
        let target = Offscreen::new(gpu, size[0], size[1], 1);
        let (mut fragments, mut covered) = (0u64, 0u64);
        for camera in metric_views(bounds, size, distance) {
            m.level.camera = camera;
            m.level.prepare(gpu, size, 0.0, 0.0);
            m.level
                .renderer
                .render_timed(gpu, &target.targets, &target.view, Some(&mut timer))?;
            let times = timer.read(gpu)?;
            if times.ms[Pass::Foliage as usize].is_none() {
                continue;
            }
            let Some(f) = times.fragments[Pass::Foliage as usize] else {
                return Ok(None);
            };
            fragments += f;
            covered += crate::measure::coverage::covered_pixels(
                gpu,
                &m.level.renderer,
                &target,
                Pass::Foliage,
            )?;
        }
        Ok((covered > 0).then(|| fragments as f64 / covered as f64))
    }

    /// The worlds of `tree` with `level` (drawn as `bake`) in the level's: made for a new
    /// tree, the level's character replaced for the same tree.
    fn worlds(
        &self,
        tree: &Model,
        level: &Model,
        bake: Drawable,
    ) -> Result<std::sync::MutexGuard<'_, Option<Measuring>>> {
        let gpu = self.gpu;
        let mut worlds = self
            .worlds
            .lock()
            .map_err(|_| anyhow::anyhow!("a colour measurement failed midway"))?;
        match worlds.as_mut() {
            Some(m) if m.tree == tree.name => {
                m.level.renderer.replace_character(gpu, 0, &bake)?;
                m.level.bakes[0] = bake;
            }
            _ => {
                *worlds = Some(Measuring {
                    tree: tree.name.clone(),
                    original: metric_world(gpu, Loaded::forest_of(tree, None, 1)?)?,
                    level: metric_world(gpu, Loaded::forest_of_bake(level, bake, 1))?,
                });
            }
        }
        Ok(worlds)
    }
}

impl crate::bake::gpu_products::MeasureColour for GpuColourError<'_> {
    fn fragments(
        &self,
        tree: &Model,
        level: &Model,
        bake: Drawable,
        heights_px: &[f32],
    ) -> Result<Option<Vec<f64>>> {
        let gpu = self.gpu;
        let Some(mut timer) = crate::render::timer::FrameTimer::new(gpu) else {
            return Ok(None);
        };
        let mut worlds = self.worlds(tree, level, bake)?;
        let m = worlds.as_mut().expect("just made");
        let bounds = m.original.bakes[0].bounds;
        let mut out = Vec::with_capacity(heights_px.len());
        for &px in heights_px {
            let (size, distance) = framing(px);
            let target = Offscreen::new(gpu, size[0], size[1], 1);
            let mut sum = 0.0;
            for camera in metric_views(bounds, size, distance) {
                m.level.camera = camera;
                m.level.prepare(gpu, size, 0.0, 0.0);
                m.level.renderer.render_timed(
                    gpu,
                    &target.targets,
                    &target.view,
                    Some(&mut timer),
                )?;
                let times = timer.read(gpu)?;
                // The level's own passes: the sky and ground behind it are not its cost.
                for pass in crate::render::timer::Pass::ALL {
                    if pass == crate::render::timer::Pass::Environment
                        || times.ms[pass as usize].is_none()
                    {
                        continue;
                    }
                    let Some(f) = times.fragments[pass as usize] else {
                        return Ok(None);
                    };
                    sum += f as f64;
                }
            }
            out.push(sum / METRIC_VIEWS as f64);
        }
        Ok(Some(out))
    }

    fn colour_errors(
        &self,
        tree: &Model,
        level: &Model,
        bake: Drawable,
        heights_px: &[f32],
    ) -> Result<Vec<f32>> {
        let gpu = self.gpu;
        let mut worlds = self.worlds(tree, level, bake)?;
        let m = worlds.as_mut().expect("just made");
        heights_px
            .iter()
            .map(|&px| {
                let (size, distance) = framing(px);
                disagreement(
                    gpu,
                    &mut m.original,
                    &mut m.level,
                    tree,
                    size,
                    METRIC_FRAMES,
                    distance,
                )
            })
            .collect()
    }
}

/// The image size and the camera's distance (in tree heights) at which [`whole_tree_error`]
/// sees a tree `height_px` pixels high (and `impostor_fit` a character).
pub(crate) fn framing(height_px: f32) -> ([u32; 2], f32) {
    // The metric's camera frames the tree's height in this share of the image.
    let fov = crate::scene::Camera::new(glam::Vec3::ZERO, 0.0, 0.0, 1.0).fov_y;
    let screen = 2.0 * (fov * 0.5).tan();
    let side = (height_px * FRAMING * screen).ceil().clamp(8.0, 2048.0) as u32;
    // Seen from where a tree that high stands on a 720-pixel-high screen: far off, nearly
    // orthographic, as the level will be seen (a flat impostor drawn 1.25 heights away would
    // be judged by a perspective no one sees it in).
    let distance = (SCREEN_PX / height_px.max(1.0) / screen).clamp(FRAMING, 100.0);
    ([side, side], distance)
}

/// Whether a metric's picture covers a pixel: its colour there `x` differs from the same
/// view's empty picture `bg` by more than the renderer's noise in some channel.
pub(crate) fn covers(x: &image::Rgba<u8>, bg: &image::Rgba<u8>) -> bool {
    (0..3).any(|c| x[c].abs_diff(bg[c]) > 10)
}

/// A world of its own for one tree, as the metric draws it: no shadows, no fog (however far
/// off the camera stands, the masks see the whole tree).
pub(crate) fn metric_world(gpu: &Gpu, loaded: Loaded) -> Result<World> {
    let mut w = World::new(gpu, loaded, OFFSCREEN_FORMAT, 1)?;
    w.renderer.shadows = false;
    w.renderer.lighting.fog_density = 0.0;
    Ok(w)
}

/// The metric's camera stands this many tree heights away.
pub(crate) const FRAMING: f32 = 1.25;

/// `w`'s one model (`centre` and `height` its bounds') seen from `yaw` round it and `pitch`
/// above, looking at its centre (a crown's, where only the foliage is drawn, not the point
/// half its height above the ground), `distance` heights off, the field of view narrowed to
/// frame it as from [`FRAMING`] heights.
pub(crate) fn metric_camera(
    centre: glam::Vec3,
    height: f32,
    yaw: f32,
    pitch: f32,
    distance: f32,
) -> crate::scene::Camera {
    let mut camera = crate::scene::Camera::new(centre, yaw, pitch, height * distance);
    camera.fov_y = 2.0 * ((camera.fov_y * 0.5).tan() * FRAMING / distance).atan();
    camera
}

/// `w` drawn into `target` from `camera` at time `t`; with `empty`, without its instances
/// (the background).
pub(crate) fn picture(
    gpu: &Gpu,
    w: &mut World,
    target: &Offscreen,
    camera: crate::scene::Camera,
    t: f32,
    empty: bool,
) -> Result<image::RgbaImage> {
    w.camera = camera;
    if empty {
        w.relayout(None, 0, None);
    }
    w.prepare(
        gpu,
        [target.texture.width(), target.texture.height()],
        t,
        0.0,
    );
    w.renderer.render_to(gpu, &target.targets, &target.view)?;
    let img = target.read_rgba(gpu);
    if empty {
        w.relayout(None, 1, None);
    }
    img
}

/// The metric's [`METRIC_VIEWS`] cameras round a tree of `bounds` for a `size` picture,
/// `distance` tree heights off: at ground level, far enough for the whole tree to fit with a
/// margin.
fn metric_views(
    bounds: crate::model::Bounds,
    size: [u32; 2],
    distance: f32,
) -> impl Iterator<Item = crate::scene::Camera> {
    // The whole tree in every view: its height, or its widest span across (seen from any
    // side, at most the diagonal of its bounds' footprint) if that fills the width sooner.
    let span = glam::Vec2::new(bounds.size().x, bounds.size().z).length();
    let height = bounds
        .size()
        .y
        .max(span * size[1] as f32 / size[0] as f32)
        .max(1e-3);
    (0..METRIC_VIEWS).map(move |view| {
        let yaw = 360.0 * view as f32 / METRIC_VIEWS as f32;
        metric_camera(bounds.center(), height, yaw, 0.0, distance)
    })
}

/// Of the pixels `a` or `b` covers, the share on which they disagree (see [`colour_error`]);
/// `original` gives the loop's length. The camera stands `distance` tree heights off, its field of view
/// narrowed to frame the tree as from [`FRAMING`] heights.
fn disagreement(
    gpu: &Gpu,
    a: &mut World,
    b: &mut World,
    original: &Model,
    size: [u32; 2],
    frames: usize,
    distance: f32,
) -> Result<f32> {
    let target = Offscreen::new(gpu, size[0], size[1], 1);
    let bounds = a.bakes[0].bounds;
    let duration = original.clips.first().map_or(1.0, |c| c.duration);
    let (mut wrong, mut either) = (0u64, 0u64);
    let shoot = |w: &mut World, camera, t, empty| picture(gpu, w, &target, camera, t, empty);
    for camera in metric_views(bounds, size, distance) {
        let background = shoot(a, camera, 0.0, true)?;
        for frame in 0..frames.max(1) {
            let t = duration * frame as f32 / frames.max(1) as f32;
            let ia = shoot(a, camera, t, false)?;
            let ib = shoot(b, camera, t, false)?;
            for ((p, q), bg) in ia.pixels().zip(ib.pixels()).zip(background.pixels()) {
                let (ma, mb) = (covers(p, bg), covers(q, bg));
                either += (ma || mb) as u64;
                wrong += (ma != mb) as u64;
            }
        }
    }
    Ok(wrong as f32 / either.max(1) as f32)
}
