//! The options several commands share: the scene (models, counts, seed, clip), the level
//! policy (method, transition, tolerance) and the foliage (policy, chain, wind).

use crate::app::cli::values::{
    parse_compare, parse_epsilon_growth, parse_first_epsilon, parse_hysteresis, parse_non_negative,
    parse_seconds, parse_tolerance, parse_wind,
};
use crate::bake::foliage::billboard::chain::ChainOptions;
use crate::bake::foliage::spectral::description::DescriptionType;
use crate::render::DebugView;
use crate::runtime::headless::ShotLod;
use crate::runtime::spec::{BakeInputs, SceneSpec};
use crate::scene::SceneKind;
use crate::scene::foliage::{FoliagePolicy, FoliageView};
use crate::scene::{Drive, LodMethod, LodPolicy, Transition};
use clap::Args;
use std::path::PathBuf;

/// Which scene and which characters.
#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// Scene to show: mixed (the crowd walking in a clearing of the forest), crowd
    /// (characters), forest (trees) or study (copies of one model) [default: mixed; study for
    /// record].
    #[arg(long, value_enum)]
    pub scene: Option<SceneKind>,
    #[arg(
        long = "model",
        value_name = "NAME|PATH",
        help = format!(
            "Model: a built-in asset ({}) or a glTF path. Repeat for several; the models replace the scene's own, trees included",
            crate::assets::model_names()
        )
    )]
    pub models: Vec<String>,
    /// Number of characters (or trees in the forest) [default: 300 characters, 500 trees, 100
    /// copies in the study scene].
    #[arg(long)]
    pub count: Option<usize>,
    /// Trees round the mixed scene's clearing.
    #[arg(long, default_value_t = crate::scene::kind::DEFAULT_MIXED_TREES)]
    pub trees: usize,
    /// Play this clip on every model that has it (default: a mix).
    #[arg(long)]
    pub clip: Option<String>,
    /// Seed of the crowd layout.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Walkers stop now and then to play a clip on the spot (a wave), cross-fading into it and
    /// back over this many seconds; 0: they never stop.
    #[arg(long, default_value_t = 0.0, value_name = "SECONDS", value_parser = parse_seconds)]
    pub cross_fade: f32,
    /// Far characters become animated impostors, their last level of detail under every
    /// simplified method: VIEWSxFRAMESxCELL is views on a side of the view grid, frames per
    /// clip and texels on a side of a view (memory grows as views² × frames × cell²), or
    /// `off`.
    #[arg(long, default_value = "12x12x24", value_name = "VIEWSxFRAMESxCELL|off", value_parser = parse_impostors)]
    pub impostors: Impostors,
    /// Cache folder of baked levels of detail (default: the platform cache folder's lodlab/).
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
}

impl SceneArgs {
    /// The scene asked for, its models read and their levels cut as `inputs` says.
    pub fn spec(&self, inputs: &BakeInputs) -> SceneSpec {
        self.spec_or(SceneKind::Mixed, inputs)
    }

    /// The scene asked for, `default` where none is.
    pub fn spec_or(&self, default: SceneKind, inputs: &BakeInputs) -> SceneSpec {
        let scene = self.scene.unwrap_or(default);
        SceneSpec {
            count: self.count.unwrap_or_else(|| scene.default_count()),
            scene,
            models: self.models.clone(),
            trees: self.trees,
            clip: self.clip.clone(),
            seed: self.seed,
            cross_fade: self.cross_fade,
            impostors: self.impostors.0,
            cache_dir: self.cache.clone(),
            inputs: inputs.clone(),
        }
    }
}

