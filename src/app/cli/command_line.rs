//! The command line read backwards: what a view shows (scene, levels of detail, camera, size,
//! time) as the `lodlab shot` command that renders it. The viewer's "copy as command" gives
//! it, so that any screenshot can be made again headless. Only what differs from `shot`'s
//! defaults is written.

use super::{Cli, Command, ShotArgs};
use crate::import::validate::Limits;
use crate::runtime::headless::ShotLod;
use crate::runtime::spec::{BakeInputs, SceneSpec};
use crate::scene::{Camera, SceneKind};
use clap::{Parser, ValueEnum};

/// What a view shows, as `shot` takes it.
pub struct ViewState<'a> {
    pub spec: &'a SceneSpec,
    pub lod: &'a ShotLod,
    pub camera: &'a Camera,
    /// The 3D view's size in pixels.
    pub size: (u32, u32),
    /// Scene time, seconds.
    pub time: f32,
    /// Samples per pixel the view draws with.
    pub samples: u32,
    /// What `shot` would take without `--msaa` and `--camera` on this machine: the adapter's
    /// default samples, and the scene's home camera where the shot's scene is the view's.
    pub default_samples: u32,
    pub home: Option<Camera>,
}

/// Whether two cameras frame the same view (to the digits `--camera` is written with).
fn same_camera(a: &Camera, b: &Camera) -> bool {
    (a.yaw - b.yaw).abs() < 1e-5
        && (a.pitch - b.pitch).abs() < 1e-5
        && (a.distance - b.distance).abs() < 1e-5 * b.distance.max(1.0)
        && a.target.distance(b.target) < 1e-5 * b.distance.max(1.0)
        && a.fov_y == b.fov_y
}

/// `shot`'s arguments when none is given.
fn defaults() -> ShotArgs {
    match Cli::try_parse_from(["lodlab", "shot"]).map(|c| c.command) {
        Ok(Some(Command::Shot(a))) => a,
        _ => unreachable!("`lodlab shot` parses"),
    }
}

