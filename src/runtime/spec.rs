//! What a world shows, before any GPU work: the scene spec, its models loaded, baked and
//! checked, the crowd laid out and the camera that frames it. Shared by the viewer, `shot` and
//! the tests, so they all show the same thing.

use super::levels::LevelSource;
use crate::bake::gpu_data::drawable::Drawable;
use crate::bake::impostor::animated::ImpostorOptions;
use crate::import::{Imported, import};
use crate::model::Model;
use crate::scene::kind::DEFAULT_MIXED_TREES;
use crate::scene::{Camera, Crowd, CrowdConfig, CrowdModel, SceneKind};
use anyhow::{Result, bail};
use glam::Vec3;
use std::path::PathBuf;

/// What to show.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneSpec {
    pub scene: SceneKind,
    /// Built-in asset names or glTF paths; empty means the scene's default.
    pub models: Vec<String>,
    pub count: usize,
    /// Trees round the clearing of the mixed scene (`count` is its characters).
    pub trees: usize,
    /// Play this clip (by name) on every model that has it.
    pub clip: Option<String>,
    pub seed: u64,
    /// Seconds a walker's clip cross-fades into a clip on the spot and back when it stops;
    /// 0: walkers never stop (see [`CrowdConfig::cross_fade`]).
    pub cross_fade: f32,
    /// Where baked levels of detail are cached (default: the platform cache folder).
    pub cache_dir: Option<PathBuf>,
    /// How characters' animated impostors are baked (`None`, the default here: characters
    /// get none; the front ends bake them unless told `--impostors off`).
    pub impostors: Option<ImpostorOptions>,
    /// How its models are read and their levels cut (the command line's global options).
    pub inputs: BakeInputs,
}

/// What the command line says, for every command, about reading models and cutting their
/// levels: the import's limits and extra clips, and the triangle budgets of characters'
/// levels. Plain values handed down from the command line: two scenes or bakes in one process
/// may ask for different ones.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BakeInputs {
    pub import: crate::import::ImportOptions,
    /// Triangle budgets characters' levels are cut by (`--levels triangles:N,N,…`, the levels
    /// `lodlab bake MODEL --triangles N,N,…` made); `None`: by error, the default.
    pub level_budgets: Option<Vec<u32>>,
}

impl Default for SceneSpec {
    fn default() -> Self {
        SceneSpec {
            scene: SceneKind::Crowd,
            models: Vec::new(),
            count: SceneKind::Crowd.default_count(),
            trees: DEFAULT_MIXED_TREES,
            clip: None,
            seed: 1,
            cross_fade: 0.0,
            cache_dir: None,
            impostors: None,
            inputs: BakeInputs::default(),
        }
    }
}

/// Loads and bakes the models a spec names, in order.
pub fn load_characters(spec: &SceneSpec) -> Result<Vec<Drawable>> {
    Ok(load_sources(spec)?.into_iter().map(|(b, _)| b).collect())
}

/// Loads the models a spec names, in order: their full-detail bakes, and what baking their
/// levels of detail later needs.
fn load_sources(spec: &SceneSpec) -> Result<Vec<(Drawable, LevelSource)>> {
    if spec.scene == SceneKind::Study && spec.models.len() > 1 {
        bail!(
            "the study scene shows copies of one model, not {} (--model once)",
            spec.models.len()
        );
    }
    let names: Vec<String> = if spec.models.is_empty() {
        let defaults = spec.scene.default_models();
        defaults.iter().map(|s| s.to_string()).collect()
    } else {
        spec.models.clone()
    };
    names
        .iter()
        .map(|name| {
            let Imported { model, source_hash } = import(name, &spec.inputs.import)?;
            let bake = Drawable::new(&model).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
            Ok((
                bake,
                LevelSource {
                    model,
                    hash: source_hash,
                    impostor: spec.impostors,
                    budgets: spec.inputs.level_budgets.clone(),
                },
            ))
        })
        .collect()
}

