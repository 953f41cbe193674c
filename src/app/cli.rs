//! The command line's arguments: every subcommand and its options, with clap. `main.rs`
//! parses them and hands each command to its front end.

use crate::bake::foliage::billboard::chain::{ChainOptions, MIN_EPSILON_GROWTH};
use crate::bake::foliage::spectral::description::DescriptionType;
use crate::render::DebugView;
use crate::runtime::headless::ShotLod;
use crate::runtime::spec::SceneSpec;
use crate::scene::SceneKind;
use crate::scene::camera_path::PathKind;
use crate::scene::foliage::{FoliagePolicy, FoliageView};
use crate::scene::{Camera, Drive, LodMethod, LodPolicy, Transition};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "lodlab",
    version,
    about = "Compare level-of-detail methods on animated crowds",
    long_about = "Compare level-of-detail methods on animated crowds.\n\n\
                  Without a subcommand, lodlab opens the viewer: `lodlab [OPTIONS]` is \
                  `lodlab view [OPTIONS]`.",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// The viewer's options, for `lodlab` without a subcommand.
    #[command(flatten)]
    pub view: ViewArgs,
    /// Raise (or lower) a bound on what one model file may ask for or expand to, NAME=VALUE,
    /// repeatable: file-mb (1024: the file and each file it refers to, MiB), nodes (100000),
    /// joints (1024: bones, all skins' joints and the nodes unskinned parts ride on),
    /// clip-seconds (600 a clip), clips-seconds (3600, all clips), materials (256 textured
    /// ones; plain colours share one palette), texture-side
    /// (8192 texels), texture-mb (1024: decoded texels of the textured materials), vertices
    /// and triangles (4000000 each, every primitive as often as nodes draw it), decoded-mb
    /// (1024: accessors and decoded compressed views).
    /// Each keeps a small hostile file from taking the machine; a model past one is refused
    /// in one line naming the option.
    #[arg(long = "limit", value_name = "NAME=VALUE", global = true, value_parser = parse_limit)]
    pub limits: Vec<String>,
    /// Let a model's buffers and images be files outside its folder (absolute paths, '..',
    /// file: URIs, symbolic links leading out). By default only files beside the model are
    /// read, so that a file from a stranger cannot read others.
    #[arg(long, global = true)]
    pub allow_outside_files: bool,
    /// Add the clips of another glTF file to every model, bound by joint name, repeatable: a
    /// character and its animations sent as separate files on one skeleton, as Mixamo and
    /// many asset stores send them (a built-in name, such as mocap-walk, or a path). A joint
    /// the file animates that the model lacks is an error naming it.
    #[arg(long = "clips", value_name = "FILE", global = true)]
    pub clips: Vec<PathBuf>,
    /// How characters' levels are cut: `error` (the default: each level's error doubling
    /// from the first) or `triangles:N,N,...`, the levels `lodlab bake MODEL --triangles
    /// N,N,...` made (read from its cache when it is there).
    #[arg(long = "levels", value_name = "error|triangles:N,N,...", global = true, value_parser = parse_levels)]
    pub levels: Option<LevelCut>,
}

/// How characters' levels are cut (`--levels`).
#[derive(Clone, Debug, PartialEq)]
pub enum LevelCut {
    Error,
    Triangles(Vec<u32>),
}

impl LevelCut {
    /// The budgets it cuts by, where it cuts by triangles.
    pub fn budgets(&self) -> Option<Vec<u32>> {
        match self {
            LevelCut::Error => None,
            LevelCut::Triangles(b) => Some(b.clone()),
        }
    }
}

fn parse_levels(s: &str) -> Result<LevelCut, String> {
    if s == "error" {
        return Ok(LevelCut::Error);
    }
    let list = s
        .strip_prefix("triangles:")
        .ok_or_else(|| format!("'{s}' is neither 'error' nor 'triangles:N,N,...'"))?;
    let budgets: Vec<u32> = list
        .split(',')
        .map(|n| {
            n.trim()
                .parse::<u32>()
                .ok()
                .filter(|&v| v > 0)
                .ok_or_else(|| format!("'{n}' is not a positive whole number of triangles"))
        })
        .collect::<Result<_, _>>()?;
    if budgets.is_empty() {
        return Err("triangles: needs at least one budget".into());
    }
    Ok(LevelCut::Triangles(budgets))
}

