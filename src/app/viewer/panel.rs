//! The egui side panel: statistics, levels of detail, comparison, debug views, and the crowd's
//! controls.

use crate::app::viewer::figures::{pass_times, statistics};
use crate::app::viewer::history::FrameHistory;
use crate::app::viewer::inspect::{SelectionInfo, SelectionRequests};
use crate::render::timer::PassTimes;
use crate::render::{DebugView, FrameStats};
use crate::runtime::world::LevelSummary;
use crate::scene::foliage::FoliageView;
use crate::scene::{Drive, LodMethod, LodPolicy, Transition};

/// The instance slider's top: a 10,000-character crowd and then some (`--count` goes
/// further, up to what the device's instance buffer holds).
const MAX_PANEL_COUNT: usize = 20_000;

/// Seconds a clip cross-fade takes when the panel turns stopping walkers on.
const DEFAULT_CROSS_FADE: f32 = 0.6;

/// What the user can change.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub count: usize,
    /// `None`: every model; otherwise only this one.
    pub model: Option<usize>,
    /// `None`: each character plays a clip of its own.
    pub clip: Option<String>,
    /// Seconds of a clip cross-fade when walkers stop to play a clip on the spot; 0: they
    /// never stop.
    pub cross_fade: f32,
    pub playing: bool,
    pub speed: f32,
    pub shadows: bool,
    pub method: LodMethod,
    /// Split screen: the right half shows this method.
    pub compare: Option<LodMethod>,
    pub policy: LodPolicy,
    pub debug: DebugView,
    pub foliage: FoliageView,
    /// Far characters show as their animated impostors.
    pub impostors: bool,
    /// Coarse levels are lit through their normal maps.
    pub normal_maps: bool,
    /// The panel is shown (F1 hides it, and the view takes the whole window).
    pub panel_shown: bool,
}

/// Facts the panel shows.
pub struct Info<'a> {
    pub adapter: &'a str,
    pub backend: &'a str,
    pub models: &'a [String],
    /// Clip names of every model.
    pub clips: &'a [Vec<String>],
    pub stats: FrameStats,
    /// Each pass's GPU time (smoothed), where the adapter has timestamp queries.
    pub passes: Option<PassTimes>,
    /// Pixels of the 3D view, for fragments per pixel.
    pub view_pixels: u64,
    /// The panel's own CPU time, ms a frame.
    pub panel_cpu_ms: f64,
    /// Where memory goes, bytes by kind.
    pub memory: &'a [(&'static str, u64)],
    /// What the Selection section shows.
    pub selection: SelectionInfo<'a>,
    pub time: f32,
    /// The method being baked and the fraction done.
    pub baking: Option<(String, f32)>,
    pub bake_error: Option<&'a str>,
    /// Can the adapter draw wireframes?
    pub wireframe: bool,
    /// Which methods' levels are on the GPU, in [`LodMethod::ALL`] order.
    pub ready: [bool; LodMethod::COUNT],
    /// Does the scene have trees?
    pub trees: bool,
    /// The characters' animated impostors, in a line (see `World::impostor_summary`).
    pub impostors: String,
    /// The characters' normal maps, in a line (see `World::normal_map_summary`).
    pub normal_maps: String,
    /// Where the last screenshot went, or why a model did not open.
    pub notice: Option<&'a str>,
    /// The chain each tree shows: its name, whether it is cut as the panel says, its levels.
    pub chains: Vec<(String, bool, &'a [LevelSummary])>,
}

/// What the panel asks for beyond changing [`Settings`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Requests {
    pub relayout: bool,
    pub reset_camera: bool,
    /// "Open…": pick a model file to show instead.
    pub open: bool,
    /// The Selection section's buttons.
    pub selection: SelectionRequests,
}

/// Width of the side panel in points.
pub const PANEL_WIDTH: f32 = 270.0;

/// The window size, in points, the panel is laid out for: smaller windows draw it smaller
/// (see [`panel_zoom`]).
const LAID_OUT_FOR: [f32; 2] = [1280.0, 720.0];

/// The smallest zoom a small window draws the panel at: its small text still reads.
const MIN_ZOOM: f32 = 0.7;

