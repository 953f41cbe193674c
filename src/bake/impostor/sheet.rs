//! An animated impostor's sheet: how finely it is baked (views, frames, cell), how its pages
//! lie in one sheet, and how many frames each clip gets there (see [`super::animated`]).

use crate::bake::gpu_data::anim_texture::AnimationTexture;
use crate::bake::impostor::octahedral::ViewGrid;
use crate::model::Model;
use serde::{Deserialize, Serialize};

/// How finely an animated impostor is baked: views on a side of its grid, frames per clip and
/// texels on a side of a view's cell. Memory grows as views² × frames × cell²
/// ([`ImpostorOptions::bytes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ImpostorOptions {
    pub views: u32,
    pub frames: u32,
    pub cell: u32,
}

impl Default for ImpostorOptions {
    /// 12 × 12 views put one within 14° of any line of sight (with 8 × 8, 22°, the
    /// walker's impostor was worse than its coarsest mesh at every size measured); 12 frames a
    /// clip; 24-texel cells hold a character about 20 texels high, more than it covers where
    /// its impostor comes in (10 to 15 pixels). About 22 MB a model of two clips.
    fn default() -> Self {
        ImpostorOptions {
            views: 12,
            frames: 12,
            cell: 24,
        }
    }
}

/// Bounds on the options. The pages of every clip's frames must fit a sheet of at most
/// [`SHEET_SIZE`] texels a side ([`sheet_layout`]).
pub const VIEWS: std::ops::RangeInclusive<u32> = 2..=16;
pub const FRAMES: std::ops::RangeInclusive<u32> = 2..=64;
pub const CELL: std::ops::RangeInclusive<u32> = 8..=256;
/// The widest sheet: the material layers' own limit.
pub const SHEET_SIZE: u32 = crate::bake::gpu_data::materials::MAX_LAYER_SIZE;

/// Frames each clip of `model` gets in its impostor with `options`: `options.frames` each
/// where their pages fit one sheet ([`sheet_layout`]); else the sheet's pages shared among
/// the clips by their durations, at least two each (its first and last pose), so that a
/// character of many clips (asset-store characters ship 10–30) keeps an impostor, its frames
/// further apart in its longer clips. The impostor's frame error, measured from the poses
/// between its frames, grows with the gaps, and the placement weighs it like any other.
pub fn clip_frames(model: &Model, options: &ImpostorOptions) -> Result<Vec<u32>, String> {
    let durations: Vec<f32> = model.clips.iter().map(|c| c.duration.max(0.0)).collect();
    // A clip that does not last (and the rest pose of a model with none) is one frame.
    let lasting = durations.iter().filter(|&&d| d > 0.0).count() as u32;
    let still = durations.len().max(1) as u32 - lasting;
    let most = (SHEET_SIZE / options.page_side().max(1)).max(1).pow(2);
    let frames = options.frames.max(2);
    let budget = most.saturating_sub(still);
    if lasting * frames <= budget {
        return Ok(vec![frames; durations.len().max(1)]);
    }
    if 2 * lasting > budget {
        return Err(format!(
            "{} clips of at least 2 frames of {}² texels do not fit a {SHEET_SIZE}² sheet (at most {most}); lower the views × cell (--impostors VIEWSxFRAMESxCELL)",
            lasting,
            options.page_side()
        ));
    }
    // Two frames each, then the rest of the budget by duration, never past `frames`.
    let total: f32 = durations.iter().sum();
    let spare = (budget - 2 * lasting) as f32;
    let mut counts: Vec<u32> = durations
        .iter()
        .map(|&d| match d > 0.0 {
            true => (2 + (spare * d / total.max(1e-6)).floor() as u32).min(frames),
            false => 1,
        })
        .collect();
    // Rounding down leaves a few pages: to the clips furthest under their share.
    let mut used: u32 = counts.iter().sum::<u32>() - still;
    while used < budget {
        let Some(c) = (0..counts.len())
            .filter(|&c| durations[c] > 0.0 && counts[c] < frames)
            .max_by(|&a, &b| {
                let gap = |c: usize| durations[c] / counts[c] as f32;
                gap(a).total_cmp(&gap(b))
            })
        else {
            break;
        };
        counts[c] += 1;
        used += 1;
    }
    Ok(counts)
}

