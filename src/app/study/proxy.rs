//! `lodlab study proxy`: an image-metric stand-in for a study's participants. Every clip of the
//! study is scored, frame by frame, against a full-detail clip of the same model recorded with
//! the same camera, crowd, size and frame rate (the plan's, method `none`) by two metrics:
//!
//! - SSIM (Wang et al. 2004, [`crate::measure::ssim`]) on luma: 1 for identical frames, higher is
//!   better;
//! - ꟻLIP (Andersson et al. 2020, NVIDIA's own code through the `nv-flip` crate) on sRGB
//!   colour, at its default 67 pixels per degree: the mean per-pixel error in 0..1, lower is
//!   better.
//!
//! Frames are scored as rendered, before any encoding: the clip is rendered again (it renders
//! the same frames `study make` encoded, see `record`) beside its reference's lossless frames.
//! Scoring the decoded MP4s measured the codec as much as the methods: H.264's keyframe
//! interval drew a one-second sawtooth of about 0.01 SSIM into every clip, while the methods
//! differed by 0.0004. What the codec itself takes away is still measured, on each reference
//! (its MP4 against its own frames), and reported beside the scores.
//!
//! A method whose clip stays closer to full detail should be the one participants prefer;
//! `analyze` then reports how well each metric predicted the answers, and before any
//! participant comes, the scores are a pilot of the study.
//!
//! Writes into the study folder: `proxy.csv` (per clip: mean and lowest SSIM),
//! `proxy-frames.csv` (per clip and frame), `proxy.md` (per condition: both clips' scores and
//! which one the metric prefers), `proxy.json` (all of it, for `analyze`) and `proxy.png`
//! (SSIM over time, a line per clip). The full-detail clips are kept in `clips/` as
//! `MODEL-reference.mp4`, their lossless frames in `clips/MODEL-reference-frames/`.

use super::make::clip_options;
use super::plan::{CLIPS, Manifest, read_manifest};
use crate::app::commands::record;
use crate::app::plotting::{plot_error, register_font, write_plot};
use crate::app::video::ClipReader;
use crate::atomic::write as write_atomic;
use crate::measure::ssim::{Luma, ssim};
use crate::scene::LodMethod;
use anyhow::{Result, anyhow, bail};
use plotters::prelude::*;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub const PROXY_JSON: &str = "proxy.json";

/// The proxy's metrics, in words (for tables).
pub const SSIM: &str = "SSIM on luma (Wang et al. 2004: 11×11 Gaussian window, σ 1.5)";
pub const FLIP: &str = "ꟻLIP mean error (Andersson et al. 2020, 67 pixels per degree)";

/// Frames scored at once (in parallel), two pictures each in memory.
const BATCH: usize = 8;

/// One clip's scores.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ClipScore {
    pub model: String,
    pub method: LodMethod,
    pub tolerance_px: f32,
    /// The clip and its full-detail reference, relative to the study folder.
    pub file: String,
    pub reference: String,
    /// SSIM of every frame against the reference's.
    pub ssim: Vec<f64>,
    pub mean: f64,
    pub lowest: f64,
    /// ꟻLIP's mean error of every frame against the reference's, and its mean and highest.
    pub flip: Vec<f64>,
    pub flip_mean: f64,
    pub flip_highest: f64,
}

/// One condition as the proxy sees it: both clips' means by both metrics.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ProxyCondition {
    pub condition: super::plan::Condition,
    pub ssim_a: f64,
    pub ssim_b: f64,
    pub flip_a: f64,
    pub flip_b: f64,
}

