//! Flat arrays of RGBA32F texels laid out row by row in a 2D texture.
//!
//! Both GPU data textures (animation and vertex) are addressed by a linear texel index `i`; the
//! shader finds it at `(i % width, i / width)` with `width = textureDimensions(t).x`. The width
//! is always a power of two, so the shader does that with a mask and a shift instead of an
//! integer division per texel. Keeping the layout here, in one place, keeps the CPU writer and
//! the WGSL reader (`texel()` in `shaders/skinning.wgsl`) in step.

use serde::{Deserialize, Serialize};

/// Widest row used; well inside every adapter's 2D texture limit (8192 by default).
pub const MAX_WIDTH: u32 = 4096;

/// A 2D array of RGBA32F texels addressed linearly.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TexelGrid {
    pub width: u32,
    pub height: u32,
    /// `width * height` texels; the tail of the last row is zero padding.
    pub texels: Vec<[f32; 4]>,
}

impl TexelGrid {
    /// Lays `texels` out in rows of a power-of-two width, at most [`MAX_WIDTH`].
    pub fn from_linear(mut texels: Vec<[f32; 4]>) -> Self {
        let n = texels.len().max(1) as u32;
        let width = n.next_power_of_two().min(MAX_WIDTH);
        let height = n.div_ceil(width);
        texels.resize((width * height) as usize, [0.0; 4]);
        TexelGrid {
            width,
            height,
            texels,
        }
    }

    pub fn get(&self, i: usize) -> [f32; 4] {
        self.texels[i]
    }

    pub fn bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.texels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_wraps_rows() {
        let g = TexelGrid::from_linear(vec![[1.0; 4]; MAX_WIDTH as usize + 5]);
        assert_eq!((g.width, g.height), (MAX_WIDTH, 2));
        assert_eq!(g.texels.len(), 2 * MAX_WIDTH as usize);
        let small = TexelGrid::from_linear(vec![[1.0; 4]; 7]);
        assert_eq!((small.width, small.height), (8, 1));
    }
}
