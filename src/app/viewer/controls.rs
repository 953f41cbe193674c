//! Camera controls: orbit with the left mouse button, pan with the right (or middle), zoom with
//! the wheel over the 3D view, fly with WASD (Q/E down/up, Shift faster); on a touch screen
//! orbit with one finger, pinch to zoom and pan with two; and the keys that act once (see
//! [`KeyAction`]), F1, F11, F12, Esc and Ctrl+Q among them.

use crate::scene::Camera;
use std::collections::{BTreeMap, HashSet};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, Touch, TouchPhase, WindowEvent};
use winit::keyboard::{KeyCode, PhysicalKey};

/// Radians of orbit per pixel dragged.
const ORBIT_PER_PIXEL: f32 = 0.005;

#[derive(Default)]
pub struct Controls {
    held: HashSet<KeyCode>,
    drag: Option<MouseButton>,
    cursor: Option<(f64, f64)>,
    ctrl: bool,
    shift: bool,
    /// Where the left button went down over the view: a release near it is a click.
    pressed_at: Option<(f64, f64)>,
    /// Fingers on the screen, by id, where each is.
    touches: BTreeMap<u64, (f64, f64)>,
}

/// Pixels the cursor may move between press and release for a click (more is a drag).
const CLICK_SLOP: f64 = 4.0;

/// Keys that do something once, rather than while held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyAction {
    TogglePlay,
    ResetCamera,
    /// M: the next level-of-detail method.
    NextMethod,
    /// T: the next transition.
    NextTransition,
    /// V: the next debug view.
    NextDebugView,
    /// C: split screen on or off.
    ToggleCompare,
    /// Esc (where no text field has the keyboard) or Ctrl+Q: quit.
    Quit,
    /// F11: fullscreen on or off.
    ToggleFullscreen,
    /// F12: save a screenshot.
    Screenshot,
    /// F1: hide the panel, or show it again.
    TogglePanel,
    /// A left click on the 3D view (pressed and released without dragging): select what is
    /// under the cursor.
    Pick,
    /// F: frame the selection and follow it.
    Frame,
    /// B: bookmark the camera (and print it as `--camera`).
    Bookmark,
    /// Shift+B: back to the bookmark.
    BackToBookmark,
    /// Ctrl+C: the view as a `lodlab shot` command, on the clipboard.
    CopyCommand,
}

/// What a key pressed does wherever the keyboard is (a text field of the panel included).
pub fn window_key(code: KeyCode, ctrl: bool) -> Option<KeyAction> {
    match code {
        KeyCode::F11 => Some(KeyAction::ToggleFullscreen),
        KeyCode::F12 => Some(KeyAction::Screenshot),
        KeyCode::F1 => Some(KeyAction::TogglePanel),
        KeyCode::KeyQ if ctrl => Some(KeyAction::Quit),
        _ => None,
    }
}

/// What a key pressed does when the panel does not have the keyboard.
pub fn view_key(code: KeyCode) -> Option<KeyAction> {
    match code {
        KeyCode::Space => Some(KeyAction::TogglePlay),
        KeyCode::KeyR => Some(KeyAction::ResetCamera),
        KeyCode::KeyM => Some(KeyAction::NextMethod),
        KeyCode::KeyT => Some(KeyAction::NextTransition),
        KeyCode::KeyV => Some(KeyAction::NextDebugView),
        KeyCode::KeyC => Some(KeyAction::ToggleCompare),
        KeyCode::KeyF => Some(KeyAction::Frame),
        KeyCode::KeyB => Some(KeyAction::Bookmark),
        KeyCode::Escape => Some(KeyAction::Quit),
        _ => None,
    }
}

/// Whether the cursor at `cursor` (physical pixels) is over the 3D view `view` (x, y,
/// width, height): the camera takes the wheel and drags there only.
pub fn over_view(cursor: Option<(f64, f64)>, view: [u32; 4]) -> bool {
    let [x, y, w, h] = view.map(f64::from);
    cursor.is_some_and(|(cx, cy)| cx >= x && cy >= y && cx < x + w && cy < y + h)
}