impl ProxyCondition {
    /// How much more each metric favours B (above 0: the metric prefers B): SSIM B − A, and
    /// ꟻLIP A − B (its error is lower for the better clip).
    pub fn favour_b(&self) -> [f64; 2] {
        [self.ssim_b - self.ssim_a, self.flip_a - self.flip_b]
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Proxy {
    /// The metrics, in the order of [`ProxyCondition::favour_b`].
    pub metrics: [String; 2],
    pub fps: u32,
    pub clips: Vec<ClipScore>,
    pub conditions: Vec<ProxyCondition>,
    /// What H.264 alone takes away: each reference's MP4 against its own lossless frames.
    #[serde(default)]
    pub codec: Vec<CodecScore>,
}

/// SSIM of a reference clip's encoded frames against the frames it was encoded from.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CodecScore {
    pub model: String,
    pub mean: f64,
    pub lowest: f64,
    pub highest: f64,
}

/// Options of `study proxy`.
#[derive(Clone, Debug)]
pub struct ProxyOptions {
    pub dir: PathBuf,
    /// How the references are rendered (the study's clips' own multisampling, to compare
    /// like with like).
    pub rendering: super::make::ClipRendering,
}

/// `clips/horse-reference.mp4`: the full-detail clip of a model.
pub fn reference_file(model: &str) -> String {
    format!("{CLIPS}/{}-reference.mp4", super::plan::model_stem(model))
}

/// `clips/horse-reference-frames`: the full-detail clip's frames, lossless.
pub fn reference_frames(model: &str) -> String {
    format!(
        "{CLIPS}/{}-reference-frames",
        super::plan::model_stem(model)
    )
}

/// Records the missing full-detail clips, scores every clip of the study in `o.dir`, and
/// writes the proxy's files.
pub fn run(o: &ProxyOptions) -> Result<Proxy> {
    let manifest = read_manifest(&o.dir)?;
    let proxy = score(o, &manifest)?;
    write_outputs(&o.dir, &proxy)?;
    Ok(proxy)
}

fn score(o: &ProxyOptions, manifest: &Manifest) -> Result<Proxy> {
    let plan = &manifest.plan;
    let frames = record::frame_count(plan.seconds, plan.fps);
    let mut models: Vec<&String> = plan.models.iter().collect();
    models.sort();
    models.dedup();
    let mut codec = Vec::new();
    for model in models {
        record_reference(o, manifest, model, frames)?;
        let ssim = codec_ssim(
            &o.dir.join(reference_file(model)),
            &o.dir.join(reference_frames(model)),
        )?;
        codec.push(CodecScore {
            model: model.clone(),
            mean: ssim.iter().sum::<f64>() / ssim.len() as f64,
            lowest: ssim.iter().copied().fold(f64::INFINITY, f64::min),
            highest: ssim.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        });
    }
    let mut clips = Vec::with_capacity(manifest.clips.len());
    for (k, clip) in manifest.clips.iter().enumerate() {
        eprintln!(
            "lodlab: scoring {}/{}: {} (rendered again, before encoding)",
            k + 1,
            manifest.clips.len(),
            clip.file
        );
        let options = clip_options(
            plan,
            &clip.model,
            clip.method,
            clip.tolerance_px,
            o.dir.join(&clip.file),
            &o.rendering,
        )?;
        let (ssim, flip) = score_rendered(&options, &o.dir.join(reference_frames(&clip.model)))?;
        let mean_of = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        clips.push(ClipScore {
            model: clip.model.clone(),
            method: clip.method,
            tolerance_px: clip.tolerance_px,
            file: clip.file.clone(),
            reference: reference_file(&clip.model),
            mean: mean_of(&ssim),
            lowest: ssim.iter().copied().fold(f64::INFINITY, f64::min),
            flip_mean: mean_of(&flip),
            flip_highest: flip.iter().copied().fold(0.0, f64::max),
            ssim,
            flip,
        });
    }
    let clip_of = |model: &str, method: LodMethod, tolerance: f32| -> Result<&ClipScore> {
        clips
            .iter()
            .find(|c| c.model == model && c.method == method && c.tolerance_px == tolerance)
            .ok_or_else(|| anyhow!("the study names no clip of {model}, {method}, {tolerance} px"))
    };
    let conditions = manifest
        .conditions
        .iter()
        .map(|c| {
            let a = clip_of(&c.model, c.method_a, c.tolerance_px)?;
            let b = clip_of(&c.model, c.method_b, c.tolerance_px)?;
            Ok(ProxyCondition {
                condition: c.clone(),
                ssim_a: a.mean,
                ssim_b: b.mean,
                flip_a: a.flip_mean,
                flip_b: b.flip_mean,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Proxy {
        metrics: [SSIM.into(), FLIP.into()],
        fps: plan.fps,
        clips,
        conditions,
        codec,
    })
}

/// Records `model`'s full-detail reference (its MP4 and its lossless frames) unless both are
/// there, complete, from an earlier run. An incomplete frames folder of an interrupted run
/// (frame files only: this command's own) is cleared first.
fn record_reference(o: &ProxyOptions, manifest: &Manifest, model: &str, frames: u32) -> Result<()> {
    let plan = &manifest.plan;
    let (file, dir) = (reference_file(model), reference_frames(model));
    let (path, frames_dir) = (o.dir.join(&file), o.dir.join(&dir));
    let ours = |e: &std::fs::DirEntry| {
        let name = e.file_name().to_string_lossy().into_owned();
        name.starts_with("frame_") && name.ends_with(".png")
    };
    let listed: Vec<std::fs::DirEntry> = std::fs::read_dir(&frames_dir)
        .map(|d| d.flatten().collect())
        .unwrap_or_default();
    if path.exists() && listed.len() == frames as usize && listed.iter().all(ours) {
        eprintln!("lodlab: reference {file} (there already, with its frames)");
        return Ok(());
    }
    if !listed.iter().all(ours) {
        bail!(
            "{}: holds files other than a reference's frames; move them away",
            frames_dir.display()
        );
    }
    for e in &listed {
        std::fs::remove_file(e.path())
            .map_err(|err| anyhow!("{}: cannot remove: {err}", e.path().display()))?;
    }
    eprintln!("lodlab: reference {file} and its frames");
    let tolerance = plan.tolerances.first().copied().unwrap_or(1.5);
    let mut options = clip_options(plan, model, LodMethod::None, tolerance, path, &o.rendering)?;
    options.frames_dir = Some(frames_dir);
    record::run(&options)?;
    Ok(())
}

/// Frame `k` of the lossless frames in `dir`, which must be the size of `like` (the frame it is
/// scored against).
fn lossless_frame(dir: &Path, k: u32, like: &image::RgbaImage) -> Result<image::RgbaImage> {
    let file = dir.join(record::frame_file(k));
    let frame = image::open(&file)
        .map_err(|e| anyhow!("{}: cannot read: {e}", file.display()))?
        .to_rgba8();
    if frame.dimensions() != like.dimensions() {
        bail!(
            "{}: {}x{}, but the frame it is scored against is {}x{}",
            file.display(),
            frame.width(),
            frame.height(),
            like.width(),
            like.height()
        );
    }
    Ok(frame)
}

/// SSIM of every frame of the MP4 `clip` against the lossless frames it was encoded from, in
/// `frames`: what the codec alone takes away.
fn codec_ssim(clip: &Path, frames: &Path) -> Result<Vec<f64>> {
    use rayon::prelude::*;
    let mut video = ClipReader::open(clip)?;
    let mut out = Vec::new();
    let mut k = 0;
    loop {
        let mut batch = Vec::with_capacity(BATCH);
        while batch.len() < BATCH {
            let Some(decoded) = video.next_frame()? else {
                break;
            };
            let lossless = lossless_frame(frames, k, &decoded)?;
            k += 1;
            batch.push((decoded, lossless));
        }
        if batch.is_empty() {
            break;
        }
        out.extend(
            batch
                .par_iter()
                .map(|(a, b)| frame_ssim(a, b))
                .collect::<Vec<_>>(),
        );
    }
    if out.is_empty() {
        bail!("{}: no frames", clip.display());
    }
    Ok(out)
}

/// SSIM and ꟻLIP of every frame of the clip `options` describes, rendered (not decoded),
/// against the same frame of the reference's lossless frames in `reference`.
fn score_rendered(
    options: &record::RecordOptions,
    reference: &Path,
) -> Result<(Vec<f64>, Vec<f64>)> {
    use rayon::prelude::*;
    let (mut ssim_of, mut flip_of) = (Vec::new(), Vec::new());
    let mut batch: Vec<(image::RgbaImage, image::RgbaImage)> = Vec::with_capacity(BATCH);
    let mut flush = |batch: &mut Vec<(image::RgbaImage, image::RgbaImage)>| {
        let scores: Vec<(f64, f64)> = batch
            .par_iter()
            .map(|(fa, fb)| (frame_ssim(fa, fb), frame_flip(fa, fb)))
            .collect();
        for (s, f) in scores {
            ssim_of.push(s);
            flip_of.push(f);
        }
        batch.clear();
    };
    record::render_frames(options, &mut |k, frame| {
        let r = lossless_frame(reference, k, frame)?;
        batch.push((frame.clone(), r));
        if batch.len() == BATCH {
            flush(&mut batch);
        }
        Ok(())
    })?;
    flush(&mut batch);
    Ok((ssim_of, flip_of))
}

/// SSIM of two equally sized frames of at least 11×11 pixels.
fn frame_ssim(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    ssim(&Luma::from_rgba(a), &Luma::from_rgba(b)).unwrap_or(f64::NAN)
}

/// ꟻLIP's mean error of `test` against `reference` (equally sized sRGB frames).
pub fn frame_flip(test: &image::RgbaImage, reference: &image::RgbaImage) -> f64 {
    let rgb = |img: &image::RgbaImage| {
        let data: Vec<u8> = img.pixels().flat_map(|p| [p[0], p[1], p[2]]).collect();
        nv_flip::FlipImageRgb8::with_data(img.width(), img.height(), &data)
    };
    let error = nv_flip::flip(
        rgb(reference),
        rgb(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    nv_flip::FlipPool::from_image(&error).mean() as f64
}

fn write_outputs(dir: &Path, p: &Proxy) -> Result<()> {
    let mut per_clip = csv::Writer::from_writer(Vec::new());
    per_clip.write_record([
        "model",
        "method",
        "tolerance_px",
        "file",
        "mean_ssim",
        "lowest_ssim",
        "mean_flip",
        "highest_flip",
    ])?;
    let mut per_frame = csv::Writer::from_writer(Vec::new());
    per_frame.write_record(["file", "frame", "seconds", "ssim", "flip"])?;
    for c in &p.clips {
        per_clip.write_record([
            c.model.clone(),
            c.method.to_string(),
            c.tolerance_px.to_string(),
            c.file.clone(),
            format!("{:.6}", c.mean),
            format!("{:.6}", c.lowest),
            format!("{:.6}", c.flip_mean),
            format!("{:.6}", c.flip_highest),
        ])?;
        for (k, (s, f)) in c.ssim.iter().zip(&c.flip).enumerate() {
            per_frame.write_record([
                c.file.clone(),
                k.to_string(),
                format!("{:.4}", k as f64 / p.fps.max(1) as f64),
                format!("{s:.6}"),
                format!("{f:.6}"),
            ])?;
        }
    }
    let bytes = |w: csv::Writer<Vec<u8>>| w.into_inner().map_err(|e| anyhow!("{e}"));
    write_atomic(&dir.join("proxy.csv"), &bytes(per_clip)?)?;
    write_atomic(&dir.join("proxy-frames.csv"), &bytes(per_frame)?)?;
    write_atomic(&dir.join("proxy.md"), markdown(p).as_bytes())?;
    write_atomic(
        &dir.join(PROXY_JSON),
        crate::app::json::pretty(p)?.as_bytes(),
    )?;
    plot(p, &dir.join("proxy.png"))
}

/// Per condition: both clips' means by both metrics, and each metric's choice.
pub fn markdown(p: &Proxy) -> String {
    let mut out = format!(
        "Image-metric proxy of the study, every clip against full detail, frame by frame: {} \
         (higher is closer) and {} (lower is closer).\n\n",
        p.metrics[0], p.metrics[1]
    );
    for c in &p.codec {
        let _ = writeln!(
            out,
            "The codec's own loss, for scale: {}'s full-detail reference as H.264 against its \
             lossless frames scores SSIM {:.4} on average, from {:.4} to {:.4} over the clip. \
             The scores below are of frames before encoding, so this swing is not in them; \
             participants, who watch the MP4s, do see it.\n",
            c.model, c.mean, c.lowest, c.highest
        );
    }
    out.push_str(
        "| model | A vs B | tolerance px | SSIM A | SSIM B | SSIM prefers | ꟻLIP A | ꟻLIP B | ꟻLIP prefers |\n",
    );
    out.push_str("|---|---|---:|---:|---:|---|---:|---:|---|\n");
    for c in &p.conditions {
        let k = &c.condition;
        let prefers = |favour: f64| {
            if favour > 0.0 {
                k.method_b.to_string()
            } else if favour < 0.0 {
                k.method_a.to_string()
            } else {
                "neither".into()
            }
        };
        let [ssim, flip] = c.favour_b();
        let _ = writeln!(
            out,
            "| {} | {} vs {} | {} | {:.4} | {:.4} | {} | {:.4} | {:.4} | {} |",
            k.model,
            k.method_a,
            k.method_b,
            k.tolerance_px,
            c.ssim_a,
            c.ssim_b,
            prefers(ssim),
            c.flip_a,
            c.flip_b,
            prefers(flip)
        );
    }
    out
}

/// SSIM over the clip's time, a line per clip.
fn plot(p: &Proxy, path: &Path) -> Result<()> {
    register_font();
    let (w, h) = (1000u32, 600u32);
    let seconds = p
        .clips
        .iter()
        .map(|c| c.ssim.len() as f64 / p.fps.max(1) as f64)
        .fold(0.1f64, f64::max);
    let lowest = p
        .clips
        .iter()
        .map(|c| c.lowest)
        .fold(1.0f64, f64::min)
        .clamp(-1.0, 0.99);
    let floor = (lowest - 0.02).max(-1.0);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "SSIM against full detail, frame by frame",
                ("sans-serif", 24),
            )
            .margin(20)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..seconds, floor..1.0)
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .x_desc("seconds")
            .y_desc("SSIM")
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .draw()
            .map_err(plot_error)?;
        for (i, c) in p.clips.iter().enumerate() {
            let colour = Palette99::pick(i).to_rgba();
            let fps = p.fps.max(1) as f64;
            chart
                .draw_series(LineSeries::new(
                    c.ssim.iter().enumerate().map(|(k, &s)| (k as f64 / fps, s)),
                    colour.stroke_width(2),
                ))
                .map_err(plot_error)?
                .label(format!(
                    // FLIP spelt plainly: the plot's font has no ꟻ.
                    "{} {} {} px: SSIM {:.3}, FLIP {:.3}",
                    c.model, c.method, c.tolerance_px, c.mean, c.flip_mean
                ))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .border_style(BLACK)
            .background_style(WHITE.mix(0.9))
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    write_plot(path, w, h, buf)
}

/// The proxy's scores of the study in `dir`, if `study proxy` has run there.
pub fn read(dir: &Path) -> Result<Option<Proxy>> {
    let path = dir.join(PROXY_JSON);
    if !path.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&path)
        .map_err(|e| anyhow!("{}: cannot read: {e}", path.display()))?;
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| anyhow!("{}: not the proxy's scores: {e}", path.display()))
}

/// Spearman's rank correlation of two equally long samples: Pearson's correlation of their
/// ranks, ties given their mean rank. `None` with fewer than three pairs or where either
/// sample has no spread.
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    if x.len() != y.len() || x.len() < 3 {
        return None;
    }
    let (rx, ry) = (ranks(x), ranks(y));
    let n = x.len() as f64;
    let (mx, my) = (rx.iter().sum::<f64>() / n, ry.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in rx.iter().zip(&ry) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

/// Ranks 1..n, ties sharing their mean rank.
fn ranks(v: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut out = vec![0.0; v.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && v[order[j + 1]] == v[order[i]] {
            j += 1;
        }
        let rank = (i + j) as f64 / 2.0 + 1.0;
        for &k in &order[i..=j] {
            out[k] = rank;
        }
        i = j + 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spearman_matches_known_values() {
        // Monotone: ±1 whatever the spacing.
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(spearman(&x, &[1.0, 4.0, 9.0, 16.0, 100.0]), Some(1.0));
        assert_eq!(spearman(&x, &[5.0, 3.0, 2.0, 1.0, -7.0]), Some(-1.0));
        // With ties (R: cor(c(1,2,2,3), c(1,3,2,4), method = "spearman") = 0.9486833).
        let r = spearman(&[1.0, 2.0, 2.0, 3.0], &[1.0, 3.0, 2.0, 4.0]).unwrap();
        assert!((r - 0.948_683_3).abs() < 1e-6, "{r}");
        // R: cor(1:6, c(2,1,4,3,6,5), method = "spearman") = 0.8285714.
        let r = spearman(
            &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            &[2.0, 1.0, 4.0, 3.0, 6.0, 5.0],
        )
        .unwrap();
        assert!((r - 0.828_571_4).abs() < 1e-6, "{r}");
        assert_eq!(spearman(&[1.0, 2.0], &[2.0, 1.0]), None);
        assert_eq!(spearman(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]), None);
    }

    /// ꟻLIP: no error between a frame and itself, more as noise grows, and the shape of an
    /// error a viewer sees (a shifted edge) scores above faint noise.
    #[test]
    fn flip_scores_grow_with_the_difference() {
        let base = image::RgbaImage::from_fn(64, 48, |x, y| {
            let v = if x < 32 { 40 } else { 200 };
            image::Rgba([v, (y * 4) as u8, 90, 255])
        });
        assert!(frame_flip(&base, &base) < 1e-6);
        let mut rng = fastrand::Rng::with_seed(7);
        let noisy = |amount: i32, rng: &mut fastrand::Rng| {
            let mut img = base.clone();
            for p in img.pixels_mut() {
                for c in 0..3 {
                    p[c] = (p[c] as i32 + rng.i32(-amount..=amount)).clamp(0, 255) as u8;
                }
            }
            img
        };
        let (low, high) = (noisy(4, &mut rng), noisy(40, &mut rng));
        let (f_low, f_high) = (frame_flip(&low, &base), frame_flip(&high, &base));
        assert!(
            0.0 < f_low && f_low < f_high && f_high <= 1.0,
            "{f_low} {f_high}"
        );
        let shifted =
            image::RgbaImage::from_fn(64, 48, |x, y| *base.get_pixel(x.saturating_sub(4), y));
        assert!(frame_flip(&shifted, &base) > f_low);
    }

    #[test]
    fn reference_clips_are_named_after_the_model() {
        assert_eq!(reference_file("horse"), "clips/horse-reference.mp4");
        assert_eq!(
            reference_file("/data/Fox Run.glb"),
            "clips/Fox_Run-reference.mp4"
        );
    }
}