/// A choice's name on the command line.
fn name<T: ValueEnum>(v: &T) -> String {
    v.to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

/// `lodlab shot …` for `view`, as words (the first is `lodlab`).
pub fn shot_command(view: &ViewState) -> Vec<String> {
    let d = defaults();
    let (spec, lod) = (view.spec, view.lod);
    let mut w: Vec<String> = vec!["lodlab".into(), "shot".into()];
    let mut push = |flag: &str, value: Option<String>| {
        w.push(format!("--{flag}"));
        w.extend(value);
    };
    if spec.scene != SceneKind::Mixed {
        push("scene", Some(name(&spec.scene)));
    }
    for m in &spec.models {
        push("model", Some(m.clone()));
    }
    if spec.count != spec.scene.default_count() {
        push("count", Some(spec.count.to_string()));
    }
    if spec.trees != d.scene.trees {
        push("trees", Some(spec.trees.to_string()));
    }
    if let Some(clip) = &spec.clip {
        push("clip", Some(clip.clone()));
    }
    if spec.seed != d.scene.seed {
        push("seed", Some(spec.seed.to_string()));
    }
    if spec.cross_fade != d.scene.cross_fade {
        push("cross-fade", Some(spec.cross_fade.to_string()));
    }
    if spec.impostors != d.scene.impostors.0 {
        push(
            "impostors",
            Some(spec.impostors.map_or("off".into(), |o| o.to_string())),
        );
    }
    if let Some(cache) = &spec.cache_dir {
        push("cache", Some(cache.display().to_string()));
    }
    input_words(&spec.inputs, &mut push);
    match lod.compare {
        Some(right) => push(
            "compare",
            Some(format!("{},{}", name(&lod.method), name(&right))),
        ),
        // `none` is shot's own method.
        None if lod.method != crate::scene::LodMethod::None => {
            push("method", Some(name(&lod.method)))
        }
        None => {}
    }
    let (p, dp) = (&lod.policy, d.lod.policy.policy());
    if p.transition != dp.transition {
        push("transition", Some(name(&p.transition)));
    }
    if p.drive != dp.drive {
        push("drive", Some(name(&p.drive)));
    }
    if p.duration != dp.duration {
        push("duration", Some(p.duration.to_string()));
    }
    if p.zone_width != dp.zone_width {
        push("zone-width", Some(p.zone_width.to_string()));
    }
    if p.tolerance_px != dp.tolerance_px {
        push("tolerance", Some(p.tolerance_px.to_string()));
    }
    if p.hysteresis != dp.hysteresis {
        push("hysteresis", Some(p.hysteresis.to_string()));
    }
    if let Some(level) = p.force_level {
        push("force-level", Some(level.to_string()));
    }
    if lod.debug != d.lod.debug_view {
        push("debug-view", Some(name(&lod.debug)));
    }
    if !lod.normal_maps {
        push("no-normal-maps", None);
    }
    foliage_words(lod, &d, &mut push);
    if view.size != d.size {
        push("size", Some(format!("{}x{}", view.size.0, view.size.1)));
    }
    if view.time != d.time {
        push("time", Some(view.time.to_string()));
    }
    if view.samples != view.default_samples {
        push("msaa", Some(view.samples.to_string()));
    }
    if !view
        .home
        .is_some_and(|home| same_camera(view.camera, &home))
    {
        push("camera", Some(camera_value(view.camera)));
    }
    w
}

/// The global options that made `inputs`: extra clips, level budgets, import limits.
fn input_words(inputs: &BakeInputs, push: &mut impl FnMut(&str, Option<String>)) {
    for file in &inputs.import.extra_clips {
        push("clips", Some(file.display().to_string()));
    }
    if let Some(budgets) = &inputs.level_budgets {
        let list: Vec<String> = budgets.iter().map(u32::to_string).collect();
        push("levels", Some(format!("triangles:{}", list.join(","))));
    }
    let (limits, plain) = (&inputs.import.limits, Limits::default());
    for (limit, _) in Limits::NAMES {
        if let Some(v) = limits
            .value(limit)
            .filter(|v| Some(v) != plain.value(limit).as_ref())
        {
            push("limit", Some(format!("{limit}={v}")));
        }
    }
    if limits.outside_files {
        push("allow-outside-files", None);
    }
}

/// A camera as `--camera` takes it: `YAW,PITCH,DIST,X,Y,Z` (degrees, metres).
pub fn camera_value(c: &Camera) -> String {
    format!(
        "{},{},{},{},{},{}",
        c.yaw.to_degrees(),
        c.pitch.to_degrees(),
        c.distance,
        c.target.x,
        c.target.y,
        c.target.z
    )
}

/// The foliage options of `lod` that differ from `shot`'s defaults `d`.
fn foliage_words(lod: &ShotLod, d: &ShotArgs, push: &mut impl FnMut(&str, Option<String>)) {
    let (f, df) = (&lod.foliage, d.lod.foliage.view());
    if f.policy != df.policy {
        push("foliage", Some(name(&f.policy)));
    }
    let (c, dc) = (&f.chain, &df.chain);
    if c.first_epsilon != dc.first_epsilon {
        push("first-epsilon", Some(c.first_epsilon.to_string()));
    }
    if c.epsilon_growth != dc.epsilon_growth {
        push("epsilon-growth", Some(c.epsilon_growth.to_string()));
    }
    if c.description != dc.description {
        push("description", Some(name(&c.description)));
    }
    if c.bins != dc.bins {
        push("bins", Some(c.bins.to_string()));
    }
    if !c.shared_bone {
        push("plain-sca", None);
    }
    if c.order != dc.order {
        push("foliage-order", Some(name(&c.order)));
    }
    if f.wind != df.wind {
        push("wind", Some(f.wind.to_string()));
    }
    if f.outlines {
        push("outlines", None);
    }
    if f.tint {
        push("foliage-tint", None);
    }
    if let Some(atlas) = f.atlas_lighting {
        push(
            "billboard-lighting",
            Some(if atlas { "atlas" } else { "flat" }.into()),
        );
    }
    if f.prepass {
        push("foliage-prepass", None);
    }
    if f.patches {
        push("forest-patches", None);
    }
}

/// Words as one line a POSIX shell reads back as they are (quoted where they need it).
pub fn shell_line(words: &[String]) -> String {
    words
        .iter()
        .map(|w| {
            let plain = !w.is_empty()
                && w.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_.,/:+=@%".contains(c));
            if plain {
                w.clone()
            } else {
                format!("'{}'", w.replace('\'', r"'\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::foliage::billboard::chain::levels::FoliageOrder;
    use crate::render::DebugView;
    use crate::scene::{Drive, LodMethod, Transition};

    /// A view far from every default reads back, through the command line, as itself.
    #[test]
    fn a_view_round_trips_through_the_command_line() {
        let spec = SceneSpec {
            scene: SceneKind::Crowd,
            models: vec!["walker".into(), "/tmp/my model.glb".into()],
            count: 37,
            trees: 12,
            clip: Some("walk".into()),
            seed: 9,
            cross_fade: 0.75,
            cache_dir: Some("/tmp/cache dir".into()),
            impostors: None,
            inputs: BakeInputs {
                import: crate::import::ImportOptions {
                    limits: {
                        let mut l = Limits::default();
                        l.set("triangles=5000").unwrap();
                        l.outside_files = true;
                        l
                    },
                    extra_clips: vec!["mocap-walk".into(), "/tmp/my clips.glb".into()],
                },
                level_budgets: Some(vec![900, 300]),
            },
        };
        let mut lod = ShotLod {
            method: LodMethod::AS_IS,
            compare: Some(LodMethod::None),
            debug: DebugView::LodTint,
            normal_maps: false,
            ..Default::default()
        };
        lod.policy.transition = Transition::Alpha;
        lod.policy.drive = Drive::Zone;
        lod.policy.duration = 0.3;
        lod.policy.zone_width = 0.4;
        lod.policy.tolerance_px = 2.5;
        lod.policy.hysteresis = 0.35;
        lod.policy.force_level = Some(3);
        lod.foliage.chain.order = FoliageOrder::ALL
            .into_iter()
            .find(|&o| o != lod.foliage.chain.order)
            .unwrap();
        lod.foliage.chain.first_epsilon = 0.01;
        lod.foliage.chain.bins = 6;
        lod.foliage.chain.shared_bone = false;
        lod.foliage.wind = 1.7;
        lod.foliage.outlines = true;
        lod.foliage.atlas_lighting = Some(false);
        lod.foliage.patches = true;
        let camera = Camera::new(glam::Vec3::new(1.5, 0.25, -7.0), 33.5, 12.25, 41.0);
        let words = shot_command(&ViewState {
            spec: &spec,
            lod: &lod,
            camera: &camera,
            size: (1010, 720),
            time: 4.25,
            samples: 1,
            default_samples: 4,
            home: None,
        });
        let line = shell_line(&words);
        assert!(line.contains("'/tmp/my model.glb'"), "{line}");
        let cli = Cli::try_parse_from(&words).unwrap();
        let inputs = cli.bake_inputs();
        let Some(Command::Shot(a)) = cli.command else {
            panic!("not a shot: {line}");
        };
        assert_eq!(a.scene.spec(&inputs), spec, "{line}");
        let back = a.lod.shot_lod(LodMethod::None);
        assert_eq!(back, lod, "{line}");
        assert_eq!((a.size, a.time, a.msaa), ((1010, 720), 4.25, Some(1)));
        let c = a.camera.unwrap();
        assert!((c.yaw - camera.yaw).abs() < 1e-5 && (c.pitch - camera.pitch).abs() < 1e-5);
        assert!(c.target.distance(camera.target) < 1e-5 && (c.distance - 41.0).abs() < 1e-5);
        // The defaults are left out.
        let plain = shot_command(&ViewState {
            spec: &defaults().scene.spec(&Default::default()),
            lod: &ShotLod::default(),
            camera: &camera,
            size: (1280, 720),
            time: 1.0,
            samples: 4,
            default_samples: 4,
            home: Some(camera),
        });
        assert_eq!(plain, ["lodlab", "shot"], "{plain:?}");
        // Moved off the home camera, or drawn with other samples than the machine's
        // default, the view says so.
        let moved = Camera {
            yaw: camera.yaw + 0.1,
            ..camera
        };
        let other = shot_command(&ViewState {
            spec: &defaults().scene.spec(&Default::default()),
            lod: &ShotLod::default(),
            camera: &moved,
            size: (1280, 720),
            time: 1.0,
            samples: 1,
            default_samples: 4,
            home: Some(camera),
        });
        assert_eq!(other[2..5], ["--msaa", "1", "--camera"], "{other:?}");
    }
}
