//! What `lodlab export` writes and tells, for characters and trees alike: each level's figures,
//! the file names, and the `MSFT_screencoverage` hints worked out from where lodlab switches.

use serde::Serialize;
use std::path::PathBuf;

/// The screen the coverage hints assume, pixels.
pub const SCREEN: [f32; 2] = [1920.0, 1080.0];

/// One exported level.
#[derive(Clone, Debug, Serialize)]
pub struct ExportedLevel {
    pub level: usize,
    pub triangles: usize,
    pub vertices: usize,
    /// The most influences any vertex has.
    pub max_influences: usize,
    /// `JOINTS_n`/`WEIGHTS_n` sets: four influences a set.
    pub weight_sets: usize,
    /// The level's error bound, scene units.
    pub error: f32,
    /// Its `MSFT_screencoverage` value: the share of the screen's area below which the next
    /// level takes over (0 for the last: drawn to the end).
    pub coverage: f32,
    pub file: PathBuf,
    pub bytes: usize,
    /// What a tree's level is, in words (a character's levels have none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
    /// A tree's level's place in lodlab's chain by ε, levels left out counted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chain_level: Option<usize>,
}

impl ExportedLevel {
    /// Level `level` of `mesh`, of error `error` and hint `coverage`, written to `file` in
    /// `bytes` bytes (a character's: no kind, no place in a tree's chain).
    pub(crate) fn written(
        level: usize,
        mesh: &crate::model::SkinnedMesh,
        (error, coverage): (f32, f32),
        file: PathBuf,
        bytes: usize,
    ) -> ExportedLevel {
        let most = (0..mesh.vertex_count())
            .map(|v| mesh.influences_of(v).len())
            .max()
            .unwrap_or(0);
        ExportedLevel {
            level,
            triangles: mesh.triangle_count(),
            vertices: mesh.vertex_count(),
            max_influences: most,
            weight_sets: most.max(1).div_ceil(4),
            error,
            coverage,
            file,
            bytes,
            kind: None,
            chain_level: None,
        }
    }
}

/// Where each level hands over to the next, as its height in pixels on screen: where the next
/// level's error (of `errors`, finest first, in scene units) projects to `tolerance` pixels on
/// a model `height` high; 0 for the last.
pub(crate) fn switch_px(errors: &[f32], tolerance: f32, height: f32) -> Vec<f32> {
    (0..errors.len())
        .map(|k| {
            errors
                .get(k + 1)
                .map_or(0.0, |e| tolerance * height / e.max(1e-9))
        })
        .collect()
}

/// What an export wrote.
#[derive(Clone, Debug, Serialize)]
pub struct Exported {
    pub model: String,
    pub method: String,
    pub levels: Vec<ExportedLevel>,
    /// The file with every level under `MSFT_lod`.
    pub lod_file: PathBuf,
    pub lod_bytes: usize,
    pub from_cache: bool,
    /// Levels that plain glTF cannot draw and were left out, a line each saying why.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub left_out: Vec<String>,
}

/// The share of [`SCREEN`]'s area the model's bounding box covers, seen from the side, when
/// the model is `height_px` pixels high.
pub(crate) fn coverage(height_px: f32, aspect: f32) -> f32 {
    (height_px * height_px * aspect / (SCREEN[0] * SCREEN[1])).clamp(0.0, 1.0)
}

/// The height in pixels at which the model's box fills the screen: 90% of its height, or of
/// its width for a model wider than the screen's shape (a fox, a horse seen from the side).
pub(crate) fn filling_px(aspect: f32) -> f32 {
    0.9 * SCREEN[1].min(SCREEN[0] / aspect.max(1e-6))
}

/// The `MSFT_screencoverage` hints of levels that lodlab switches from at `switch_px` pixels
/// high (each where the next level's error projects to the tolerance; 0 for the last, drawn to
/// the end): the coverage at that height, strictly falling level by level. A switch above the
/// height where the model fills the screen ([`filling_px`]; a fine level's error is a
/// fraction of a millimetre) is put at that height, so full detail shows wherever the model
/// fills the screen. A hint that would not fall below the one before (two fine levels both
/// switching above that height) is nine tenths of it: a narrow band for the level, so that
/// the next hints are again the coverage where their levels switch. (A quarter, as this was
/// before, made every later hint a quarter of the one before it, far below where lodlab
/// switches: a fox's last levels were hinted at a twentieth of their coverage.)
pub(crate) fn coverage_hints(switch_px: &[f32], aspect: f32) -> Vec<f32> {
    /// The share of the hint before that a crowded level's hint takes.
    const CROWDED: f32 = 0.9;
    let mut hints: Vec<f32> = Vec::with_capacity(switch_px.len());
    for (k, &px) in switch_px.iter().enumerate() {
        let mut c = coverage(px.min(filling_px(aspect)), aspect);
        if let Some(&before) = hints.last()
            && c >= before
        {
            c = before * CROWDED;
        }
        if k + 1 == switch_px.len() || px <= 0.0 {
            c = 0.0;
        }
        hints.push(c);
    }
    hints
}

/// A file name from a model name: letters, digits, `-` and `_` kept, anything else `_`.
pub(crate) fn file_stem(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() { "model".into() } else { s }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_hints_fall_from_below_full_screen() {
        // Two fine levels whose successors come in far above the screen's height, then a
        // level switching at 300 px, then the last.
        let hints = coverage_hints(&[40_000.0, 9_000.0, 300.0, 0.0], 0.4);
        let full_height = coverage(filling_px(0.4), 0.4);
        assert!((hints[0] - full_height).abs() < 1e-6, "{hints:?}");
        assert!(hints[0] < 1.0);
        assert!(hints.windows(2).all(|w| w[1] < w[0]), "{hints:?}");
        assert!((hints[1] - full_height * 0.9).abs() < 1e-6, "{hints:?}");
        assert!((hints[2] - coverage(300.0, 0.4)).abs() < 1e-6, "{hints:?}");
        assert_eq!(hints[3], 0.0);
    }

    #[test]
    fn a_model_wider_than_the_screen_still_shows_full_detail_below_full_screen() {
        // A fox from the side is about twice as long as it is high, wider than 16:9.
        for aspect in [1.0, 16.0 / 9.0, 2.5, 8.0] {
            let hints = coverage_hints(&[40_000.0, 9_000.0, 0.0], aspect);
            assert!(hints[0] < 1.0 && hints[0] > 0.1, "{aspect}: {hints:?}");
            assert!(hints.windows(2).all(|w| w[1] < w[0]), "{aspect}: {hints:?}");
        }
    }

    #[test]
    fn hints_rejoin_the_coverage_after_crowded_fine_levels() {
        // Three fine levels switching above the screen, then levels at 300, 150 and 20 px:
        // their hints are their own coverage, not a chain of fractions of the fine ones.
        let hints = coverage_hints(&[9e4, 5e4, 2e4, 300.0, 150.0, 20.0, 0.0], 1.0);
        for (k, px) in [(3, 300.0), (4, 150.0), (5, 20.0)] {
            assert!(
                (hints[k] - coverage(px, 1.0)).abs() < 1e-7,
                "{k}: {hints:?}"
            );
        }
        assert!(hints.windows(2).all(|w| w[1] < w[0]), "{hints:?}");
    }
}
