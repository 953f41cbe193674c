//! The panel's Foliage section: the trees' level policy, how their chains are cut, wind,
//! outlines, tint, lighting, and the levels of the chains shown.

use crate::app::viewer::figures::chain_table;
use crate::bake::foliage::billboard::chain::MIN_EPSILON_GROWTH;
use crate::bake::foliage::billboard::chain::levels::FoliageOrder;
use crate::bake::foliage::spectral::description::DescriptionType;
use crate::runtime::world::LevelSummary;
use crate::scene::LodMethod;
use crate::scene::foliage::{FoliagePolicy, FoliageView};

/// Trees: the level policy, how their chains are cut, wind, outlines, tint, and the levels of
/// the chains shown.
pub(super) fn foliage(
    ui: &mut egui::Ui,
    f: &mut FoliageView,
    method: LodMethod,
    chains: &[(String, bool, &[LevelSummary])],
) {
    egui::ComboBox::from_label("level policy")
        .selected_text(f.policy.name())
        .show_ui(ui, |ui| {
            for p in FoliagePolicy::ALL {
                ui.selectable_value(&mut f.policy, p, p.name());
            }
        })
        .response
        .on_hover_text("What trees become under a simplified method (Bennett-Therkildsen et al.): automatic (skeleton clouds near, spectral clouds farther, view-selected clumps and impostors farthest), skeleton or spectral clouds alone, or full (every leaf: the costliest). A change bakes new chains in the background (--foliage)");
    if method == LodMethod::None && f.policy != FoliagePolicy::Full {
        ui.label(
            egui::RichText::new("method none: trees are drawn full; pick a method to see clouds")
                .small(),
        );
    }
    let clouds = f.policy != FoliagePolicy::Full;
    let spectral = matches!(f.policy, FoliagePolicy::Spectral | FoliagePolicy::Automatic);
    ui.add_enabled_ui(clouds, |ui| {
        let c = &mut f.chain;
        egui::ComboBox::from_label("level order")
            .selected_text(c.order.name())
            .show_ui(ui, |ui| {
                for o in FoliageOrder::ALL {
                    ui.selectable_value(&mut c.order, o, o.name());
                }
            })
            .response
            .on_hover_text(
                "cost: at each size the cheapest level (fragments and triangles, measured) \
                 whose colour error is no worse than the ε chain's there; epsilon: each level \
                 from where its ε projects to the tolerance (the thesis's chain)",
            );
        ui.add(
            egui::Slider::new(&mut c.first_epsilon, 0.001..=0.05)
                .logarithmic(true)
                .text("ε of level 1")
                .custom_formatter(|x, _| format!("{:.2}% h", x * 100.0)),
        )
        .on_hover_text("ε of the first cloud level, as a share of the tree's height");
        ui.add(
            egui::Slider::new(&mut c.epsilon_growth, MIN_EPSILON_GROWTH..=4.0)
                .text("ε per level")
                .custom_formatter(|x, _| format!("×{x:.2}")),
        )
        .on_hover_text("each level's ε is the last one's times this");
        ui.add_enabled_ui(spectral, |ui| {
            egui::ComboBox::from_label("description")
                .selected_text(c.description.name())
                .show_ui(ui, |ui| {
                    for d in DescriptionType::ALL {
                        ui.selectable_value(&mut c.description, d, d.name());
                    }
                })
                .response
                .on_hover_text("How a spectral billboard's motion is described (thesis Ch. 5): naive, dominating axis or axis and phase (--description)");
            ui.add(egui::Slider::new(&mut c.bins, 1..=16).text("K lines per axis"))
                .on_hover_text("Frequencies kept per axis of each billboard's motion: more follow the leaves closer, and each costs three texture reads a vertex (--bins)");
            ui.checkbox(&mut c.shared_bone, "shared bone (§6.4)")
                .on_hover_text(
                    "billboards follow their leaves' deepest shared bone; off: plain SCA, \
                     billboards hang from the root with all the motion in their spectra",
                );
        });
    });
    ui.add(egui::Slider::new(&mut f.wind, 0.0..=3.0).text("wind strength"))
        .on_hover_text(
            "Scales every tree's sway about its rest pose (0: still air); costs nothing (--wind)",
        );
    ui.checkbox(&mut f.outlines, "billboard outlines")
        .on_hover_text("Each billboard's outline in magenta, half see-through: where the planes are (--outlines)");
    ui.checkbox(&mut f.tint, "tint trees by level")
        .on_hover_text(
            "Trees coloured by the level they draw, characters as they are (--foliage-tint)",
        );
    let mut lit = f.atlas_lighting.unwrap_or(true);
    if ui
        .checkbox(&mut lit, "light billboards per texel")
        .on_hover_text(
            "each billboard texel lit by the normal of the leaf drawn there; off: one \
             shade per billboard, by its plane (the thesis); off by default on a CPU \
             adapter, where it costs about a fifth of the frame",
        )
        .changed()
    {
        f.atlas_lighting = Some(lit);
    }
    ui.checkbox(&mut f.prepass, "foliage depth pre-pass")
        .on_hover_text(
            "plane-lit leaves drawn twice: depth first (alpha tested), then colour where the \
             depth is equal, so each pixel is shaded once; one sample a pixel only. On \
             lavapipe the second pass rasterises every layer again: the foliage pass takes \
             about 1.6× as long",
        );
    for (name, current, levels) in chains {
        let title = if *current {
            format!("{name}: {} levels", levels.len())
        } else {
            format!("{name}: {} levels (earlier settings)", levels.len())
        };
        egui::CollapsingHeader::new(title)
            .id_salt(("chain", name))
            .show(ui, |ui| chain_table(ui, name, levels));
    }
}