/// The zoom the interface is drawn at in a window `size` points large: 1 from 1280×720 up, and
/// below that shrinking with the window (to [`MIN_ZOOM`]), so that at 640×360 the panel takes
/// under a third of the width instead of 42% with its controls cut off. F1 hides it.
pub fn panel_zoom(size: [f32; 2]) -> f32 {
    (size[0] / LAID_OUT_FOR[0])
        .min(size[1] / LAID_OUT_FOR[1])
        .clamp(MIN_ZOOM, 1.0)
}

/// Sets `ctx`'s zoom for a window `pixels` large (physical), as [`panel_zoom`] says.
pub fn zoom_for_window(ctx: &egui::Context, pixels: [u32; 2]) {
    let native = ctx.native_pixels_per_point().unwrap_or(1.0);
    let zoom = panel_zoom(pixels.map(|p| p as f32 / native));
    if (ctx.zoom_factor() - zoom).abs() > 1e-3 {
        ctx.set_zoom_factor(zoom);
    }
}

/// One frame of the viewer's interface: the panel on the left and, over the 3D view, the
/// split-screen labels. Returns what the panel asked for and the rectangle left to the 3D view
/// (in points).
pub fn frame(
    ui: &mut egui::Ui,
    s: &mut Settings,
    history: &FrameHistory,
    info: &Info,
) -> (Requests, egui::Rect) {
    let mut requests = Requests::default();
    if s.panel_shown {
        egui::Panel::left("lodlab panel")
            .resizable(false)
            .exact_size(PANEL_WIDTH)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    requests = show(ui, s, history, info);
                });
            });
    }
    let central = ui.available_rect_before_wrap();
    if !s.panel_shown {
        super::overlay::hidden_hint(ui, central);
    }
    if let Some(right) = s.compare {
        super::overlay::compare_overlay(ui, central, s.method, right);
    }
    (requests, central)
}

pub fn show(ui: &mut egui::Ui, s: &mut Settings, history: &FrameHistory, info: &Info) -> Requests {
    let open = header(ui, info);
    ui.separator();

    statistics(ui, history, &info.stats);
    pass_times(
        ui,
        info.passes.as_ref(),
        info.view_pixels,
        info.panel_cpu_ms,
        info.memory,
    );
    ui.separator();
    level_of_detail(ui, s, info);
    ui.separator();
    let mut requests = Requests {
        open,
        ..Default::default()
    };
    // The rest fold, closed at first, so that at 720 lines every section's title is on screen
    // and nothing moves under the cursor until one is opened.
    super::inspect::section(ui, &info.selection, &mut requests.selection);
    section(ui, "Compare", |ui| compare(ui, s, info));
    section(ui, "Debug view", |ui| debug_views(ui, s, info));
    if info.trees {
        section(ui, "Foliage", |ui| {
            super::foliage_panel::foliage(ui, &mut s.foliage, s.method, &info.chains)
        });
    }
    requests.relayout = section(ui, "Crowd", |ui| crowd(ui, s, info)).unwrap_or(false);
    section(ui, "Animation", |ui| animation(ui, s, info));
    requests.reset_camera = section(ui, "Camera", camera).unwrap_or(false);
    requests
}

/// A section of the panel that folds, closed at first; what `body` returned where it is open.
fn section<R>(ui: &mut egui::Ui, title: &str, body: impl FnOnce(&mut egui::Ui) -> R) -> Option<R> {
    egui::CollapsingHeader::new(egui::RichText::new(title).strong())
        .id_salt(title)
        .default_open(false)
        .show(ui, body)
        .body_returned
}

