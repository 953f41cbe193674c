//! The command line's arguments: every subcommand and its options, with clap. `main.rs`
//! parses them and hands each command to its front end.

pub mod command_line;
pub mod scene_args;
pub mod values;

use crate::render::DebugView;
use crate::scene::camera_path::PathKind;
use crate::scene::{Camera, LodMethod};
use clap::{Args, Parser, Subcommand};
pub use scene_args::{BillboardLighting, FoliageArgs, Impostors, LodArgs, PolicyArgs, SceneArgs};
use std::path::PathBuf;
use values::{
    parse_camera, parse_clip_length, parse_export_tolerance, parse_frames, parse_limit,
    parse_number, parse_samples, parse_seconds, parse_size, parse_video_size,
};

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
    /// Raise (or lower) a bound on what one model file may expand to, NAME=VALUE, repeatable:
    /// file-mb, nodes, joints, clip-seconds, clips-seconds, materials, texture-side,
    /// texture-mb, vertices, triangles, decoded-mb (`lodlab doctor` lists their defaults).
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
    /// What the global options say about reading models and cutting their levels, handed to
    /// every command.
    pub fn bake_inputs(&self) -> crate::runtime::spec::BakeInputs {
        crate::runtime::spec::BakeInputs {
            import: crate::import::ImportOptions {
                limits: self.import_limits(),
                extra_clips: self.clips.clone(),
            },
            level_budgets: self.levels.as_ref().and_then(|l| l.budgets()),
        }
    }

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

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Open the viewer on a scene (the default command).
    View(ViewArgs),
    /// Render a scene headless to a PNG and print one JSON line of figures.
    Shot(ShotArgs),
    /// Write the built-in models afresh from their generators as .glb files: the demo models
    /// (horse, walker, broadleaf, conifer, sapling), the test models (split-tube, armour,
    /// patchwork, lowpoly, robot, mocap, knight), the card trees (card-palm, card-bush,
    /// card-oak, card-pine) and the clips of mocap-walk.
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
    /// Say what lodlab finds on this machine (adapter, driver, defaults, cache, models, the
    /// tests' checkers, import limits) and the problems it sees, each with its remedy.
    Doctor(DoctorArgs),
    /// Write the web viewer's folder: the page, the levels of detail its scene needs
    /// (baked first where the cache lacks them) and, with --wasm, the viewer built for the
    /// browser; serve it over HTTP. The view is `lodlab view`'s options after `--`.
    Web(WebArgs),
}

