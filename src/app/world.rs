//! Building a scene for the front ends: load the models, bake them, lay out the crowd, place the
//! camera. Shared by the viewer, `shot` and the tests, so they all show the same thing.

use crate::bake::CharacterBake;
use crate::import::load_model;
use crate::render::{Gpu, SceneRenderer};
use crate::scene::{Camera, Crowd, CrowdConfig, CrowdModel, Instance};
use anyhow::{Result, bail};
use glam::Vec3;

/// Scenes lodlab knows.
pub const SCENES: &[&str] = &["crowd"];

/// Models of the default crowd.
pub const DEFAULT_MODELS: &[&str] = &["horse", "walker"];

/// What to show.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneSpec {
    pub scene: String,
    /// Built-in asset names or glTF paths; empty means the scene's default.
    pub models: Vec<String>,
    pub count: usize,
    /// Play this clip (by name) on every model that has it.
    pub clip: Option<String>,
    pub seed: u64,
}

impl Default for SceneSpec {
    fn default() -> Self {
        SceneSpec {
            scene: "crowd".into(),
            models: Vec::new(),
            count: 300,
            clip: None,
            seed: 1,
        }
    }
}

/// Loads and bakes the models a spec names, in order.
pub fn load_characters(spec: &SceneSpec) -> Result<Vec<CharacterBake>> {
    if !SCENES.contains(&spec.scene.as_str()) {
        bail!(
            "unknown scene '{}' (scenes: {})",
            spec.scene,
            SCENES.join(", ")
        );
    }
    let names: Vec<String> = if spec.models.is_empty() {
        DEFAULT_MODELS.iter().map(|s| s.to_string()).collect()
    } else {
        spec.models.clone()
    };
    names
        .iter()
        .map(|name| {
            let model = load_model(name)?;
            CharacterBake::new(&model).map_err(|e| anyhow::anyhow!("{name}: {e}"))
        })
        .collect()
}

/// The crowd for a spec over already-loaded characters: all of them, or only character
/// `only`. Agents refer to characters by their index in `bakes`.
pub fn layout_crowd(spec: &SceneSpec, bakes: &[CharacterBake], only: Option<usize>) -> Crowd {
    let chosen: Vec<usize> = match only {
        Some(m) if m < bakes.len() => vec![m],
        _ => (0..bakes.len()).collect(),
    };
    let crowd_models: Vec<CrowdModel> = chosen
        .iter()
        .map(|&m| {
            let b = &bakes[m];
            CrowdModel {
                clip_speeds: b.animation.clips.iter().map(|c| c.ground_speed).collect(),
                bounds: b.bounds,
            }
        })
        .collect();
    // A clip is chosen by name, model by model: models without it play a mix.
    let clips = chosen
        .iter()
        .map(|&m| {
            spec.clip.as_ref().and_then(|wanted| {
                bakes[m]
                    .animation
                    .clips
                    .iter()
                    .position(|c| c.name.eq_ignore_ascii_case(wanted))
            })
        })
        .collect();
    let mut crowd = Crowd::layout(
        &crowd_models,
        &CrowdConfig {
            count: spec.count,
            seed: spec.seed,
            clips,
        },
    );
    for a in &mut crowd.agents {
        a.model = chosen[a.model];
    }
    crowd
}

/// Checks that a requested clip exists on at least one model.
pub fn check_clip(spec: &SceneSpec, bakes: &[CharacterBake]) -> Result<()> {
    if let Some(wanted) = &spec.clip {
        let found = bakes.iter().any(|b| {
            b.animation
                .clips
                .iter()
                .any(|c| c.name.eq_ignore_ascii_case(wanted))
        });
        if !found {
            let all: Vec<String> = bakes
                .iter()
                .flat_map(|b| {
                    b.clip_names()
                        .into_iter()
                        .map(|c| format!("{}/{c}", b.name))
                })
                .collect();
            bail!(
                "no model has a clip named '{wanted}' (clips: {})",
                all.join(", ")
            );
        }
    }
    Ok(())
}