/// The crowd for a spec over already-loaded characters: all of them, or only character
/// `only`. Agents refer to characters by their index in `bakes`.
pub fn layout_crowd(spec: &SceneSpec, bakes: &[Drawable], only: Option<usize>) -> Crowd {
    let chosen: Vec<usize> = match only {
        Some(m) if m < bakes.len() => vec![m],
        _ => (0..bakes.len()).collect(),
    };
    if spec.scene == SceneKind::Mixed && only.is_none() {
        return mixed_crowd(spec, bakes);
    }
    let crowd_models: Vec<CrowdModel> = chosen
        .iter()
        .map(|&m| {
            let b = &bakes[m];
            CrowdModel {
                clip_speeds: b.animation.clips.iter().map(|c| c.ground_speed).collect(),
                clip_durations: b.animation.clips.iter().map(|c| c.duration).collect(),
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
    let mut crowd = if spec.scene == SceneKind::Forest {
        crate::scene::forest::layout(&crowd_models, spec.count, spec.seed)
    } else {
        Crowd::layout(
            &crowd_models,
            &CrowdConfig {
                count: spec.count,
                seed: spec.seed,
                clips,
                cross_fade: spec.cross_fade,
            },
        )
    };
    for a in &mut crowd.agents {
        a.model = chosen[a.model];
    }
    crowd
}

/// The mixed scene: the crowd of the characters among `bakes` walking in a clearing, and
/// `spec.trees` trees of the rest round it, their trunks clear of the outermost lane and their
/// crowns over it.
fn mixed_crowd(spec: &SceneSpec, bakes: &[Drawable]) -> Crowd {
    let (trees, characters): (Vec<usize>, Vec<usize>) =
        (0..bakes.len()).partition(|&m| bakes[m].kind.is_tree());
    let part = |scene: SceneKind, models: &[usize], count: usize| {
        let mut sub = layout_crowd(
            &SceneSpec {
                scene,
                count,
                ..spec.clone()
            },
            &models.iter().map(|&m| bakes[m].clone()).collect::<Vec<_>>(),
            None,
        );
        for a in &mut sub.agents {
            a.model = models[a.model];
        }
        sub
    };
    let mut crowd = part(SceneKind::Crowd, &characters, spec.count);
    if !trees.is_empty() && spec.trees > 0 {
        let models: Vec<CrowdModel> = trees
            .iter()
            .map(|&m| CrowdModel {
                clip_speeds: vec![0.0],
                clip_durations: vec![0.0],
                bounds: bakes[m].bounds,
            })
            .collect();
        let mut forest = crate::scene::forest::around(
            &models,
            spec.trees,
            spec.seed,
            crowd
                .radius
                .max(if crowd.agents.is_empty() { 0.0 } else { 4.0 })
                + 1.0,
        );
        for a in &mut forest.agents {
            a.model = trees[a.model];
        }
        // The camera frames the crowd, with the forest round and behind it.
        if crowd.agents.is_empty() {
            crowd.radius = forest.radius;
        }
        crowd.agents.extend(forest.agents);
    }
    crowd
}

/// Checks that a requested clip exists on at least one model.
pub fn check_clip(spec: &SceneSpec, bakes: &[Drawable]) -> Result<()> {
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
pub fn default_camera(crowd: &Crowd, characters: &[Drawable]) -> Camera {
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

/// Models loaded and baked for a spec, checked, before any GPU work: bad input fails the same
/// way with or without a GPU.
#[derive(Clone)]
pub struct Loaded {
    pub spec: SceneSpec,
    pub bakes: Vec<Drawable>,
    pub sources: Vec<LevelSource>,
    /// Where its levels are cached: the spec's folder, with files held in memory where a
    /// front end put them there ([`Loaded::with_cache`]).
    pub cache: crate::bake::cache::LodCache,
}

impl Loaded {
    /// A forest of `count` copies of a model built in memory (a tree's level, say, with its
    /// spectral motion if it has one), not read from a file: it has no source to cache levels
    /// under.
    pub fn forest_of(
        model: &Model,
        motion: Option<&crate::bake::gpu_data::spectra::SpectralMotion>,
        count: usize,
    ) -> Result<Loaded> {
        let bake = Drawable::with_motion(model, motion)
            .map_err(|e| anyhow::anyhow!("{}: {e}", model.name))?;
        Ok(Self::forest_of_bake(model, bake, count))
    }

    /// [`Self::forest_of`] with the model already baked.
    pub fn forest_of_bake(model: &Model, bake: Drawable, count: usize) -> Loaded {
        Loaded {
            cache: crate::bake::cache::LodCache::new(None),
            spec: SceneSpec {
                scene: SceneKind::Forest,
                count,
                ..Default::default()
            },
            bakes: vec![bake],
            sources: vec![LevelSource {
                model: model.clone(),
                hash: [0; 32],
                impostor: None,
                budgets: None,
            }],
        }
    }

    /// The same scene over `cache` (a cache with files preloaded, or recording its reads).
    pub fn with_cache(self, cache: crate::bake::cache::LodCache) -> Loaded {
        Loaded { cache, ..self }
    }

    pub fn new(spec: SceneSpec) -> Result<Loaded> {
        let (bakes, sources): (Vec<_>, Vec<_>) = load_sources(&spec)?.into_iter().unzip();
        check_clip(&spec, &bakes)?;
        Ok(Loaded {
            cache: crate::bake::cache::LodCache::new(spec.cache_dir.clone()),
            spec,
            bakes,
            sources,
        })
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