#[derive(Args, Debug)]
pub struct WebArgs {
    /// Folder to write (new or empty, or one `lodlab web` wrote before).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Cache folder of baked levels of detail (default: the platform cache folder's lodlab/):
    /// the levels are read from it, and baked into it where missing.
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Folder holding lodlab.js and lodlab_bg.wasm (wasm-bindgen's output, see
    /// tools/web/build-wasm.sh), copied in beside the page.
    #[arg(long, value_name = "DIR")]
    pub wasm: Option<PathBuf>,
    /// The page's view: `lodlab view`'s options (e.g. -- --scene forest --count 100); the
    /// default scene without.
    #[arg(last = true, value_name = "VIEW OPTIONS")]
    pub view: Vec<String>,
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
        /// The study plan (TOML; docs/study-plan.toml is an example); the same as --plan.
        #[arg(value_name = "PLAN", required_unless_present = "plan_flag")]
        plan: Option<PathBuf>,
        /// The study plan, as `study web` takes it too.
        #[arg(long = "plan", value_name = "PLAN", conflicts_with = "plan")]
        plan_flag: Option<PathBuf>,
        /// Folder of the study to write (new or empty, or one made from the same plan, whose
        /// clips are kept).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Cache folder of baked levels of detail (default: the platform cache folder's lodlab/).
        #[arg(long, value_name = "DIR")]
        cache: Option<PathBuf>,
        /// Multisampling of the clips: 1 (off) or 4.
        #[arg(long, default_value_t = 4, value_parser = parse_samples)]
        msaa: u32,
        /// Render only this job's share of the clips, K of N (clip i goes to shard
        /// i mod N + 1), noted in DIR/shards/K-of-N.json; no sessions are written. A run
        /// without --shard over the same folder then merges the shards.
        #[arg(long, value_name = "K/N", conflicts_with = "merge")]
        shard: Option<crate::app::shard::Shard>,
        /// Merge the shards only: fail, naming them, if any clips are missing instead of
        /// rendering them.
        #[arg(long)]
        merge: bool,
    },
    /// Make a study (as `make` does) and write it as a static site that runs the sessions
    /// in a browser: index.html?participant=P01 plays that participant's trials, keeps each
    /// answer in the browser (a reload resumes) and at the end downloads answers-P01.csv,
    /// which `analyze` reads beside answers.csv.
    Web {
        /// The study plan (TOML; docs/study-plan.toml is an example); the same as --plan.
        #[arg(value_name = "PLAN", required_unless_present = "plan_flag")]
        plan: Option<PathBuf>,
        /// The study plan, as `study make` takes it too.
        #[arg(long = "plan", value_name = "PLAN", conflicts_with = "plan")]
        plan_flag: Option<PathBuf>,
        /// Folder of the study and the site to write (new or empty, or one made from the same
        /// plan).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Cache folder of baked levels of detail (default: the platform cache folder's lodlab/).
        #[arg(long, value_name = "DIR")]
        cache: Option<PathBuf>,
        /// Multisampling of the clips: 1 (off) or 4.
        #[arg(long, default_value_t = 4, value_parser = parse_samples)]
        msaa: u32,
        /// Also POST each participant's answers (text/csv) to this URL at the end.
        #[arg(long, value_name = "URL")]
        post: Option<String>,
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
        /// Cache folder of baked levels of detail (default: the platform cache folder's lodlab/).
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
    /// Length of the clip in seconds of scene time (at most an hour).
    #[arg(long = "length", value_name = "SECONDS", default_value_t = 8.0, value_parser = parse_clip_length)]
    pub seconds: f32,
    /// Camera path over the clip: spiral (inwards, Merry et al. §6.2) or orbit.
    #[arg(long, default_value = "spiral", value_enum)]
    pub path: PathKind,
    /// The MP4 file to write.
    #[arg(long, value_name = "FILE.mp4")]
    pub out: PathBuf,
    /// Also write every frame as a PNG into this folder (new or empty).
    #[arg(long, value_name = "DIR")]
    pub frames_dir: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Level-of-detail methods to measure, comma separated, in this order (`--methods` is the
    /// same option).
    #[arg(
        long = "method",
        visible_alias = "methods",
        value_name = "METHOD,...",
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
    /// Seconds of measuring, all methods together, their calibration included (at least six
    /// frames of each are measured; at most a day).
    #[arg(long, default_value_t = 30.0, value_parser = parse_seconds)]
    pub seconds: f32,
    /// Seconds of unmeasured warm-up frames first (at most a day).
    #[arg(long, default_value_t = 3.0, value_parser = parse_seconds)]
    pub warmup: f32,
    /// Frames to render of each method, instead of measuring for --seconds.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100000))]
    pub frames: Option<u32>,
    /// Leave out what follows the frame times: each pass's fragments against the pixels it
    /// covers and each level kind drawn alone, at a few views a method (the bench says
    /// before it starts how long they will take).
    #[arg(long)]
    pub no_coverage: bool,
    /// Camera path: orbit (one turn, swinging from near to far and back) or spiral (inwards).
    #[arg(long, default_value = "orbit", value_enum)]
    pub path: PathKind,
    /// Seconds the camera path lasts (at most a day).
    #[arg(long, default_value_t = 20.0, value_parser = parse_seconds)]
    pub path_seconds: f32,
    /// The figures as JSON: printed instead of the table, or with =FILE written there too.
    #[arg(long, value_name = "FILE", num_args = 0..=1, require_equals = true)]
    pub json: Option<Option<PathBuf>>,
    /// Also write the Markdown table to a file.
    #[arg(long, value_name = "FILE")]
    pub markdown: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct ReportArgs {
    #[arg(
        value_name = "MODEL",
        help = format!("A built-in asset name ({}) or a glTF path; the same as --model", crate::assets::model_names())
    )]
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
    /// Tie orders each method is baked in: every curve is their median with a band from the
    /// lowest to the highest, and methods are compared only where their bands separate. The
    /// first order is the levels' own; each other costs a simplification.
    #[arg(long, value_name = "N", default_value_t = REPORT_ORDERS,
          value_parser = clap::value_parser!(u32).range(1..=32))]
    pub orders: u32,
    /// Cache folder of baked levels of detail (default: the platform cache folder's
    /// lodlab/): a character's levels are read from it, and baked into it where missing, so a
    /// second report measures without baking again (its bake times are those measured when
    /// the levels were made). A tree's chain is always built afresh: its bake is measured.
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Image size of a tree's colour metric, the pictures each level is compared in
    /// [default: 800x600, the thesis's]: smaller is quicker and coarser. A character's report
    /// renders no such pictures and refuses it.
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
}

