//! What lighting billboards through their atlases buys: each level of a tree drawn beside the
//! full tree under two suns, its billboards lit as one (each by its leaves' mean normal; the thesis
//! lit each by its plane) and per texel by
//! the leaves' normals (see `bake::billboard::atlas`); the crown's occlusion darkens both.
//!
//! Two numbers per picture pair, each a mean over the three channels in 0..1:
//! - *shading*: the colour difference over the pixels both pictures cover: how each bit of
//!   crown is lit, leaving out where the level's coverage differs (the colour error's
//!   business);
//! - *tone*: the difference of the two pictures' mean colours over what each covers: how
//!   light or dark the tree reads as a whole from afar.
//!
//! Both from five views round the tree 15° above the ground at two times of its loop.

use super::colour_error::{METRIC_VIEWS, covers, framing, metric_camera, metric_world, picture};
use super::impostor_fit::PITCH_DEG;
use crate::bake::foliage::billboard::chain::CloudLevel;
use crate::model::Model;
use crate::render::Gpu;
use crate::render::targets::Offscreen;
use crate::runtime::spec::Loaded;
use anyhow::Result;
use glam::Vec3;
use serde::Serialize;

/// The two suns: the scene's own, high in the south-west, and a low sun from the opposite
/// side, which lights the crown's other face and grazes its top.
pub fn suns() -> [(&'static str, Vec3); 2] {
    [
        ("high", crate::render::Lighting::default().sun_dir),
        ("low, opposite", Vec3::new(0.6, 0.25, -0.75).normalize()),
    ]
}

/// Times of the loop each view is drawn at.
const FRAMES: usize = 2;

/// A level against the full tree under one sun, by the two measures of the module comment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Difference {
    pub shading: f32,
    pub tone: f32,
}

/// One level under one sun: its billboards lit by their planes and through their atlases.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LevelLighting {
    pub level: usize,
    pub sun: String,
    pub flat: Difference,
    pub atlas: Difference,
}

/// The differences of `levels` (index, level) of `tree` from the full tree, drawn whole (wood
/// and all) `px` pixels high, under both [`suns`].
pub fn foliage_lighting(
    gpu: &Gpu,
    tree: &Model,
    levels: &[(usize, &CloudLevel)],
    px: f32,
) -> Result<Vec<LevelLighting>> {
    let Some(&(_, first)) = levels.first() else {
        return Ok(Vec::new());
    };
    let bake = |l: &CloudLevel| {
        l.bake()
            .map_err(|e| anyhow::anyhow!("{}: {e}", l.model.name))
    };
    let mut full = metric_world(gpu, Loaded::forest_of(tree, None, 1)?)?;
    let mut level = metric_world(gpu, Loaded::forest_of_bake(&first.model, bake(first)?, 1))?;
    let (size, distance) = framing(px);
    let target = Offscreen::new(gpu, size[0], size[1], 1);
    let bounds = full.bakes[0].bounds;
    let height = bounds.size().y.max(1e-3);
    let duration = tree.clips.first().map_or(1.0, |c| c.duration);
    let mut out = Vec::new();
    for (i, &(k, l)) in levels.iter().enumerate() {
        if i > 0 {
            let b = bake(l)?;
            level.renderer.replace_character(gpu, 0, &b)?;
            level.bakes[0] = b;
        }
        for (name, sun) in suns() {
            full.renderer.lighting.sun_dir = sun;
            level.renderer.lighting.sun_dir = sun;
            let mut sums = [Sums::default(), Sums::default()];
            for view in 0..METRIC_VIEWS {
                let yaw = 360.0 * view as f32 / METRIC_VIEWS as f32;
                let camera = metric_camera(bounds.center(), height, yaw, PITCH_DEG, distance);
                let background = picture(gpu, &mut full, &target, camera, 0.0, true)?;
                for frame in 0..FRAMES {
                    let t = duration * frame as f32 / FRAMES as f32;
                    let reference = picture(gpu, &mut full, &target, camera, t, false)?;
                    for (lit, s) in sums.iter_mut().enumerate() {
                        level.renderer.atlas_lighting = lit == 1;
                        let other = picture(gpu, &mut level, &target, camera, t, false)?;
                        s.add(&reference, &other, &background);
                    }
                }
            }
            out.push(LevelLighting {
                level: k,
                sun: name.into(),
                flat: sums[0].difference(),
                atlas: sums[1].difference(),
            });
        }
    }
    Ok(out)
}

/// Running sums of one comparison over several picture pairs.
#[derive(Default)]
struct Sums {
    /// Pixels both cover, and their colour differences summed.
    both: u64,
    off: f64,
    /// Per picture (full, level): pixels covered and their colours summed.
    covered: [u64; 2],
    colour: [[f64; 3]; 2],
}

impl Sums {
    /// A pixel is covered where it differs from `background` (the same view, empty; see
    /// [`covers`]).
    fn add(
        &mut self,
        full: &image::RgbaImage,
        other: &image::RgbaImage,
        background: &image::RgbaImage,
    ) {
        for ((a, b), bg) in full.pixels().zip(other.pixels()).zip(background.pixels()) {
            let (ia, ib) = (covers(a, bg), covers(b, bg));
            for (j, (p, covered)) in [(a, ia), (b, ib)].into_iter().enumerate() {
                if covered {
                    self.covered[j] += 1;
                    for c in 0..3 {
                        self.colour[j][c] += p[c] as f64 / 255.0;
                    }
                }
            }
            if ia && ib {
                self.both += 1;
                self.off += (0..3).map(|i| a[i].abs_diff(b[i]) as f64).sum::<f64>() / (3.0 * 255.0);
            }
        }
    }

    fn difference(&self) -> Difference {
        let mean = |j: usize| {
            let n = self.covered[j].max(1) as f64;
            self.colour[j].map(|c| c / n)
        };
        let (a, b) = (mean(0), mean(1));
        Difference {
            shading: (self.off / self.both.max(1) as f64) as f32,
            tone: ((0..3).map(|c| (a[c] - b[c]).abs()).sum::<f64>() / 3.0) as f32,
        }
    }
}