impl Cli {
    /// The import limits the command line asks for.
    pub fn import_limits(&self) -> crate::import::validate::Limits {
        let mut limits = crate::import::validate::Limits::default();
        for l in &self.limits {
            limits.set(l).expect("checked by parse_limit");
        }
        limits.outside_files = self.allow_outside_files;
        limits
    }
}

fn parse_limit(s: &str) -> Result<String, String> {
    crate::import::validate::Limits::default().set(s)?;
    Ok(s.to_string())
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Open the viewer on a scene (the default command).
    View(ViewArgs),
    /// Render a scene headless to a PNG and print one JSON line of figures.
    Shot(ShotArgs),
    /// Regenerate the demo models (horse, walker, broadleaf, conifer, sapling), the test
    /// models (split-tube, armour, patchwork, lowpoly, robot, mocap, knight) and the clips of
    /// mocap-walk as .glb files.
    GenAssets(GenAssetsArgs),
    /// Build the levels of detail of models (progressive meshes by rest-pose, AS, AS+IS; a
    /// tree's chain of billboard clouds), or fetch them from the cache, and print them as a
    /// table.
    Bake(BakeArgs),
    /// Write a character's levels of detail by one method as glTF: a .glb per level (skin,
    /// clips, materials) and one .glb holding them all under MSFT_lod, for other engines.
    Export(ExportArgs),
    /// Measure a model's levels of detail: for a character, error curves (report.json,
    /// error.png, as in Merry et al. Figure 7) and bake timings (timings.md, their Table 1);
    /// for a tree, its billboard-cloud chain (report.json, colour-error.png, levels.png).
    Report(ReportArgs),
    /// Measure frame times of level-of-detail methods on a scene, headless, along a fixed
    /// camera path, interleaved in one process, against a trivial unskinned shader drawing the
    /// same triangles; print a Markdown table.
    Bench(BenchArgs),
    /// Record a clip for a perceptual study: offline at a fixed time step along a camera path
    /// (by default an inward spiral round 100 copies of one model), as H.264 MP4.
    Record(RecordArgs),
    /// Run many frames headless through every method, transition, foliage policy, character
    /// count and frame size (0×0: a minimised window) in a fixed cycle, print memory every
    /// --every frames (resident set, and what wgpu's allocator holds), and fail on a GPU error
    /// or on resident growth past --max-growth-mb after the first cycle.
    Soak(SoakArgs),
    /// A perceptual study (Merry et al. §6.2): make its clips and sessions from a plan, run a
    /// participant's session in a window, analyze the answers.
    Study(StudyArgs),
}

#[derive(Args, Debug)]
pub struct StudyArgs {
    #[command(subcommand)]
    pub command: StudyCommand,
}

#[derive(Subcommand, Debug)]
pub enum StudyCommand {
    /// Render every distinct clip of a plan once and write one session list per participant.
    Make {
        /// The study plan (TOML; docs/study-plan.toml is an example).
        #[arg(long)]
        plan: PathBuf,
        /// Folder of the study (new or empty, or one made from the same plan, whose clips are
        /// kept).
        #[arg(long)]
        out: PathBuf,
        /// Cache folder of baked levels of detail.
        #[arg(long, value_name = "DIR")]
        cache: Option<PathBuf>,
        /// Multisampling of the clips: 1 (off) or 4.
        #[arg(long, default_value_t = 4, value_parser = parse_samples)]
        msaa: u32,
    },
    /// Run a participant's session: each pair's clips one after the other, then a forced
    /// choice (keys 1 and 2); every answer is saved at once, and a session resumes where it
    /// stopped.
    Run {
        /// Folder of the study.
        dir: PathBuf,
        /// The participant (P01, P02, …: see the study's sessions/ folder).
        #[arg(long)]
        participant: String,
        /// Full screen.
        #[arg(long)]
        fullscreen: bool,
        /// Window size.
        #[arg(long, default_value = "1280x720", value_parser = parse_size)]
        size: (u32, u32),
        /// Answer without a window, e.g. 1,2,2,1: each trial's clips are still played
        /// (decoded at their own rate) before its answer is recorded; stops when the answers
        /// run out. For demonstrations and tests.
        #[arg(long, value_name = "1,2,...")]
        script: Option<String>,
    },
    /// Score every clip of a study against a full-detail clip of its model, frame by frame
    /// (SSIM on luma), as a stand-in for participants: a pilot with no one. Records the
    /// full-detail clips (clips/MODEL-reference.mp4) where missing; writes proxy.md, proxy.csv,
    /// proxy-frames.csv, proxy.json and proxy.png; `analyze` then reports how well the scores
    /// predict the answers.
    Proxy {
        /// Folder of the study.
        dir: PathBuf,
        /// Cache folder of baked levels of detail.
        #[arg(long, value_name = "DIR")]
        cache: Option<PathBuf>,
        /// Multisampling of the full-detail clips: as the study's were made (`make`'s
        /// default is 4).
        #[arg(long, default_value_t = 4, value_parser = parse_samples)]
        msaa: u32,
    },
    /// Per condition: preference counts and share, two-sided binomial (sign) test, training
    /// answers left out; writes analysis.md, analysis.json and preferences.png into the folder.
    Analyze {
        /// Folder of the study.
        dir: PathBuf,
    },
}

