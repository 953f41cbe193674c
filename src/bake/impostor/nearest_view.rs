//! A tree impostor far off shown by one view: the view its blend of three weighs most, alone
//! (`fs_impostor_nearest` in `shaders/impostor.wgsl`), two texture reads a pixel instead of
//! seven. How far that puts a point of the tree from where it should stand, so the renderer
//! can do it only where the error projects within the screen tolerance.

use super::octahedral::{ImpostorFrame, ViewGrid, hemi_oct_decode};
use glam::Vec2;

/// The largest angle (radians) between a line of sight and the view `grid`'s blend weighs
/// most (the heaviest of [`ViewGrid::blend`]'s three, the one the shader shows alone): found
/// over a fine grid of directions on the hemisphere, as the shader picks it.
pub fn nearest_view_angle(grid: ViewGrid) -> f32 {
    const SAMPLES: u32 = 96;
    let mut worst = 0.0f32;
    for j in 0..=SAMPLES {
        for i in 0..=SAMPLES {
            let s = Vec2::new(i as f32, j as f32) / SAMPLES as f32 * 2.0 - Vec2::ONE;
            let d = hemi_oct_decode(s);
            let ((vi, vj), _) = grid
                .blend(d)
                .into_iter()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or(((0, 0), 1.0));
            let angle = d.dot(grid.direction(vi, vj)).clamp(-1.0, 1.0).acos();
            worst = worst.max(angle);
        }
    }
    worst
}

/// How far, in model units, a point of the tree can stand from where it should when `frame`'s
/// impostor shows its heaviest view alone: the chord a point on its sphere moves through
/// [`nearest_view_angle`]. Where this projects within the screen tolerance, one view is as
/// good as the blend of three, for a third of the texture reads.
pub fn nearest_view_error(frame: &ImpostorFrame) -> f32 {
    let angle = nearest_view_angle(ViewGrid {
        frames: frame.frames,
        cell: 1,
    });
    2.0 * frame.radius * (0.5 * angle).sin()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_heaviest_view_is_within_the_grid_spacing_of_any_line_of_sight() {
        let angle = |frames| nearest_view_angle(ViewGrid { frames, cell: 1 }).to_degrees();
        let (eight, sixteen) = (angle(8), angle(16));
        // 8 × 8 views: within 22° of any direction (see `octahedral::FRAMES`), the heaviest
        // of three within about that too; twice the views, about half the angle.
        assert!(eight > 5.0 && eight < 25.0, "8 views: {eight}°");
        assert!(sixteen < 0.65 * eight, "16 views: {sixteen}°, 8: {eight}°");
        let frame = ImpostorFrame {
            frames: 8,
            centre: [0.0; 3],
            radius: 2.0,
            base: 0.0,
            height: 4.0,
            rows: 4,
            bounds: [[-1.0; 3], [1.0; 3]],
        };
        let e = nearest_view_error(&frame);
        assert!((e - 2.0 * 2.0 * (0.5 * eight.to_radians()).sin()).abs() < 1e-4);
    }
}
