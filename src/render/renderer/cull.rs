//! Culling: which part of the frame a side covers, and the instances whose bounding sphere
//! lies outside its part of the view frustum.

use glam::{Affine3A, Vec3, Vec4};

/// Which part of the view a side covers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Region {
    #[default]
    Full,
    Left,
    Right,
}

impl Region {
    /// The planes (xyz · p + w ≥ 0 inside) of the part of the view frustum of `view_proj` that
    /// this region shows: left, right, bottom, top, near, each normalised so that a sphere
    /// test is a signed distance.
    pub fn frustum(self, view_proj: glam::Mat4) -> [glam::Vec4; 5] {
        let row = |i| view_proj.row(i);
        let (x, y, z, w) = (row(0), row(1), row(2), row(3));
        // Clip-space x runs from −w to w; a half keeps x ≥ 0 or x ≤ 0.
        let (left, right) = match self {
            Region::Full => (w + x, w - x),
            Region::Left => (w + x, -x),
            Region::Right => (x, w - x),
        };
        [left, right, w + y, w - y, z].map(|p| p / p.truncate().length().max(1e-12))
    }

    /// The region's rectangle (x, y, width, height) within `view`.
    pub fn rect(self, [x, y, w, h]: [u32; 4]) -> [u32; 4] {
        let half = w / 2;
        match self {
            Region::Full => [x, y, w, h],
            Region::Left => [x, y, half.max(1), h],
            Region::Right => [x + half, y, (w - half).max(1), h],
        }
    }
}

/// The bounding sphere of a character whose model-space sphere is `sphere`, placed by
/// `transform`: its centre moved, its radius grown by the transform's largest scale.
pub(super) fn bounding_sphere(sphere: (Vec3, f32), transform: &Affine3A) -> (Vec3, f32) {
    let centre = transform.transform_point3(sphere.0);
    let m = transform.matrix3;
    let scale = m
        .x_axis
        .length()
        .max(m.y_axis.length())
        .max(m.z_axis.length());
    (centre, sphere.1 * scale)
}

/// Whether a sphere lies wholly outside one of the frustum's `planes` (inward normals).
pub(super) fn outside(planes: &[Vec4], centre: Vec3, radius: f32) -> bool {
    planes
        .iter()
        .any(|p| p.truncate().dot(centre) + p.w < -radius)
}
