//! When the viewer's panel runs again. Laying the panel out, tessellating it and uploading its
//! meshes cost a software adapter more than some whole scenes do, so a panel nobody touches is
//! drawn again from its last meshes, and its figures (frame times, triangles, GPU passes) are
//! brought up to date a few times a second, as an engine's statistics overlay is.

use std::time::Duration;
use web_time::Instant;

/// How often the panel's figures are brought up to date when nothing else asks for it: every
/// quarter of a second, but no more often than every [`REFRESH_FRAMES`] frames, so that at a
/// few frames a second, drawing the panel (about 10 ms on lavapipe) stays a small share of
/// the frames.
pub const PANEL_REFRESH: Duration = Duration::from_millis(250);
pub const REFRESH_FRAMES: u64 = 10;

/// When the panel last ran, and what since then asks for it to run again.
pub struct PanelSchedule {
    /// When it last ran; `None` before the first frame.
    ran_at: Option<Instant>,
    /// The time egui asked to run again by (an animation, a tooltip's delay).
    repaint_by: Option<Instant>,
    /// An event since the last run that the panel must see or show: input egui wants, a key
    /// that changed a setting, a new size.
    touched: bool,
    /// Whether the pointer was over the panel at the last event egui saw.
    pointer_on_panel: bool,
    /// The rectangle the panel left to the 3D view, in points, when it last ran.
    pub central: egui::Rect,
    /// The CPU time the panel took (running, tessellating, uploading), in ms a frame, over
    /// every frame: those where it ran and those where it was drawn as it was.
    cpu_ms_sum: f64,
    frames: u64,
    /// [`Self::frames`] when it last ran.
    ran_frame: u64,
}

impl Default for PanelSchedule {
    fn default() -> Self {
        PanelSchedule {
            ran_at: None,
            repaint_by: None,
            touched: false,
            pointer_on_panel: false,
            central: egui::Rect::NOTHING,
            cpu_ms_sum: 0.0,
            frames: 0,
            ran_frame: 0,
        }
    }
}

/// What the panel attends to at an event: which points it covers, and whether it wants the
/// keyboard (a text field has focus).
pub struct Attention<'a> {
    pub covers: &'a dyn Fn(egui::Pos2) -> bool,
    pub keyboard: bool,
}

impl PanelSchedule {
    /// Whether the panel runs this frame (at `now`), given egui's input `raw` gathered
    /// since the last frame. The pointer moving or the wheel turning over the 3D view, and
    /// keys while no text field has focus (flying the camera), are the view's, not the
    /// panel's; the pointer leaving the panel is the panel's (its hover ends).
    pub fn due(&mut self, now: Instant, raw: &egui::RawInput, attention: Attention) -> bool {
        let mut for_panel = false;
        for event in &raw.events {
            for_panel |= match event {
                egui::Event::PointerMoved(p) => {
                    let over = (attention.covers)(*p);
                    let left = self.pointer_on_panel && !over;
                    self.pointer_on_panel = over;
                    over || left
                }
                egui::Event::MouseMoved(_) => false,
                egui::Event::MouseWheel { .. } => self.pointer_on_panel,
                egui::Event::Key { .. } | egui::Event::Text(_) => attention.keyboard,
                _ => true,
            };
        }
        let Some(ran_at) = self.ran_at else {
            return true;
        };
        self.touched
            || for_panel
            || !raw.dropped_files.is_empty()
            || !raw.hovered_files.is_empty()
            || self.repaint_by.is_some_and(|t| now >= t)
            || (now.duration_since(ran_at) >= PANEL_REFRESH
                && self.frames >= self.ran_frame + REFRESH_FRAMES)
    }

    /// Something the panel shows or reacts to changed: run it on the next frame.
    pub fn touch(&mut self) {
        self.touched = true;
    }

    /// The panel ran at `now`, leaving `central` to the view; egui asked to run again after
    /// `repaint_delay` (`Duration::MAX`: not of itself).
    pub fn ran(&mut self, now: Instant, central: egui::Rect, repaint_delay: Duration) {
        self.ran_at = Some(now);
        self.ran_frame = self.frames;
        self.central = central;
        self.touched = false;
        self.repaint_by = (repaint_delay < PANEL_REFRESH).then(|| now + repaint_delay);
    }

