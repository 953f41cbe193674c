//! Camera controls: orbit with the left mouse button, pan with the right (or middle), zoom with
//! the wheel, fly with WASD (Q/E down/up, Shift faster).

use crate::scene::Camera;
use std::collections::HashSet;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::keyboard::{KeyCode, PhysicalKey};

/// Radians of orbit per pixel dragged.
const ORBIT_PER_PIXEL: f32 = 0.005;

#[derive(Default)]
pub struct Controls {
    held: HashSet<KeyCode>,
    drag: Option<MouseButton>,
    cursor: Option<(f64, f64)>,
}

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
            WindowEvent::KeyboardInput { event, .. } if keyboard_free => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return None;
                };
                match event.state {
                    ElementState::Pressed => {
                        let first = self.held.insert(code);
                        if first {
                            match code {
                                KeyCode::Space => return Some(KeyAction::TogglePlay),
                                KeyCode::KeyR => return Some(KeyAction::ResetCamera),
                                KeyCode::KeyM => return Some(KeyAction::NextMethod),
                                KeyCode::KeyT => return Some(KeyAction::NextTransition),
                                KeyCode::KeyV => return Some(KeyAction::NextDebugView),
                                KeyCode::KeyC => return Some(KeyAction::ToggleCompare),
                                _ => {}
                            }
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
                ElementState::Pressed if pointer_free => self.drag = Some(*button),
                ElementState::Released if self.drag == Some(*button) => self.drag = None,
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