#[derive(Args, Debug)]
pub struct RecordArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Level-of-detail method: none, rest-pose, as, as+is.
    #[arg(long, default_value = "as+is", value_enum)]
    pub method: LodMethod,
    #[command(flatten)]
    pub policy: PolicyArgs,
    /// Debug view: shaded, lod, transition, wireframe, influences (lod tints by level).
    #[arg(long, default_value = "shaded", value_enum)]
    pub debug_view: DebugView,
    #[command(flatten)]
    pub foliage: FoliageArgs,
    /// Video size: even sides, at least 16×16, at most 3840×2160 (or 2160×3840), what H.264's
    /// encoder takes.
    #[arg(long, default_value = "1280x720", value_parser = parse_video_size)]
    pub size: (u32, u32),
    /// Multisampling: 1 (off) or 4.
    #[arg(long, default_value_t = 4, value_parser = parse_samples)]
    pub msaa: u32,
    /// Frames a second.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=240))]
    pub fps: u32,
    /// Length of the clip in seconds (at most an hour).
    #[arg(long, default_value_t = 8.0, value_parser = parse_clip_length)]
    pub seconds: f32,
    /// Camera path over the clip: spiral (inwards, Merry et al. §6.2) or orbit.
    #[arg(long, default_value = "spiral", value_enum)]
    pub path: PathKind,
    /// The MP4 file to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Also write every frame as a PNG into this folder (new or empty).
    #[arg(long, value_name = "DIR")]
    pub frames_dir: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Methods to measure, comma separated, in this order.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "none,rest-pose,as,as+is"
    )]
    pub methods: Vec<LodMethod>,
    #[command(flatten)]
    pub policy: PolicyArgs,
    #[command(flatten)]
    pub foliage: FoliageArgs,
    /// Light the coarse levels with their vertex normals only, not through their normal maps.
    #[arg(long)]
    pub no_normal_maps: bool,
    /// Image size.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Multisampling: 1 (off) or 4 [default: 1 on a CPU adapter such as lavapipe, else 4].
    #[arg(long, value_parser = parse_samples)]
    pub msaa: Option<u32>,
    /// Seconds of measuring, all methods together (their calibration included; at most a day).
    #[arg(long, default_value_t = 30.0, value_parser = parse_seconds)]
    pub seconds: f32,
    /// Seconds of unmeasured warm-up frames first (at most a day).
    #[arg(long, default_value_t = 3.0, value_parser = parse_seconds)]
    pub warmup: f32,
    /// Frames per method, instead of as many as fit --seconds.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100000))]
    pub frames: Option<u32>,
    /// Camera path: orbit (one turn, swinging from near to far and back) or spiral (inwards).
    #[arg(long, default_value = "orbit", value_enum)]
    pub path: PathKind,
    /// Seconds the camera path lasts (at most a day).
    #[arg(long, default_value_t = 20.0, value_parser = parse_seconds)]
    pub path_seconds: f32,
    /// Also write the figures as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Also write the Markdown table to a file.
    #[arg(long, value_name = "FILE")]
    pub markdown: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// A built-in asset name (horse, walker, broadleaf, conifer, sapling, split-tube, armour,
    /// patchwork, lowpoly, robot, mocap, knight) or a glTF path; the same as --model.
    #[arg(value_name = "MODEL")]
    pub model: Option<String>,
    /// The model, as shot, bench and view take it.
    #[arg(long = "model", value_name = "NAME|PATH", conflicts_with = "model")]
    pub model_flag: Option<String>,
    /// Folder to write the report into (created if needed): report.json, error.png and
    /// timings.md; for a tree report.json, colour-error.png and levels.png.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Also measure this simplifier on the rest pose at the same triangle counts.
    #[arg(long, value_enum)]
    pub baseline: Option<Baseline>,
}