/// The panel's head: the name and "Open…", the adapter, the keys, and the latest notice.
/// Returns whether "Open…" was clicked, for [`Requests::open`].
fn header(ui: &mut egui::Ui, info: &Info) -> bool {
    let mut open = false;
    ui.horizontal(|ui| {
        ui.heading("lodlab");
        // A page shows the scenes it was written with (see `lodlab web`).
        if cfg!(not(target_arch = "wasm32")) {
            open = ui
                .button("Open…")
                .on_hover_text("Show a .glb or .gltf model instead of the scene's models, trees too (or drop one on the window)")
                .clicked();
        }
    });
    let adapter = if info.adapter.is_empty() {
        info.backend.to_string()
    } else {
        format!("{} · {}", info.adapter, info.backend)
    };
    ui.label(egui::RichText::new(adapter).small());
    // A notice takes the keys' line (one line either way, so that nothing below moves when
    // one comes); a longer one is cut, whole in its tooltip.
    let keys = if cfg!(target_arch = "wasm32") {
        "drag to orbit · wheel or pinch to zoom · M method · T transition"
    } else {
        "F1 panel · F12 screenshot · F11 fullscreen · Esc or Ctrl+Q quit"
    };
    let line = match info.notice {
        Some(notice) => egui::RichText::new(notice).small().strong(),
        None => egui::RichText::new(keys).small(),
    };
    ui.add(egui::Label::new(line).truncate())
        .on_hover_text(info.notice.unwrap_or(keys));
    open
}

/// The crowd: how many instances, which model and clip, and whether walkers stop to wave.
/// Returns whether any of them changed, so that the crowd is laid out again
/// ([`Requests::relayout`]).
fn crowd(ui: &mut egui::Ui, s: &mut Settings, info: &Info) -> bool {
    let mut relayout = false;
    if ui
        .add(
            egui::Slider::new(&mut s.count, 0..=MAX_PANEL_COUNT)
                .logarithmic(true)
                .text("instances"),
        )
        .on_hover_text("Characters in the scene (trees apart): each costs its level's triangles and vertex skinning a frame; the crowd is laid out again (--count)")
        .changed()
    {
        relayout = true;
    }
    let model_label = |m: Option<usize>| match m {
        None => info.models.join(" + "),
        Some(i) => info.models[i].clone(),
    };
    egui::ComboBox::from_label("model")
        .selected_text(model_label(s.model))
        .show_ui(ui, |ui| {
            for choice in std::iter::once(None).chain((0..info.models.len()).map(Some)) {
                if ui
                    .selectable_value(&mut s.model, choice, model_label(choice))
                    .changed()
                {
                    s.clip = None;
                    relayout = true;
                }
            }
        })
        .response
        .on_hover_text("Which of the scene's models the crowd is made of: all, or one alone (nothing is reloaded)");
    let mut names: Vec<String> = Vec::new();
    for (i, clips) in info.clips.iter().enumerate() {
        if s.model.is_none_or(|m| m == i) {
            for c in clips {
                if !names.contains(c) {
                    names.push(c.clone());
                }
            }
        }
    }
    egui::ComboBox::from_label("clip")
        .selected_text(s.clip.clone().unwrap_or_else(|| "mixed".into()))
        .show_ui(ui, |ui| {
            if ui.selectable_value(&mut s.clip, None, "mixed").changed() {
                relayout = true;
            }
            for n in &names {
                if ui
                    .selectable_value(&mut s.clip, Some(n.clone()), n)
                    .changed()
                {
                    relayout = true;
                }
            }
        })
        .response
        .on_hover_text("The clip every character plays, or a mix of their clips (--clip)");
    // Walkers stopping to play a clip on the spot (a wave), cross-fading into it and back.
    let mut stopping = s.cross_fade > 0.0;
    if ui
        .checkbox(&mut stopping, "walkers stop and wave")
        .on_hover_text("Lanes whose model has a clip played on the spot stop now and then to play it, cross-fading the two clips' bone matrices")
        .changed()
    {
        s.cross_fade = if stopping { DEFAULT_CROSS_FADE } else { 0.0 };
        relayout = true;
    }
    if stopping
        && ui
            .add(egui::Slider::new(&mut s.cross_fade, 0.1..=3.0).text("cross-fade s"))
            .on_hover_text("Seconds the walk and the wave blend over (--cross-fade); a fading instance reads twice the bone matrices")
            .changed()
    {
        relayout = true;
    }
    relayout
}

