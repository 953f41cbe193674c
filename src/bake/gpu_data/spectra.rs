//! The spectra texture: the K lines per axis of every billboard of a spectral cloud, for the vertex
//! shader to evaluate (Bennett-Therkildsen, Carlsen & Schmid's thesis "Animated Billboard Clouds
//! for Foliage Simplification" (2007) §6.2.1: "a simple vertex program" reading per-billboard
//! descriptions from a texture).
//!
//! Layout: `Rgba32Float`, `3K` texels wide and one row per billboard. Texel `axis · K + j` of
//! row `r` holds line j of that axis as `(cycles m, amplitude a, phase φ, 0)`. The shader
//! (`spectral_offset` in `shaders/skinning.wgsl`) finds K as a third of the width and adds
//! `Σ_axes Σ_j a · cos(2π m τ + φ)` to all four corners of billboard r: the same offset for
//! every corner, so the billboard moves rigidly. [`SpectraTexture::offset`] is its CPU mirror.
//!
//! Which row a vertex reads is in the vertex texture (see `crate::bake::gpu_data::vertex_texture`):
//! [`SpectralMotion::vertex_rows`] gives it per vertex of the level's model.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// One kept frequency of one axis: offset(τ) += amplitude · cos(2π · cycles · τ + phase).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Line {
    /// Whole cycles per loop.
    pub cycles: u32,
    pub amplitude: f32,
    pub phase: f32,
}

impl Line {
    /// A constant offset `value` (the mean pose): 0 cycles, the sign in the phase (0 or π),
    /// as `a cos(2π·0·τ + φ)` evaluates it.
    pub fn constant(value: f32) -> Line {
        Line {
            cycles: 0,
            amplitude: value.abs(),
            phase: if value < 0.0 {
                std::f32::consts::PI
            } else {
                0.0
            },
        }
    }
}

/// Rows a spectra texture may have: the 2D texture limit every wgpu adapter offers.
pub const MAX_ROWS: usize = 8192;

/// A vertex that no spectrum moves.
pub const NO_ROW: u32 = u32::MAX;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpectraTexture {
    /// Lines per axis (K).
    pub bins: u32,
    pub rows: u32,
    /// `rows × 3K` texels, row by row.
    pub texels: Vec<[f32; 4]>,
}

impl SpectraTexture {
    /// One row per billboard, from its K lines per axis (shorter lists are padded with lines
    /// of amplitude 0; longer ones are an error of the caller).
    pub fn new(rows: &[[Vec<Line>; 3]], bins: usize) -> Result<SpectraTexture, String> {
        if rows.len() > MAX_ROWS {
            return Err(format!(
                "{} billboards: more than the spectra texture's {MAX_ROWS} rows",
                rows.len()
            ));
        }
        let bins = bins.max(1);
        let mut texels = Vec::with_capacity(rows.len() * 3 * bins);
        for lines in rows {
            for axis in lines {
                assert!(axis.len() <= bins, "more lines than bins");
                for j in 0..bins {
                    let l = axis.get(j).copied().unwrap_or_default();
                    texels.push([l.cycles as f32, l.amplitude, l.phase, 0.0]);
                }
            }
        }
        Ok(SpectraTexture {
            bins: bins as u32,
            rows: rows.len() as u32,
            texels,
        })
    }

    pub fn width(&self) -> u32 {
        3 * self.bins
    }

    /// Texel `(x, y)`.
    pub fn get(&self, x: u32, y: u32) -> [f32; 4] {
        self.texels[(y * self.width() + x) as usize]
    }

    /// The offset of row `row` at loop time `tau` scaled by the wind `strength`: the CPU
    /// mirror of `spectral_offset` in `shaders/skinning.wgsl`, with the same arithmetic.
    pub fn offset(&self, row: u32, tau: f32, strength: f32) -> Vec3 {
        let mut d = [0.0f32; 3];
        for (axis, out) in d.iter_mut().enumerate() {
            for j in 0..self.bins {
                let [m, a, phi, _] = self.get(axis as u32 * self.bins + j, row);
                *out += a * (std::f32::consts::TAU * m * tau + phi).cos();
            }
        }
        Vec3::from(d) * strength
    }

    pub fn bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.texels)
    }
}

/// The spectral motion of a cloud level: its spectra texture and, for every vertex of the
/// level's model, the row that moves it ([`NO_ROW`] for the wood).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpectralMotion {
    pub spectra: SpectraTexture,
    pub vertex_rows: Vec<u32>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_hold_their_lines_and_evaluate_like_the_lines() {
        let a = [
            vec![Line {
                cycles: 2,
                amplitude: 0.5,
                phase: 0.3,
            }],
            vec![],
            vec![
                Line {
                    cycles: 1,
                    amplitude: 0.1,
                    phase: -1.0,
                },
                Line {
                    cycles: 5,
                    amplitude: 0.02,
                    phase: 2.0,
                },
            ],
        ];
        let b = [vec![], vec![Line::default(); 2], vec![]];
        let t = SpectraTexture::new(&[a.clone(), b], 2).unwrap();
        assert_eq!((t.width(), t.rows, t.texels.len()), (6, 2, 12));
        assert_eq!(t.get(4, 0), [1.0, 0.1, -1.0, 0.0]);
        assert_eq!(t.get(5, 0), [5.0, 0.02, 2.0, 0.0]);
        for tau in [0.0, 0.13, 0.5, 0.77] {
            let want = crate::bake::foliage::spectral::bins::eval(&a, tau);
            assert!(t.offset(0, tau, 1.0).distance(want) < 1e-6);
            assert!(t.offset(0, tau, 0.5).distance(want * 0.5) < 1e-6);
            assert_eq!(t.offset(1, tau, 1.0), Vec3::ZERO);
        }
        assert!(SpectraTexture::new(&vec![b_rows(); MAX_ROWS + 1], 1).is_err());
    }

    fn b_rows() -> [Vec<Line>; 3] {
        [vec![], vec![], vec![]]
    }
}