    /// Counts a frame in which the panel took `cpu` (zero where it was drawn as it was).
    pub fn count(&mut self, cpu: Duration) {
        self.cpu_ms_sum += cpu.as_secs_f64() * 1000.0;
        self.frames += 1;
    }

    /// The panel's mean CPU time a frame so far, in ms.
    pub fn cpu_ms(&self) -> f64 {
        self.cpu_ms_sum / self.frames.max(1) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(events: Vec<egui::Event>) -> egui::RawInput {
        egui::RawInput {
            events,
            ..Default::default()
        }
    }

    fn key() -> egui::Event {
        egui::Event::Key {
            key: egui::Key::A,
            physical_key: None,
            pressed: true,
            repeat: false,
            modifiers: Default::default(),
        }
    }

    fn click(x: f32) -> egui::Event {
        egui::Event::PointerButton {
            pos: egui::pos2(x, 10.0),
            button: egui::PointerButton::Primary,
            pressed: true,
            modifiers: Default::default(),
        }
    }

    /// The panel covers x < 270.
    fn panel_left(p: egui::Pos2) -> bool {
        p.x < 270.0
    }

    const TYPING: Attention = Attention {
        covers: &panel_left,
        keyboard: true,
    };
    const FLYING: Attention = Attention {
        covers: &panel_left,
        keyboard: false,
    };

    #[test]
    fn a_still_panel_runs_only_to_refresh_its_figures() {
        let t0 = Instant::now();
        let quiet = egui::RawInput::default();
        let mut s = PanelSchedule::default();
        assert!(s.due(t0, &quiet, FLYING), "the first frame runs it");
        s.ran(t0, egui::Rect::EVERYTHING, Duration::MAX);
        let soon = t0 + Duration::from_millis(16);
        assert!(!s.due(soon, &quiet, FLYING));
        for _ in 0..REFRESH_FRAMES - 1 {
            s.count(Duration::ZERO);
        }
        let later = t0 + PANEL_REFRESH;
        assert!(
            !s.due(later, &quiet, FLYING),
            "not before the frames are in"
        );
        s.count(Duration::ZERO);
        assert!(s.due(later, &quiet, FLYING), "the figures are refreshed");
        s.touch();
        assert!(s.due(soon, &quiet, FLYING), "a touch runs it");
        s.ran(soon, egui::Rect::EVERYTHING, Duration::from_millis(50));
        assert!(!s.due(soon + Duration::from_millis(49), &quiet, FLYING));
        assert!(
            s.due(soon + Duration::from_millis(50), &quiet, FLYING),
            "egui's own repaint request is kept"
        );
    }

    #[test]
    fn input_for_the_view_leaves_the_panel_alone() {
        let t0 = Instant::now();
        let soon = t0 + Duration::from_millis(16);
        let mut s = PanelSchedule::default();
        s.ran(t0, egui::Rect::EVERYTHING, Duration::MAX);
        let moved = |x| input(vec![egui::Event::PointerMoved(egui::pos2(x, 10.0))]);
        assert!(!s.due(soon, &moved(500.0), FLYING), "orbiting the view");
        assert!(s.due(soon, &moved(100.0), FLYING), "over the panel");
        assert!(
            s.due(soon, &moved(500.0), FLYING),
            "leaving it ends its hover"
        );
        assert!(!s.due(soon, &moved(600.0), FLYING));
        assert!(
            s.due(soon, &input(vec![click(500.0)]), FLYING),
            "a click anywhere (it closes a pop-up)"
        );
        assert!(
            !s.due(soon, &input(vec![key()]), FLYING),
            "flying the camera"
        );
        assert!(
            s.due(soon, &input(vec![key()]), TYPING),
            "typing into the panel"
        );
    }

    #[test]
    fn the_cost_is_spread_over_every_frame() {
        let mut s = PanelSchedule::default();
        s.count(Duration::from_millis(9));
        s.count(Duration::ZERO);
        s.count(Duration::ZERO);
        assert!((s.cpu_ms() - 3.0).abs() < 1e-9);
    }
}