/// Animation: play or pause, the clock, the speed, and blob shadows.
fn animation(ui: &mut egui::Ui, s: &mut Settings, info: &Info) {
    ui.horizontal(|ui| {
        let label = if s.playing { "Pause" } else { "Play" };
        if ui
            .button(label)
            .on_hover_text("Stop or start the animation clock (Space); levels keep being chosen")
            .clicked()
        {
            s.playing = !s.playing;
        }
        ui.label(format!("t = {:.2} s", info.time));
    });
    ui.add(egui::Slider::new(&mut s.speed, 0.0..=3.0).text("speed"))
        .on_hover_text("Playback speed of every clip; costs nothing");
    ui.checkbox(&mut s.shadows, "blob shadows")
        .on_hover_text("A soft disc under each character, blended over the ground: one small pass");
}

/// The camera: a reset button and the mouse and keyboard controls. Returns whether the reset
/// was clicked, for [`Requests::reset_camera`].
fn camera(ui: &mut egui::Ui) -> bool {
    let mut reset = false;
    if ui
        .button("reset view (R)")
        .on_hover_text("Back to the camera the scene opened with")
        .clicked()
    {
        reset = true;
    }
    ui.label(
        egui::RichText::new(
            "left drag: orbit · right drag: pan\nwheel: zoom · WASD: fly · Q/E: down/up\nShift: faster · Space: play/pause",
        )
        .small(),
    );
    reset
}

/// A method picker; methods still to bake say so.
fn method_combo(ui: &mut egui::Ui, id: &str, value: &mut LodMethod, info: &Info) {
    egui::ComboBox::from_label(id)
        .selected_text(value.name())
        .show_ui(ui, |ui| {
            for m in LodMethod::ALL {
                let label = if info.ready[m.index()] {
                    m.name().to_string()
                } else {
                    format!("{} (bakes on first use)", m.name())
                };
                ui.selectable_value(value, m, label);
            }
        })
        .response
        .on_hover_text("How characters are simplified (Merry et al.): none (full detail), rest-pose (the rest pose's quadric error), as (animation space's L2,2 metric over the clips), as+is (as, with influence simplification: fewer bones a vertex, cheaper skinning). Trees follow their foliage policy under any simplified method. M: next");
}