/// A camera that shows the crowd: standing a little above head height at its south-east edge
/// and looking across it, so that characters are seen at every distance from near to far.
pub fn default_camera(crowd: &Crowd, characters: &[CharacterBake]) -> Camera {
    let height = characters
        .iter()
        .map(|b| b.bounds.size().y)
        .fold(0.5f32, f32::max);
    if crowd.agents.len() <= 1 {
        return Camera::new(Vec3::new(0.0, height * 0.5, 0.0), 35.0, 12.0, height * 2.6);
    }
    let r = crowd.radius.max(height * 3.0);
    Camera::new(Vec3::new(0.0, height * 0.3, 0.0), 35.0, 14.0, r * 1.12)
}

/// A loaded scene: the renderer with its characters, the crowd and a camera.
pub struct World {
    pub spec: SceneSpec,
    pub bakes: Vec<CharacterBake>,
    pub crowd: Crowd,
    pub camera: Camera,
    pub renderer: SceneRenderer,
    instances: Vec<Instance>,
}

/// Models loaded and baked for a spec, checked, before any GPU work: bad input fails the same
/// way with or without a GPU.
pub struct Loaded {
    pub spec: SceneSpec,
    pub bakes: Vec<CharacterBake>,
}

impl Loaded {
    pub fn new(spec: SceneSpec) -> Result<Loaded> {
        let bakes = load_characters(&spec)?;
        check_clip(&spec, &bakes)?;
        Ok(Loaded { spec, bakes })
    }
}

impl World {
    pub fn new(
        gpu: &Gpu,
        loaded: Loaded,
        color_format: wgpu::TextureFormat,
        sample_count: u32,
    ) -> Result<World> {
        let Loaded { spec, bakes } = loaded;
        let mut renderer = SceneRenderer::new(gpu, color_format, sample_count);
        for b in &bakes {
            renderer.add_character(gpu, b)?;
        }
        let crowd = layout_crowd(&spec, &bakes, None);
        let camera = default_camera(&crowd, &bakes);
        Ok(World {
            spec,
            bakes,
            crowd,
            camera,
            renderer,
            instances: Vec::new(),
        })
    }

    /// Re-lays the crowd for a new count, clip or model choice without reloading anything:
    /// every character stays on the GPU.
    pub fn relayout(&mut self, only: Option<usize>, count: usize, clip: Option<String>) {
        self.spec.count = count;
        self.spec.clip = clip;
        self.crowd = layout_crowd(&self.spec, &self.bakes, only);
    }

    pub fn reset_camera(&mut self) {
        self.camera = default_camera(&self.crowd, &self.bakes);
    }

    /// Uploads everything for a frame at scene time `time` and returns what it will draw.
    pub fn prepare(&mut self, gpu: &Gpu, aspect: f32, time: f32) -> crate::render::FrameStats {
        self.crowd.instances_at(time, &mut self.instances);
        let view = crate::render::FrameView::from_camera(&self.camera, aspect, time);
        self.renderer.prepare(gpu, &view, &self.instances)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clip_is_chosen_by_name_model_by_model() {
        let spec = SceneSpec {
            count: 40,
            clip: Some("gallop".into()),
            ..Default::default()
        };
        let bakes = load_characters(&spec).unwrap();
        let crowd = layout_crowd(&spec, &bakes, None);
        let horse = bakes.iter().position(|b| b.name == "horse").unwrap();
        let gallop = bakes[horse]
            .animation
            .clips
            .iter()
            .position(|c| c.name == "gallop")
            .unwrap();
        for a in &crowd.agents {
            if a.model == horse {
                assert_eq!(a.clip, gallop);
            } else {
                // Walkers have no gallop: they keep a mix of their own clips.
                assert!(a.clip < bakes[a.model].animation.clips.len());
            }
        }
        let walker_clips: std::collections::HashSet<usize> = crowd
            .agents
            .iter()
            .filter(|a| a.model != horse)
            .map(|a| a.clip)
            .collect();
        assert!(
            walker_clips.len() > 1,
            "walkers must not all be forced onto one clip"
        );
    }
}
