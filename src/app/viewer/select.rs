//! Looking at one instance closely, as in an engine's editor: a click selects what is under
//! the cursor, F frames it and the camera follows it (until the user pans or flies away), B
//! bookmarks the camera and prints it as `--camera` (Shift+B goes back to it), "copy as
//! command" gives the `lodlab shot` line that renders the view, and the models opened at run
//! time are remembered between runs.

use super::Viewer;
use super::inspect::SelectionRequests;
use crate::app::cli::command_line::{ViewState, camera_value, shell_line, shot_command};
use crate::runtime::headless::ShotLod;
use glam::Vec2;

impl Viewer {
    /// What the panel's selection section asked for.
    pub(super) fn act_on_selection(&mut self, requests: &SelectionRequests) {
        if requests.frame {
            self.frame_selection();
        }
        if requests.deselect {
            self.selection.picked = None;
            self.selection.following = None;
        }
        if requests.bookmark || requests.back_to_bookmark {
            self.bookmark(requests.back_to_bookmark);
        }
        if requests.copy_command {
            self.copy_command();
        }
        if let Some(path) = &requests.open_recent {
            self.open_model(path);
        }
        if requests != &SelectionRequests::default() {
            self.panel.touch();
        }
    }

    /// A left click on the view: selects the instance under the cursor, or nothing.
    pub(super) fn pick_at_cursor(&mut self) {
        let Some((x, y)) = self.controls.cursor() else {
            return;
        };
        let [vx, vy, vw, vh] = self.view.map(|v| v as f64);
        let ndc = Vec2::new(
            ((x - vx) / vw.max(1.0) * 2.0 - 1.0) as f32,
            (1.0 - (y - vy) / vh.max(1.0) * 2.0) as f32,
        );
        let picked = self.world.pick(ndc, (vw / vh.max(1.0)) as f32);
        if picked != self.selection.picked {
            self.selection.following = None;
            self.selection.just_picked = picked.is_some();
        }
        self.selection.picked = picked;
        self.panel.touch();
    }

    /// F: the camera looks at the selection from where it fills about half the view's height,
    /// and follows it from now on.
    pub(super) fn frame_selection(&mut self) {
        let Some((centre, radius)) = self
            .selection
            .picked
            .and_then(|i| self.world.instance_sphere(i))
        else {
            self.notice = Some("nothing selected: click a character or a tree first".into());
            return;
        };
        let camera = &mut self.world.camera;
        camera.target = centre;
        camera.distance = (radius / (camera.fov_y * 0.25).tan()).max(0.5);
        self.selection.following = Some(centre);
    }

    /// Each frame: a followed selection keeps the camera's target on it; a target the user
    /// moved (panning, flying) ends the following.
    pub(super) fn follow_selection(&mut self) {
        self.world.highlight = self.selection.picked;
        let Some(last) = self.selection.following else {
            return;
        };
        if self.world.camera.target.distance(last) > 1e-4 {
            self.selection.following = None;
            return;
        }
        if let Some((centre, _)) = self
            .selection
            .picked
            .and_then(|i| self.world.instance_sphere(i))
        {
            self.world.camera.target = centre;
            self.selection.following = Some(centre);
        }
    }

    /// B: keeps the camera, and prints it as `--camera` for `shot`; Shift+B: goes back to it.
    pub(super) fn bookmark(&mut self, back: bool) {
        let camera = &mut self.world.camera;
        if back {
            match self.selection.bookmark {
                Some(b) => {
                    *camera = b;
                    self.selection.following = None;
                    self.notice = Some("back to the bookmarked camera".into());
                }
                None => self.notice = Some("no bookmark yet: B keeps the camera".into()),
            }
            return;
        }
        self.selection.bookmark = Some(*camera);
        let line = format!("--camera {}", camera_value(camera));
        eprintln!("lodlab: camera bookmarked: {line}");
        self.notice = Some(format!("bookmarked (Shift+B: back): {line}"));
    }

    /// "Copy as command": the `lodlab shot` line that renders this view, on the clipboard, on
    /// stderr and in the panel.
    pub(super) fn copy_command(&mut self) {
        let s = &self.settings;
        let spec = crate::runtime::spec::SceneSpec {
            count: s.count,
            clip: s.clip.clone(),
            cross_fade: s.cross_fade,
            impostors: self.world.spec.impostors.filter(|_| s.impostors),
            models: match s.model {
                Some(m) => {
                    let names = if self.world.spec.models.is_empty() {
                        self.world
                            .spec
                            .scene
                            .default_models()
                            .iter()
                            .map(|n| n.to_string())
                            .collect()
                    } else {
                        self.world.spec.models.clone()
                    };
                    names.get(m).cloned().into_iter().collect()
                }
                None => self.world.spec.models.clone(),
            },
            ..self.world.spec.clone()
        };
        let lod = ShotLod {
            method: s.method,
            compare: s.compare,
            policy: s.policy,
            debug: s.debug,
            normal_maps: s.normal_maps,
            foliage: s.foliage,
            ..Default::default()
        };
        let words = shot_command(&ViewState {
            spec: &spec,
            lod: &lod,
            camera: &self.world.camera,
            size: (self.view[2].max(1), self.view[3].max(1)),
            time: self.clock.time,
            samples: self.targets.sample_count,
            default_samples: self.win.gpu.default_samples(),
            // Shot's home camera is the view's where it draws the same scene.
            home: (spec == self.world.spec).then(|| self.world.home_camera()),
        });
        let line = shell_line(&words);
        eprintln!("lodlab: this view as a command: {line}");
        let copied = self
            .selection
            .clipboard
            .take()
            .or_else(super::clipboard::Clipboard::new)
            .and_then(|mut c| c.set_text(&line).then_some(c));
        self.notice = Some(if copied.is_some() {
            "copied to the clipboard (and printed on stderr)".into()
        } else {
            "no clipboard here: printed on stderr".into()
        });
        self.selection.clipboard = copied;
        self.selection.command = Some(line);
    }
}