fn level_of_detail(ui: &mut egui::Ui, s: &mut Settings, info: &Info) {
    // The heading shares its line with the bake's progress, its failure or "in place", so
    // that nothing below moves when a bake starts or ends.
    ui.horizontal(|ui| {
        ui.strong("Level of detail")
            .on_hover_text("Keys: M next method, T next transition");
        if let Some(e) = info.bake_error {
            let text = egui::RichText::new(e).small().color(ui.visuals().error_fg_color);
            ui.add(egui::Label::new(text).truncate()).on_hover_text(e);
        } else if let Some((what, f)) = &info.baking {
            ui.add(
                egui::ProgressBar::new(*f)
                    .text(egui::RichText::new(format!("baking {:.0}%", f * 100.0)).small())
                    .desired_height(14.0),
            )
            .on_hover_text(format!(
                "baking {what} in the background; full detail is drawn until each model's levels are in"
            ));
        } else {
            ui.label(egui::RichText::new("levels in place").small().weak());
        }
    });
    method_combo(ui, "method", &mut s.method, info);
    let p = &mut s.policy;
    egui::ComboBox::from_label("transition")
        .selected_text(p.transition.name())
        .show_ui(ui, |ui| {
            for t in Transition::ALL {
                ui.selectable_value(&mut p.transition, t, t.name());
            }
        })
        .response
        .on_hover_text("How a character changes level (Houle & Poulin): pop (at once), alpha (both levels drawn, the new one fading in: twice the cost while it lasts), morph (geomorph: vertices glide, one level drawn), dither (each level on its share of the pixels). T: next");
    // Greyed out, not hidden, under pop: the rows below stay where they are.
    ui.add_enabled_ui(p.transition != Transition::Pop, |ui| {
        ui.horizontal(|ui| {
            ui.radio_value(&mut p.drive, Drive::Time, "over time")
                .on_hover_text("A transition runs for a fixed time once the level changes");
            ui.radio_value(&mut p.drive, Drive::Zone, "morph zones")
                .on_hover_text("A transition follows the distance across a zone round each switch distance (Houle & Poulin's morph zones): no time, no popping when the camera stops");
        });
        match p.drive {
            Drive::Time => ui
                .add(
                    egui::Slider::new(&mut p.duration, 0.05..=3.0)
                        .suffix(" s")
                        .text("duration"),
                )
                .on_hover_text("Seconds a transition takes (--duration)"),
            Drive::Zone => ui
                .add(
                    egui::Slider::new(&mut p.zone_width, 0.05..=1.0)
                        .text("zone width")
                        .custom_formatter(|x, _| format!("{:.0}%", x * 100.0)),
                )
                .on_hover_text(
                    "Width of a morph zone, as a share of its switch distance (--zone-width)",
                ),
        };
    });
    ui.add(
        egui::Slider::new(&mut p.tolerance_px, 0.25..=16.0)
            .logarithmic(true)
            .suffix(" px")
            .text("tolerance"),
    )
    .on_hover_text("The largest error a level may show on screen, in pixels: each instance draws the coarsest level within it. Larger: fewer triangles, more visible error (--tolerance)");
    ui.horizontal(|ui| {
        let mut on = p.force_level.is_some();
        let mut level = p.force_level.unwrap_or(0);
        let label = ui.checkbox(&mut on, "force level")
            .on_hover_text("Every character shows this level (its coarsest if it has fewer), whatever its distance: to look at one level close up (--force-level)");
        ui.add_enabled(on, egui::DragValue::new(&mut level).range(0..=15))
            .labelled_by(label.id);
        p.force_level = on.then_some(level);
    });
    // What each model's impostor and normal maps are is in the tooltips, not in lines of
    // their own, so that the panel fits a 720-line window.
    ui.checkbox(&mut s.impostors, "far characters as impostors")
        .on_hover_text(format!("Below its coarsest mesh a character becomes one quad showing it baked from the nearest of a grid of views at the frames round its time, under every simplified method (--impostors). Costs a texture per model, baked once.\n\n{}", info.impostors));
    ui.checkbox(&mut s.normal_maps, "normal maps on coarse levels")
        .on_hover_text(format!("Coarse levels are lit by full detail's normals, baked into a normal map on each level's texture coordinates (Merry et al.); off, by their own vertex normals (--no-normal-maps). Models without usable texture coordinates keep their vertex normals. Costs one texture read a pixel.\n\n{}", info.normal_maps));
    ui.add(
        egui::Slider::new(&mut p.hysteresis, 0.0..=0.9)
            .text("hysteresis")
            .custom_formatter(|x, _| format!("{:.0}%", x * 100.0)),
    )
    .on_hover_text("A coarser level must undercut the tolerance by this share before it comes in, so that an instance at a switch distance does not flicker between levels (--hysteresis)");
}

fn compare(ui: &mut egui::Ui, s: &mut Settings, info: &Info) {
    let mut on = s.compare.is_some();
    if ui
        .checkbox(&mut on, "split screen: method left, this right (C)")
        .on_hover_text("The same camera and time, the panel's method on the left half and another on the right: both are selected and drawn, so the frame costs both (--compare)")
        .changed()
    {
        s.compare = toggle_compare(s);
    }
    if let Some(right) = &mut s.compare {
        method_combo(ui, "right half", right, info);
    }
}

/// The comparison after switching it on or off: on, it shows full detail against a simplified
/// method, whichever the left half does not.
pub fn toggle_compare(s: &Settings) -> Option<LodMethod> {
    match s.compare {
        Some(_) => None,
        None if s.method == LodMethod::None => Some(LodMethod::AS_IS),
        None => Some(LodMethod::None),
    }
}