/// Levels of detail: which, how they change, what the view shows.
#[derive(Args, Debug, Clone)]
pub struct LodArgs {
    /// Level-of-detail method: none, rest-pose, as, as+is [default: as+is in the viewer, none
    /// for shot, the full-detail baseline].
    #[arg(long, value_enum)]
    pub method: Option<LodMethod>,
    #[command(flatten)]
    pub policy: PolicyArgs,
    /// Debug view: shaded, lod, transition, wireframe, influences.
    #[arg(long, default_value = "shaded", value_enum)]
    pub debug_view: DebugView,
    /// Light the coarse levels with their vertex normals only, not through the normal maps
    /// baked from full detail.
    #[arg(long)]
    pub no_normal_maps: bool,
    /// Split the view: method A on the left half, B on the right, e.g. as+is,rest-pose.
    #[arg(long, value_name = "A,B", value_parser = parse_compare)]
    pub compare: Option<(LodMethod, LodMethod)>,
    #[command(flatten)]
    pub foliage: FoliageArgs,
}

/// How instances choose and change levels.
#[derive(Args, Debug, Clone)]
pub struct PolicyArgs {
    /// Transition between levels: pop, alpha (blend), morph (geomorph), dither (screen-door
    /// cross-fade).
    #[arg(long, default_value_t = LodPolicy::DEFAULT.transition, value_enum)]
    pub transition: Transition,
    /// What drives alpha, morph and dither: time (over --duration) or zone (morph zones over
    /// distance).
    #[arg(long, value_enum, default_value_t = LodPolicy::DEFAULT.drive)]
    pub drive: Drive,
    /// Seconds a time-driven transition takes.
    #[arg(long, default_value_t = LodPolicy::DEFAULT.duration, value_parser = parse_seconds)]
    pub duration: f32,
    /// Width of a morph zone, as a fraction of its threshold distance.
    #[arg(long, default_value_t = LodPolicy::DEFAULT.zone_width, value_parser = parse_non_negative)]
    pub zone_width: f32,
    /// Largest projected error allowed, in pixels (0.25 to 16).
    #[arg(long, default_value_t = LodPolicy::DEFAULT.tolerance_px, value_parser = parse_tolerance)]
    pub tolerance: f32,
    /// Hysteresis: the fraction of the tolerance a coarser level must undercut (0 to 0.9).
    #[arg(long, default_value_t = LodPolicy::DEFAULT.hysteresis, value_parser = parse_hysteresis)]
    pub hysteresis: f32,
    /// Show level N of every character (its coarsest if it has fewer), whatever the distance.
    #[arg(long, value_name = "N")]
    pub force_level: Option<u8>,
}

impl PolicyArgs {
    pub fn policy(&self) -> LodPolicy {
        LodPolicy {
            tolerance_px: self.tolerance,
            hysteresis: self.hysteresis,
            transition: self.transition,
            drive: self.drive,
            duration: self.duration,
            zone_width: self.zone_width,
            force_level: self.force_level,
        }
    }
}