/// Tie orders `report` bakes each method in by default (`--orders`).
pub const REPORT_ORDERS: u32 = 5;

/// Simplifiers a report can measure beside the paper's methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Baseline {
    /// meshoptimizer's `simplify` on the rest pose.
    Meshopt,
}

#[derive(Args, Debug)]
pub struct BakeArgs {
    #[arg(
        value_name = "MODEL",
        help = format!("Models: built-in asset names ({}) or glTF paths; the same as --model", crate::assets::model_names())
    )]
    pub models: Vec<String>,
    /// A model, as shot, bench and view take it. Repeat for several.
    #[arg(long = "model", value_name = "NAME|PATH")]
    pub model_flags: Vec<String>,
    /// Level-of-detail methods to bake, comma separated (`--methods` is the same option;
    /// trees get their billboard clouds whatever the methods).
    #[arg(
        long = "method",
        visible_alias = "methods",
        value_name = "METHOD,...",
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
    /// Cache folder of baked levels of detail (default: the platform cache folder's lodlab/).
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// The table as JSON (per character and method its levels: triangles, vertices,
    /// influences, error; per tree its billboard-cloud levels): printed instead of the table,
    /// or with =FILE written there too.
    #[arg(long, value_name = "FILE", num_args = 0..=1, require_equals = true)]
    pub json: Option<Option<PathBuf>>,
    /// Bake only this job's share of the models, K of N (e.g. a Slurm array's
    /// $SLURM_ARRAY_TASK_ID/N): model i goes to shard i mod N + 1. The shards fill one
    /// --cache; a bake of all the models then finds every level there.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<crate::app::shard::Shard>,
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// Model: a built-in asset name (as for bake) or a glTF path; the same as --model.
    #[arg(value_name = "MODEL")]
    pub model: Option<String>,
    /// A model, as shot, bench and view take it.
    #[arg(long = "model", value_name = "NAME|PATH", conflicts_with = "model")]
    pub model_flag: Option<String>,
    /// Level-of-detail method of a character's levels: rest-pose, as, as+is or meshopt (a
    /// tree's levels are its billboard clouds, whatever this says).
    #[arg(long, value_enum, default_value = "as+is")]
    pub method: crate::bake::character::simplify::Method,
    /// Folder to write the files into (made if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Largest projected error allowed, in pixels, as the MSFT_screencoverage hints are
    /// worked out for (a level switches where the next one's error projects to it, on a
    /// 1920×1080 screen).
    #[arg(long, default_value_t = 1.5, value_parser = parse_export_tolerance)]
    pub tolerance: f32,
    /// Cache folder of baked levels of detail (default: the platform cache folder's lodlab/).
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// What was written, as JSON: printed instead of the table, or with =FILE written there
    /// too.
    #[arg(long, value_name = "FILE", num_args = 0..=1, require_equals = true)]
    pub json: Option<Option<PathBuf>>,
}

#[derive(Args, Debug)]
pub struct DoctorArgs {
    /// Cache folder of baked levels of detail to look at (default: the platform cache
    /// folder's lodlab/).
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct GenAssetsArgs {
    /// Folder to write into (`assets` in a checkout regenerates the committed files; point
    /// `LODLAB_ASSETS` at another to have lodlab read its models from there).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Only these assets.
    #[arg(long = "only", value_name = "NAME")]
    pub only: Vec<String>,
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
    /// Frames to render, with --screenshot: the last is the one written.
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
    #[arg(long, value_name = "FILE.png", default_value = "shot.png")]
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
    /// Camera as YAW,PITCH,DISTANCE\[,X,Y,Z\] (degrees, metres; X,Y,Z the point looked at).
    #[arg(long, value_parser = parse_camera, allow_hyphen_values = true)]
    pub camera: Option<Camera>,
    /// Frames to render and time after one warm-up frame (frame_ms is their median); each
    /// shows the scene at --time.
    #[arg(long, default_value_t = 5, value_parser = parse_frames)]
    pub frames: usize,
    /// Also time the same triangles drawn by a trivial unskinned shader.
    #[arg(long)]
    pub calibrate: bool,
    /// What the figures are drawn over: scene (sky, ground and shadows) or plain (black, no
    /// ground, shadows or fog).
    #[arg(long, value_enum, default_value_t = values::Backdrop::Scene)]
    pub backdrop: values::Backdrop,
}

#[derive(Args, Debug)]
pub struct SoakArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Frames to render in all, through the cycle of settings.
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
    pub vary: Vec<values::Setting>,
}