fn debug_views(ui: &mut egui::Ui, s: &mut Settings, info: &Info) {
    ui.label(egui::RichText::new("V: next view").small());
    for (view, label) in [
        (DebugView::Shaded, "shaded"),
        (DebugView::LodTint, "tint by level"),
        (DebugView::TransitionTint, "tint by transition t"),
        (DebugView::Wireframe, "wireframe"),
        (DebugView::Influences, "influences per vertex"),
    ] {
        let enabled = view != DebugView::Wireframe || info.wireframe;
        ui.add_enabled_ui(enabled, |ui| {
            ui.radio_value(&mut s.debug, view, label)
                .on_hover_text("What the characters are drawn with; only the colours change, the levels and the cost stay (V: next; --debug-view)")
                .on_disabled_hover_text("this adapter cannot draw lines");
        });
    }
    let legend = match s.debug {
        DebugView::LodTint | DebugView::Wireframe => {
            Some("level 0 green … 9 blue, as in the histogram")
        }
        DebugView::TransitionTint => Some("t = 0 blue … t = 1 red; grey: not in transition"),
        DebugView::Influences => Some("one influence blue … eight or more red"),
        DebugView::Shaded => None,
    };
    if let Some(l) = legend {
        ui.label(egui::RichText::new(l).small());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::viewer::figures::thousands;
    use crate::app::viewer::history::{MIN_SAMPLES, PAUSE_SECONDS};

    #[test]
    fn fps_counts_the_last_second() {
        let mut h = FrameHistory::default();
        for k in 0..200 {
            h.push(k as f64 * 0.02, 20.0);
        }
        assert!((h.fps() - 50.0).abs() < 0.5);
        // Old samples drop out of the window.
        assert!(h.samples.len() <= 252);
    }

    #[test]
    fn slow_frames_read_as_they_are() {
        // lavapipe drawing a big scene: 3.4 s a frame.
        let mut h = FrameHistory::default();
        for k in 1..=10 {
            h.push(k as f64 * 3.4, 3400.0);
        }
        assert!((h.fps() - 1.0 / 3.4).abs() < 1e-3, "{}", h.fps());
        assert_eq!(h.mean_ms(), 3400.0);
        // Frames older than the graph's span stay, so there is a line to draw.
        assert_eq!(h.samples.len(), MIN_SAMPLES);
        // The animation keeps wall time at that rate...
        assert_eq!(h.animation_step(3.4), 3.4);
        // ...but not across a pause far longer than the usual frame.
        assert_eq!(h.animation_step(60.0), 4.0 * 3.4);
    }

    #[test]
    fn a_pause_does_not_jump_the_animation() {
        let mut h = FrameHistory::default();
        // Before any frame is known, and at 60 Hz, a long gap is clamped to half a second.
        assert_eq!(h.animation_step(5.0), PAUSE_SECONDS);
        for k in 0..100 {
            h.push(k as f64 / 60.0, 1000.0 / 60.0);
        }
        assert_eq!(h.animation_step(1.0 / 60.0), 1.0 / 60.0);
        assert_eq!(h.animation_step(5.0), PAUSE_SECONDS);
    }

    #[test]
    fn thousands_separators() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(1234567), "1,234,567");
        assert_eq!(thousands(999), "999");
    }
}

/// The panel under a pointer, as the viewer runs it, at lavapipe's frame rates.
#[cfg(test)]
mod clicks {
    use super::*;
    use egui_kittest::Harness;
    use egui_kittest::kittest::{Queryable, by};