impl Controls {
    /// Feeds a window event that egui did not take. `view_height` is the 3D view's height in
    /// pixels (pans move by what the screen shows).
    pub fn on_event(
        &mut self,
        event: &WindowEvent,
        camera: &mut Camera,
        view_height: f32,
        pointer_free: bool,
        keyboard_free: bool,
    ) -> Option<KeyAction> {
        match event {
            WindowEvent::ModifiersChanged(m) => {
                self.ctrl = m.state().control_key();
                self.shift = m.state().shift_key();
            }
            // The window's own keys (F1, F11, F12, Ctrl+Q) work whoever has the keyboard.
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed
                    && !event.repeat
                    && matches!(event.physical_key, PhysicalKey::Code(code)
                        if window_key(code, self.ctrl).is_some()) =>
            {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return None;
                };
                return window_key(code, self.ctrl);
            }
            WindowEvent::KeyboardInput { event, .. } if keyboard_free => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return None;
                };
                match event.state {
                    ElementState::Pressed => {
                        let first = self.held.insert(code);
                        if first {
                            return match view_key(code) {
                                Some(KeyAction::Bookmark) if self.shift => {
                                    Some(KeyAction::BackToBookmark)
                                }
                                Some(KeyAction::ToggleCompare) if self.ctrl => {
                                    Some(KeyAction::CopyCommand)
                                }
                                action => action,
                            };
                        }
                    }
                    ElementState::Released => {
                        self.held.remove(&code);
                    }
                }
            }
            WindowEvent::KeyboardInput { event, .. } => {
                // egui has the keyboard: still notice releases so no key sticks.
                if let PhysicalKey::Code(code) = event.physical_key
                    && event.state == ElementState::Released
                {
                    self.held.remove(&code);
                }
            }
            WindowEvent::Focused(false) => self.held.clear(),
            WindowEvent::MouseInput { state, button, .. } => match state {
                ElementState::Pressed if pointer_free => {
                    self.drag = Some(*button);
                    self.pressed_at = (*button == MouseButton::Left)
                        .then_some(self.cursor)
                        .flatten();
                }
                ElementState::Released if self.drag == Some(*button) => {
                    self.drag = None;
                    let clicked =
                        self.pressed_at.take().zip(self.cursor).is_some_and(
                            |((x0, y0), (x1, y1))| (x1 - x0).hypot(y1 - y0) <= CLICK_SLOP,
                        );
                    if clicked && *button == MouseButton::Left {
                        return Some(KeyAction::Pick);
                    }
                }
                _ => {}
            },
            WindowEvent::CursorMoved { position, .. } => {
                let now = (position.x, position.y);
                if let (Some(prev), Some(button)) = (self.cursor, self.drag) {
                    let (dx, dy) = ((now.0 - prev.0) as f32, (now.1 - prev.1) as f32);
                    match button {
                        MouseButton::Left => {
                            camera.orbit(-dx * ORBIT_PER_PIXEL, dy * ORBIT_PER_PIXEL)
                        }
                        MouseButton::Right | MouseButton::Middle => {
                            let h = view_height.max(1.0);
                            camera.pan(dx / h, dy / h);
                        }
                        _ => {}
                    }
                }
                self.cursor = Some(now);
            }
            WindowEvent::Touch(touch) => self.on_touch(touch, camera, view_height, pointer_free),
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } if pointer_free => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => *y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                camera.zoom(0.88f32.powf(steps));
            }
            _ => {}
        }
        None
    }

    /// One finger drags to orbit as the left button does; two pinch to zoom and move together
    /// to pan. A finger landing on the panel is egui's.
    fn on_touch(&mut self, t: &Touch, camera: &mut Camera, view_height: f32, pointer_free: bool) {
        let at = (t.location.x, t.location.y);
        match t.phase {
            TouchPhase::Started if pointer_free => {
                self.touches.insert(t.id, at);
            }
            TouchPhase::Moved => {
                let before: Vec<(f64, f64)> = self.touches.values().copied().collect();
                let Some(slot) = self.touches.get_mut(&t.id) else {
                    return;
                };
                let prev = *slot;
                *slot = at;
                let after: Vec<(f64, f64)> = self.touches.values().copied().collect();
                match (before.as_slice(), after.as_slice()) {
                    ([_], [_]) => {
                        let (dx, dy) = ((at.0 - prev.0) as f32, (at.1 - prev.1) as f32);
                        camera.orbit(-dx * ORBIT_PER_PIXEL, dy * ORBIT_PER_PIXEL);
                    }
                    ([a0, b0], [a1, b1]) => {
                        let spread = |a: &(f64, f64), b: &(f64, f64)| (a.0 - b.0).hypot(a.1 - b.1);
                        let (s0, s1) = (spread(a0, b0), spread(a1, b1));
                        if s0 > 1.0 && s1 > 1.0 {
                            camera.zoom((s0 / s1) as f32);
                        }
                        let h = view_height.max(1.0);
                        let mid =
                            |a: &(f64, f64), b: &(f64, f64)| ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
                        let (m0, m1) = (mid(a0, b0), mid(a1, b1));
                        camera.pan((m1.0 - m0.0) as f32 / h, (m1.1 - m0.1) as f32 / h);
                    }
                    _ => {}
                }
            }
            TouchPhase::Ended | TouchPhase::Cancelled => {
                self.touches.remove(&t.id);
            }
            TouchPhase::Started => {}
        }
    }

    /// Where the cursor is in the window, physical pixels, if it is in it.
    pub fn cursor(&self) -> Option<(f64, f64)> {
        self.cursor
    }

    /// Moves the camera for held fly keys over `dt` seconds; speed grows with the distance to
    /// the target so flying feels the same close up and far away.
    pub fn fly(&self, camera: &mut Camera, dt: f32) {
        let key = |k| if self.held.contains(&k) { 1.0 } else { 0.0 };
        let forward = key(KeyCode::KeyW) - key(KeyCode::KeyS);
        let right = key(KeyCode::KeyD) - key(KeyCode::KeyA);
        let up = key(KeyCode::KeyE) - key(KeyCode::KeyQ);
        if forward == 0.0 && right == 0.0 && up == 0.0 {
            return;
        }
        let fast = if self.held.contains(&KeyCode::ShiftLeft)
            || self.held.contains(&KeyCode::ShiftRight)
        {
            3.0
        } else {
            1.0
        };
        let speed = (camera.distance * 0.5).max(2.0) * fast * dt;
        camera.fly(forward * speed, right * speed, up * speed);
    }

    pub fn is_dragging(&self) -> bool {
        self.drag.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_do_what_the_readme_says() {
        assert_eq!(window_key(KeyCode::F12, false), Some(KeyAction::Screenshot));
        assert_eq!(window_key(KeyCode::F1, false), Some(KeyAction::TogglePanel));
        assert_eq!(
            window_key(KeyCode::F11, false),
            Some(KeyAction::ToggleFullscreen)
        );
        assert_eq!(window_key(KeyCode::KeyQ, true), Some(KeyAction::Quit));
        // Q alone flies down.
        assert_eq!(window_key(KeyCode::KeyQ, false), None);
        assert_eq!(view_key(KeyCode::KeyQ), None);
        assert_eq!(view_key(KeyCode::Escape), Some(KeyAction::Quit));
        assert_eq!(view_key(KeyCode::Space), Some(KeyAction::TogglePlay));
    }

    fn touch(id: u64, phase: TouchPhase, x: f64, y: f64) -> WindowEvent {
        WindowEvent::Touch(Touch {
            device_id: winit::event::DeviceId::dummy(),
            phase,
            location: winit::dpi::PhysicalPosition::new(x, y),
            force: None,
            id,
        })
    }

    #[test]
    fn one_finger_orbits_and_two_pinch_to_zoom() {
        let mut c = Controls::default();
        let mut camera = Camera {
            target: glam::Vec3::ZERO,
            yaw: 0.0,
            pitch: 0.3,
            distance: 10.0,
            fov_y: 1.0,
        };
        let start = camera;
        for e in [
            touch(1, TouchPhase::Started, 100.0, 100.0),
            touch(1, TouchPhase::Moved, 160.0, 100.0),
        ] {
            c.on_event(&e, &mut camera, 720.0, true, true);
        }
        assert_ne!(camera.yaw, start.yaw, "one finger orbits");
        assert_eq!(camera.distance, start.distance);
        let orbited = camera;
        for e in [
            touch(2, TouchPhase::Started, 260.0, 100.0),
            touch(2, TouchPhase::Moved, 360.0, 100.0),
        ] {
            c.on_event(&e, &mut camera, 720.0, true, true);
        }
        assert!(camera.distance < orbited.distance, "spreading zooms in");
        assert_eq!(camera.yaw, orbited.yaw, "two fingers do not orbit");
        for e in [
            touch(1, TouchPhase::Ended, 160.0, 100.0),
            touch(2, TouchPhase::Ended, 360.0, 100.0),
        ] {
            c.on_event(&e, &mut camera, 720.0, true, true);
        }
        assert!(c.touches.is_empty());
    }

    #[test]
    fn the_wheel_is_the_cameras_over_the_view_only() {
        // A 1280-wide window whose panel takes the left 250 pixels.
        let view = [250, 0, 1030, 720];
        assert!(over_view(Some((600.0, 300.0)), view));
        assert!(!over_view(Some((100.0, 300.0)), view), "over the panel");
        assert!(
            !over_view(Some((1280.0, 300.0)), view),
            "past the right edge"
        );
        assert!(!over_view(None, view), "outside the window");
    }
}