/// How `pages` pages of `side` texels lie in a sheet: columns and rows, as square as fits.
pub fn sheet_layout(pages: u32, side: u32) -> Result<(u32, u32), String> {
    let most = (SHEET_SIZE / side.max(1)).max(1);
    let columns = ((pages as f32).sqrt().ceil() as u32).clamp(1, most);
    let rows = pages.div_ceil(columns);
    if rows > most {
        return Err(format!(
            "{pages} frames of {side}² texels do not fit a {SHEET_SIZE}² sheet (at most {}); lower the frames or views × cell (--impostors VIEWSxFRAMESxCELL)",
            most * most
        ));
    }
    Ok((columns, rows))
}

impl std::str::FromStr for ImpostorOptions {
    type Err = String;

    /// `VIEWSxFRAMESxCELL`, e.g. `8x12x32`.
    fn from_str(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(['x', 'X', '×']).collect();
        let [views, frames, cell] = parts.as_slice() else {
            return Err(format!(
                "`{s}`: expected VIEWSxFRAMESxCELL, e.g. 8x12x32, or `off`"
            ));
        };
        let number = |what: &str, text: &str, range: std::ops::RangeInclusive<u32>| {
            let n: u32 = text
                .trim()
                .parse()
                .map_err(|_| format!("`{s}`: {what} `{text}` is not a whole number"))?;
            if !range.contains(&n) {
                return Err(format!(
                    "`{s}`: {what} must be {} to {}, not {n}",
                    range.start(),
                    range.end()
                ));
            }
            Ok(n)
        };
        let o = ImpostorOptions {
            views: number("views", views, VIEWS)?,
            frames: number("frames", frames, FRAMES)?,
            cell: number("cell", cell, CELL)?,
        };
        if o.views * o.cell > crate::bake::gpu_data::materials::MAX_LAYER_SIZE {
            return Err(format!(
                "`{s}`: views × cell is {} texels, more than a page's {}",
                o.views * o.cell,
                crate::bake::gpu_data::materials::MAX_LAYER_SIZE
            ));
        }
        Ok(o)
    }
}

impl std::fmt::Display for ImpostorOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}x{}", self.views, self.frames, self.cell)
    }
}

impl ImpostorOptions {
    pub fn grid(&self) -> ViewGrid {
        ViewGrid {
            frames: self.views,
            cell: self.cell,
        }
    }

    /// Bytes the impostor of a model with `clips` clips takes as a texture: two sheets
    /// (colour and normal) of a page of (views · cell)² RGBA texels per frame, a third more
    /// with mipmaps (sheets with room for more pages than there are take a little more).
    pub fn bytes(&self, clips: usize) -> u64 {
        let side = (self.views * self.cell) as u64;
        let pages = 2 * self.frames as u64 * clips.max(1) as u64;
        pages * side * side * 4 * 4 / 3
    }

    /// Texels on a side of a page: every view's cell.
    pub fn page_side(&self) -> u32 {
        self.views * self.cell
    }
}

/// The times each page shows: per clip (or the rest pose, for a model without clips), the
/// clip and the times [`AnimationTexture::bake_frames`] samples it at, in page order (its
/// frames after the rest pose, frame 0).
pub fn page_times<'m>(
    model: &'m Model,
    counts: &[u32],
) -> Vec<(Option<&'m crate::model::Clip>, f32)> {
    let anim = AnimationTexture::bake_frames_each(model, counts);
    anim.clips
        .iter()
        .enumerate()
        .flat_map(|(c, clip)| {
            (0..clip.frame_count).map(move |k| {
                let t = crate::bake::gpu_data::anim_texture::frame_time(
                    clip.duration,
                    clip.frame_count,
                    k,
                );
                (model.clips.get(c), t)
            })
        })
        .collect()
}