    /// The panel drawn once a frame, each frame `frame_seconds` long, with the viewer's input
    /// options; the state is what the user changed and what the panel last asked for.
    fn panel(frame_seconds: f32) -> Harness<'static, (Settings, Requests)> {
        let settings = Settings {
            count: 100,
            model: None,
            clip: None,
            cross_fade: 0.0,
            playing: true,
            speed: 1.0,
            shadows: true,
            method: LodMethod::AS_IS,
            compare: None,
            policy: LodPolicy::default(),
            debug: DebugView::Shaded,
            foliage: FoliageView::default(),
            impostors: true,
            normal_maps: true,
            panel_shown: true,
        };
        Harness::builder()
            .with_size([PANEL_WIDTH + 300.0, 2000.0])
            .with_step_dt(frame_seconds)
            .with_context_setup(crate::app::window::configure_egui)
            .build_ui_state(
                |ui, (s, requests): &mut (Settings, Requests)| {
                    let models = ["walker".to_string()];
                    let clips = [vec!["walk".to_string()]];
                    let info = Info {
                        adapter: "test",
                        backend: "none",
                        models: &models,
                        clips: &clips,
                        stats: FrameStats::default(),
                        passes: None,
                        view_pixels: 0,
                        panel_cpu_ms: 0.0,
                        memory: &[],
                        selection: SelectionInfo::default(),
                        time: 0.0,
                        baking: None,
                        bake_error: None,
                        wireframe: false,
                        ready: [true; LodMethod::COUNT],
                        trees: false,
                        impostors: String::new(),
                        normal_maps: String::new(),
                        notice: None,
                        chains: Vec::new(),
                    };
                    let (asked, _) = frame(ui, s, &FrameHistory::default(), &info);
                    if asked != Requests::default() {
                        *requests = asked;
                    }
                },
                (settings, Requests::default()),
            )
    }

    /// Presses and releases the primary button at the centre of `rect`, with `frames` frames
    /// between (0: both inside one frame).
    fn click(
        harness: &mut Harness<'static, (Settings, Requests)>,
        rect: egui::Rect,
        frames: usize,
    ) {
        let pos = rect.center();
        let button = |pressed| egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::default(),
        };
        harness
            .input_mut()
            .events
            .push(egui::Event::PointerMoved(pos));
        harness.step();
        harness.input_mut().events.push(button(true));
        for _ in 0..frames {
            harness.step();
        }
        harness.input_mut().events.push(button(false));
        harness.step();
        harness.step();
    }

    /// F1's hidden panel leaves its controls out and the view the whole window, with a
    /// label saying how to bring it back; small windows draw it smaller.
    #[test]
    fn a_hidden_panel_leaves_the_window_to_the_view() {
        let mut h = panel(0.1);
        h.run_steps(2);
        assert!(h.query_by_label("transition").is_some());
        h.state_mut().0.panel_shown = false;
        h.run_steps(2);
        assert!(h.query_by_label("transition").is_none());
        assert!(h.query_by_label("force level").is_none());
        assert_eq!(panel_zoom([1280.0, 720.0]), 1.0);
        assert_eq!(panel_zoom([2560.0, 1440.0]), 1.0);
        let small = panel_zoom([640.0, 360.0]);
        assert!(PANEL_WIDTH * small / 640.0 < 1.0 / 3.0, "{small}");
        assert!(small >= MIN_ZOOM);
    }

    #[test]
    fn a_checkbox_takes_one_slow_click() {
        // Two seconds a frame, the press in one frame and the release in the next; then both
        // inside one frame.
        for frames in [1, 0] {
            let mut h = panel(2.0);
            h.run_steps(2);
            // The checkbox, not the level box it labels.
            let rect = h
                .get(
                    by().label("force level")
                        .include_labels()
                        .role(egui::accesskit::Role::CheckBox),
                )
                .rect();
            click(&mut h, rect, frames);
            assert_eq!(h.state().0.policy.force_level, Some(0), "{frames} frames");
            click(&mut h, rect, frames);
            assert_eq!(h.state().0.policy.force_level, None, "{frames} frames");
        }
    }

    #[test]
    fn a_combo_box_takes_one_slow_click_to_open_and_one_to_pick() {
        for frames in [1, 0] {
            let mut h = panel(2.0);
            h.run_steps(2);
            assert_eq!(h.state().0.policy.transition, Transition::Morph);
            let combo = h.get_by_label("transition").rect();
            click(&mut h, combo, frames);
            let pop = h.get_by_label(Transition::Pop.name()).rect();
            click(&mut h, pop, frames);
            assert_eq!(
                h.state().0.policy.transition,
                Transition::Pop,
                "{frames} frames"
            );
        }
    }

    /// Choosing pop greys the drive and duration rows out instead of taking them away: the
    /// controls below stay under the cursor.
    #[test]
    fn controls_stay_put_when_the_transition_changes() {
        let mut h = panel(0.1);
        h.run_steps(2);
        let force = || {
            by().label("force level")
                .include_labels()
                .role(egui::accesskit::Role::CheckBox)
        };
        let before = h.get(force()).rect();
        let combo = h.get_by_label("transition").rect();
        click(&mut h, combo, 0);
        let pop = h.get_by_label(Transition::Pop.name()).rect();
        click(&mut h, pop, 0);
        assert_eq!(h.state().0.policy.transition, Transition::Pop);
        assert_eq!(h.get(force()).rect(), before);
    }

    #[test]
    fn a_button_takes_one_slow_click() {
        let mut h = panel(2.0);
        h.run_steps(2);
        let open = h.get_by_label("Open…").rect();
        click(&mut h, open, 1);
        assert!(h.state().1.open);
    }
}