/// Trees: what they become under a simplified method and how they look.
#[derive(Args, Debug, Clone)]
pub struct FoliageArgs {
    /// Trees' level policy: automatic (skeleton clouds near, spectral clouds far, view-selected
    /// clumps farthest), skeleton, spectral, or full (every leaf at every distance).
    #[arg(long, default_value = "automatic", value_enum)]
    pub foliage: FoliagePolicy,
    /// ε of a tree's first cloud level, as a fraction of its height.
    #[arg(long, default_value_t = ChainOptions::default().first_epsilon, value_parser = parse_first_epsilon)]
    pub first_epsilon: f32,
    /// Factor from one cloud level's ε to the next (1.25 to 8).
    #[arg(long, default_value_t = ChainOptions::default().epsilon_growth, value_parser = parse_epsilon_growth)]
    pub epsilon_growth: f32,
    /// Spectral description type of spectral clouds: naive, dominating-axis, axis-phase.
    #[arg(long, default_value = "axis-phase", value_enum)]
    pub description: DescriptionType,
    /// Frequency lines kept per axis by spectral clouds (K, 1 to 16).
    #[arg(long, default_value_t = crate::bake::foliage::spectral::DEFAULT_BINS as u16, value_parser = clap::value_parser!(u16).range(1..=16))]
    pub bins: u16,
    /// Plain SCA: spectral billboards hang from the root with all their leaves' motion in their
    /// spectra, instead of following the leaves' shared bone (Bennett-Therkildsen, Carlsen &
    /// Schmid's thesis "Animated Billboard Clouds for Foliage Simplification" (2007) §6.4).
    #[arg(long)]
    pub plain_sca: bool,
    /// Which of a tree's levels each size draws: epsilon (each level from where its ε
    /// projects to the tolerance, the thesis's chain) or cost (at each switch size the
    /// cheapest level, in measured fragments and triangles, whose measured colour error is no
    /// worse than the ε chain's there).
    #[arg(long, default_value = "cost", value_enum)]
    pub foliage_order: crate::bake::foliage::billboard::chain::levels::FoliageOrder,
    /// Wind strength: scales every tree's sway (0: still air; 1: as baked).
    #[arg(long, default_value_t = 1.0, value_parser = parse_wind)]
    pub wind: f32,
    /// Draw the outlines of the billboards.
    #[arg(long)]
    pub outlines: bool,
    /// Colour trees by level of detail (characters keep their colours).
    #[arg(long)]
    pub foliage_tint: bool,
    /// How billboards are lit: atlas (per texel through their atlases, by each leaf's normal)
    /// or flat (one normal a billboard, its leaves' mean; the thesis lit each by its plane); the
    /// crown's occlusion is in their colour
    /// either way [default: flat on a CPU adapter such as lavapipe, else atlas].
    #[arg(long, value_enum)]
    pub billboard_lighting: Option<BillboardLighting>,
    /// Draw plane-lit foliage's depth first (alpha tested, one texture read), then its colour
    /// where the depth is equal, shading each pixel once; one sample a pixel only. Off by
    /// default: on lavapipe the second pass rasterises every layer again and the foliage
    /// pass takes about 1.6× as long.
    #[arg(long)]
    pub foliage_prepass: bool,
    /// Far trees as forest patches: beyond where a tree's impostor comes in, the trees of a
    /// layout cell share one impostor card composed from theirs, where it measures no worse
    /// than their impostors (baked for the layout on first use, then cached).
    #[arg(long)]
    pub forest_patches: bool,
}

/// How billboards are lit (see `FoliageArgs::billboard_lighting`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BillboardLighting {
    Atlas,
    Flat,
}

impl FoliageArgs {
    pub fn view(&self) -> FoliageView {
        FoliageView {
            policy: self.foliage,
            chain: ChainOptions {
                first_epsilon: self.first_epsilon,
                epsilon_growth: self.epsilon_growth,
                description: self.description,
                bins: self.bins as usize,
                shared_bone: !self.plain_sca,
                order: self.foliage_order,
                ..Default::default()
            },
            wind: self.wind,
            outlines: self.outlines,
            tint: self.foliage_tint,
            atlas_lighting: self
                .billboard_lighting
                .map(|l| l == BillboardLighting::Atlas),
            prepass: self.foliage_prepass,
            patches: self.forest_patches,
        }
    }
}

impl LodArgs {
    /// The choices, with `default` as the method where none is given.
    pub fn shot_lod(&self, default: LodMethod) -> ShotLod {
        let (method, compare) = match self.compare {
            Some((a, b)) => (a, Some(b)),
            None => (self.method.unwrap_or(default), None),
        };
        ShotLod {
            method,
            compare,
            policy: self.policy.policy(),
            debug: self.debug_view,
            normal_maps: !self.no_normal_maps,
            foliage: self.foliage.view(),
            ..Default::default()
        }
    }
}

/// `--impostors`: how characters' animated impostors are baked, or none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Impostors(pub Option<crate::bake::impostor::animated::ImpostorOptions>);

pub(crate) fn parse_impostors(s: &str) -> Result<Impostors, String> {
    if s.eq_ignore_ascii_case("off") || s.eq_ignore_ascii_case("none") {
        return Ok(Impostors(None));
    }
    s.parse().map(|o| Impostors(Some(o)))
}