/// Simplifiers a report can measure beside the paper's methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Baseline {
    /// meshoptimizer's `simplify` on the rest pose.
    Meshopt,
}

#[derive(Args, Debug)]
pub struct BakeArgs {
    /// Models: built-in asset names (horse, walker, broadleaf, conifer, sapling, split-tube,
    /// armour, patchwork, lowpoly, robot, mocap, knight) or glTF paths; the same as --model.
    #[arg(value_name = "MODEL", required_unless_present = "model_flags")]
    pub models: Vec<String>,
    /// A model, as shot, bench and view take it. Repeat for several.
    #[arg(long = "model", value_name = "NAME|PATH")]
    pub model_flags: Vec<String>,
    /// Simplification methods, comma separated (trees get their billboard clouds whatever
    /// the methods).
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "rest-pose,as,as+is"
    )]
    pub methods: Vec<crate::bake::character::simplify::Method>,
    /// e₁, the error bound of LOD 1 in pixels for the model filling 1000 pixels of screen
    /// height; each further level doubles it. (Not the run-time --tolerance of view, shot and
    /// bench: the projected error a level may show.)
    #[arg(long, default_value_t = 0.5, value_name = "PX", value_parser = parse_number)]
    pub first_error: f32,
    /// Cut levels by triangle budgets instead of errors, e.g. 4000,2000,1000.
    #[arg(long, value_delimiter = ',', value_name = "N,N,...")]
    pub triangles: Option<Vec<u32>>,
    /// Cache folder (default: the platform cache folder's lodlab/).
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Print the table as JSON: per character and method its levels (triangles, vertices,
    /// influences, error), per tree its billboard-cloud levels.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// Model: a built-in asset name or a glTF path; the same as --model.
    #[arg(value_name = "MODEL", required_unless_present = "model_flag")]
    pub model: Option<String>,
    /// A model, as shot, bench and view take it.
    #[arg(long = "model", value_name = "NAME|PATH", conflicts_with = "model")]
    pub model_flag: Option<String>,
    /// Simplification method of the levels.
    #[arg(long, value_enum, default_value = "as+is")]
    pub method: crate::bake::character::simplify::Method,
    /// Folder to write the files into (made if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// The pixel tolerance the MSFT_screencoverage hints are worked out for (a level switches
    /// where the next one's error projects to it, on a 1920×1080 screen).
    #[arg(long, default_value_t = 1.5, value_parser = parse_export_tolerance)]
    pub tolerance: f32,
    /// Cache folder of baked levels of detail (default: the platform cache folder's lodlab/).
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Print what was written as JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

fn parse_export_tolerance(s: &str) -> Result<f32, String> {
    parse_in(s, "tolerance", 0.25..=16.0)
}

#[derive(Args, Debug)]
pub struct GenAssetsArgs {
    /// Folder to write into (default: the project's assets/ folder).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Only these assets.
    #[arg(long = "only", value_name = "NAME")]
    pub only: Vec<String>,
}

/// Which scene and which characters.
#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// Scene to show: mixed (the crowd walking in a clearing of the forest), crowd
    /// (characters), forest (trees) or study (copies of one model) [default: mixed; study for
    /// record].
    #[arg(long, value_enum)]
    pub scene: Option<SceneKind>,
    /// Model: a built-in asset (horse, walker, broadleaf, conifer, sapling) or a glTF path.
    /// Repeat for several.
    #[arg(long = "model", value_name = "NAME|PATH")]
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
    pub fn spec(&self) -> SceneSpec {
        self.spec_or(SceneKind::Mixed)
    }

    /// The scene asked for, `default` where none is.
    pub fn spec_or(&self, default: SceneKind) -> SceneSpec {
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
    #[arg(long, default_value = "morph", value_enum)]
    pub transition: Transition,
    /// What drives alpha, morph and dither: time (over --duration) or zone (morph zones over
    /// distance).
    #[arg(long, value_enum, default_value = "time")]
    pub drive: Drive,
    /// Seconds a time-driven transition takes.
    #[arg(long, default_value_t = 0.5, value_parser = parse_seconds)]
    pub duration: f32,
    /// Width of a morph zone, as a fraction of its threshold distance.
    #[arg(long, default_value_t = 0.25, value_parser = parse_non_negative)]
    pub zone_width: f32,
    /// Largest projected error allowed, in pixels (0.25 to 16).
    #[arg(long, default_value_t = 1.5, value_parser = parse_tolerance)]
    pub tolerance: f32,
    /// Hysteresis: the fraction of the tolerance a coarser level must undercut (0 to 0.9).
    #[arg(long, default_value_t = 0.2, value_parser = parse_hysteresis)]
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
    /// or flat (by their planes, as the thesis did); the crown's occlusion is in their colour
    /// either way [default: flat on a CPU adapter such as lavapipe, else atlas].
    #[arg(long, value_enum)]
    pub billboard_lighting: Option<BillboardLighting>,
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
                ..Default::default()
            },
            wind: self.wind,
            outlines: self.outlines,
            tint: self.foliage_tint,
            atlas_lighting: self
                .billboard_lighting
                .map(|l| l == BillboardLighting::Atlas),
        }
    }
}

