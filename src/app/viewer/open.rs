//! Opening another model at run time: dropped on the window, or picked by "Open…" in the
//! panel through the desktop's file dialog.

use super::Viewer;
use crate::runtime::spec::{Loaded, SceneSpec};
use crate::runtime::world::World;

impl Viewer {
    /// "Open…" in the browser: the page has its built-in scenes only.
    #[cfg(target_arch = "wasm32")]
    pub(super) fn pick_and_open(&mut self) {
        self.panel.touch();
        self.notice =
            Some("the web viewer shows its built-in scenes: open other models in lodlab".into());
    }

    /// "Open…": the desktop's file dialog, then [`Self::open_model`] on the file picked.
    #[cfg(not(target_arch = "wasm32"))]
    pub(super) fn pick_and_open(&mut self) {
        // The platform's file dialog (the XDG desktop portal, over the session's D-Bus);
        // none where there is no session bus to ask, and then the panel says so at once
        // instead of reading as a cancel.
        let bus = std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some_and(|a| !a.is_empty());
        let picked = if bus {
            rfd::FileDialog::new()
                .add_filter("glTF", &["glb", "gltf"])
                .pick_file()
        } else {
            None
        };
        match picked {
            Some(path) => self.open_model(&path),
            None => {
                self.panel.touch();
                self.notice = Some(if bus {
                    "no file picked (or no file dialog on this desktop): drop a .glb or .gltf on the window".into()
                } else {
                    "no file dialog here (no desktop session bus): drop a .glb or .gltf on the window".into()
                })
            }
        }
    }

    /// Opens the model at `path` (dropped on the window, or picked by "Open…") in place of the
    /// scene's models (its trees too, as `--model` does): the same scene, settings and camera, its levels baked in the
    /// background as at start-up. A file that does not load leaves everything as it was and
    /// says why in the panel.
    pub(super) fn open_model(&mut self, path: &std::path::Path) {
        let spec = SceneSpec {
            models: vec![path.to_string_lossy().into_owned()],
            ..self.world.spec.clone()
        };
        let cache = self.world.cache();
        let opened = Loaded::new(spec).and_then(|loaded| {
            World::new(
                &self.win.gpu,
                loaded.with_cache(cache),
                self.win.format(),
                self.targets.sample_count,
            )
        });
        match opened {
            Ok(mut world) => {
                world.camera = self.world.camera;
                world.renderer.debug = self.world.renderer.debug;
                world.renderer.normal_maps = self.world.renderer.normal_maps;
                world.renderer.shadows = self.world.renderer.shadows;
                self.model_names = world.bakes.iter().map(|b| b.name.clone()).collect();
                self.clip_names = world.bakes.iter().map(|b| b.clip_names()).collect();
                self.world = world;
                self.baking.bake = None;
                self.baking.bake_error = None;
                self.settings.model = None;
                self.settings.clip = None;
                self.settings.count = self.world.spec.count;
                self.world.lod.method = self.settings.method;
                self.world.lod.compare = self.settings.compare;
                self.world.lod.policy = self.settings.policy;
                self.world.apply_foliage(&self.settings.foliage);
                self.world.reset_camera();
                self.panel.touch();
                self.notice = Some(format!("opened {}", path.display()));
                self.selection.picked = None;
                self.selection.opened(path);
                eprintln!("lodlab: opened {}", path.display());
            }
            Err(e) => {
                let line = format!("{e:#}");
                eprintln!("lodlab: {line}");
                self.panel.touch();
                self.notice = Some(line);
            }
        }
    }
}