fn parse_in(s: &str, what: &str, range: std::ops::RangeInclusive<f32>) -> Result<f32, String> {
    parse_number(s).and_then(|x| {
        if range.contains(&x) {
            Ok(x)
        } else {
            Err(format!(
                "{what} '{s}' must be between {} and {}",
                range.start(),
                range.end()
            ))
        }
    })
}

fn parse_first_epsilon(s: &str) -> Result<f32, String> {
    parse_in(s, "first epsilon", 0.0005..=0.2)
}

fn parse_epsilon_growth(s: &str) -> Result<f32, String> {
    parse_in(s, "epsilon growth", MIN_EPSILON_GROWTH..=8.0)
}

fn parse_wind(s: &str) -> Result<f32, String> {
    parse_in(s, "wind strength", 0.0..=5.0)
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

fn parse_compare(s: &str) -> Result<(LodMethod, LodMethod), String> {
    let (a, b) = s
        .split_once(',')
        .ok_or_else(|| format!("'{s}' is not A,B (two methods)"))?;
    Ok((
        crate::choice::parse(a, "a method")?,
        crate::choice::parse(b, "a method")?,
    ))
}

fn parse_number(s: &str) -> Result<f32, String> {
    s.trim()
        .parse::<f32>()
        .ok()
        .filter(|x| x.is_finite())
        .ok_or_else(|| format!("'{s}' is not a number"))
}

/// A frame count: at least one, at most 100,000 (an hour at 30 frames a second).
fn parse_frames(s: &str) -> Result<usize, String> {
    s.trim()
        .parse::<usize>()
        .ok()
        .filter(|n| (1..=100_000).contains(n))
        .ok_or_else(|| format!("'{s}' is not a frame count from 1 to 100000"))
}

fn parse_non_negative(s: &str) -> Result<f32, String> {
    parse_number(s).and_then(|x| {
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(format!("'{s}' must not be negative"))
        }
    })
}

/// A span of time a command runs or waits for: finite, not negative, at most a day (a larger
/// one is a slip of the keyboard that would keep the command running for ever).
fn parse_seconds(s: &str) -> Result<f32, String> {
    parse_in(s, "seconds", 0.0..=86_400.0)
}

/// A recorded clip's length: at most an hour (108,000 frames at 30 a second).
fn parse_clip_length(s: &str) -> Result<f32, String> {
    parse_in(s, "clip length in seconds", 0.0..=3600.0)
}

fn parse_tolerance(s: &str) -> Result<f32, String> {
    parse_number(s).and_then(|x| {
        if (0.25..=16.0).contains(&x) {
            Ok(x)
        } else {
            Err(format!(
                "tolerance '{s}' must be between 0.25 and 16 pixels"
            ))
        }
    })
}

fn parse_hysteresis(s: &str) -> Result<f32, String> {
    parse_number(s).and_then(|x| {
        if (0.0..=0.9).contains(&x) {
            Ok(x)
        } else {
            Err(format!("hysteresis '{s}' must be between 0 and 0.9"))
        }
    })
}

#[derive(Args, Debug)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub lod: LodArgs,
    /// Window size.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Multisampling: 1 (off) or 4 [default: 1 on a CPU adapter such as lavapipe, else 4].
    #[arg(long, value_parser = parse_samples)]
    pub msaa: Option<u32>,
    /// Render --frames frames of the window, write the last one to this PNG and exit.
    #[arg(long, value_name = "FILE.png")]
    pub screenshot: Option<PathBuf>,
    /// Frames to render before the screenshot.
    #[arg(long, default_value_t = 30, requires = "screenshot", value_parser = parse_frames)]
    pub frames: usize,
}

#[derive(Args, Debug)]
pub struct ShotArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub lod: LodArgs,
    /// PNG file to write (relative paths from the working folder).
    #[arg(long, default_value = "shot.png")]
    pub out: PathBuf,
    /// Image size.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Scene time in seconds.
    #[arg(long, default_value_t = 1.0, value_parser = parse_number)]
    pub time: f32,
    /// Multisampling: 1 (off) or 4 [default: 1 on a CPU adapter such as lavapipe, else 4].
    #[arg(long, value_parser = parse_samples)]
    pub msaa: Option<u32>,
    /// Camera as YAW,PITCH,DISTANCE[,X,Y,Z] (degrees, metres; X,Y,Z the point looked at).
    #[arg(long, value_parser = parse_camera, allow_hyphen_values = true)]
    pub camera: Option<Camera>,
    /// Frames to time after one warm-up frame; frame_ms is their median.
    #[arg(long, default_value_t = 5, value_parser = parse_frames)]
    pub frames: usize,
    /// Also time the same triangles drawn by a trivial unskinned shader.
    #[arg(long)]
    pub calibrate: bool,
}

#[derive(Args, Debug)]
pub struct SoakArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Frames to run.
    #[arg(long, default_value_t = 10_000, value_parser = parse_frames)]
    pub frames: usize,
    /// Frames each phase of the cycle of settings lasts (the cycle has 20 phases).
    #[arg(long, default_value_t = 25, value_parser = parse_frames)]
    pub phase_frames: usize,
    /// Read memory every this many frames (a multiple of the cycle's frames puts every
    /// reading at the same point of the cycle, so the GPU's figures must repeat).
    #[arg(long, default_value_t = 500, value_parser = parse_frames)]
    pub every: usize,
    /// Largest frame size of the cycle (it also takes half, three quarters, 1×1 and 0×0).
    #[arg(long, default_value = "320x180", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Multisampling: 1 (off) or 4 [default: 1 on a CPU adapter such as lavapipe, else 4].
    #[arg(long, value_parser = parse_samples)]
    pub msaa: Option<u32>,
    /// Resident growth allowed after the first cycle, in MB.
    #[arg(long, default_value_t = 5.0, value_parser = parse_number)]
    pub max_growth_mb: f32,
    /// Also write the readings to this CSV file.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// The settings the cycle changes, comma separated (to find which one leaks).
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "method,transition,foliage,count,size"
    )]
    pub vary: Vec<crate::app::soak::Setting>,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in '{s}'"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in '{s}'"))?;
    if !(1..=8192).contains(&w) || !(1..=8192).contains(&h) {
        return Err(format!("size '{s}' must be between 1x1 and 8192x8192"));
    }
    Ok((w, h))
}

/// A [`parse_size`] that H.264 (OpenH264) can encode, refused before anything is rendered.
fn parse_video_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = parse_size(s)?;
    if !w.is_multiple_of(2) || !h.is_multiple_of(2) || w < 16 || h < 16 {
        return Err(format!(
            "video size '{s}': H.264 needs even sides of at least 16 pixels"
        ));
    }
    let (long, short) = (w.max(h), w.min(h));
    if long > 3840 || short > 2160 {
        return Err(format!(
            "video size '{s}': the H.264 encoder takes at most 3840x2160 (or 2160x3840)"
        ));
    }
    Ok((w, h))
}

fn parse_samples(s: &str) -> Result<u32, String> {
    match s {
        "1" => Ok(1),
        "4" => Ok(4),
        _ => Err(format!("'{s}': multisampling must be 1 or 4")),
    }
}

fn parse_camera(s: &str) -> Result<Camera, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{s}' is not YAW,PITCH,DISTANCE[,X,Y,Z]"))?;
    if !(v.len() == 3 || v.len() == 6) || v.iter().any(|x| !x.is_finite()) || v[2] <= 0.0 {
        return Err(format!("'{s}' is not YAW,PITCH,DISTANCE[,X,Y,Z]"));
    }
    let target = if v.len() == 6 {
        glam::Vec3::new(v[3], v[4], v[5])
    } else {
        glam::Vec3::new(0.0, 1.0, 0.0)
    };
    Ok(Camera::new(target, v[0], v[1], v[2]))
}

/// `--impostors`: how characters' animated impostors are baked, or none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Impostors(pub Option<crate::bake::impostor::animated::ImpostorOptions>);

fn parse_impostors(s: &str) -> Result<Impostors, String> {
    if s.eq_ignore_ascii_case("off") || s.eq_ignore_ascii_case("none") {
        return Ok(Impostors(None));
    }
    s.parse().map(|o| Impostors(Some(o)))
}
