//! Test models whose awkward properties live in the file, as files from elsewhere have them:
//! several meshes and skins, unskinned parts on nodes, an armature node that scales and turns
//! the skeleton, joints named and oriented as a rigging service names them, hundreds of plain
//! materials, morph targets, debris in the index buffers, clips sent without a mesh. Each is
//! written as a [`file::Document`], byte for byte the same on every run, and committed under
//! `assets/` like the other models ([`super::file`]).

pub mod cards;
pub mod feathers;
pub mod file;
pub mod flight;
pub mod knight;
pub mod mocap;
pub mod parts;
pub mod random;
pub mod robot;
pub mod structure;

use glam::{Quat, Vec3};

/// Choices read from bytes, for the generators of random files ([`random`], [`structure`]):
/// each choice takes the next byte, and zeros once the bytes run out, so any bytes make a file
/// and the same bytes the same file.
pub(crate) struct Choices<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Choices<'a> {
    pub(crate) fn new(data: &'a [u8]) -> Self {
        Choices { data, at: 0 }
    }

    pub(crate) fn byte(&mut self) -> u8 {
        let b = self.data.get(self.at).copied().unwrap_or(0);
        self.at += 1;
        b
    }

    /// A whole number in `lo..=hi`.
    pub(crate) fn within(&mut self, lo: usize, hi: usize) -> usize {
        lo + self.byte() as usize % (hi - lo + 1)
    }

    /// One time in `n`.
    pub(crate) fn one_in(&mut self, n: u8) -> bool {
        self.byte().is_multiple_of(n)
    }

    /// A coordinate on a grid of 1/32 from −4 to 4: coarse, so points coincide.
    pub(crate) fn coordinate(&mut self) -> f32 {
        (self.byte() as f32 - 128.0) / 32.0
    }

    /// A number from −1 to 1 on a grid of 1/128.
    pub(crate) fn signed(&mut self) -> f32 {
        (self.byte() as f32 - 128.0) / 128.0
    }

    pub(crate) fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.signed(), self.signed(), self.signed())
    }

    /// A turn about an axis, up to half a turn (the identity when the axis comes out zero).
    pub(crate) fn rotation(&mut self) -> Quat {
        let axis = self.vec3().normalize_or_zero();
        let angle = self.signed() * std::f32::consts::PI;
        if axis == Vec3::ZERO {
            Quat::IDENTITY
        } else {
            Quat::from_axis_angle(axis, angle)
        }
    }

    /// A scale: mostly one; now and then uniform from 0.5 to 2, not uniform, or mirroring one
    /// axis.
    pub(crate) fn scale(&mut self) -> Vec3 {
        match self.byte() % 8 {
            0 => Vec3::splat(0.5 + 1.5 * (self.byte() as f32 / 255.0)),
            1 => Vec3::new(
                0.5 + self.byte() as f32 / 170.0,
                0.5 + self.byte() as f32 / 170.0,
                0.5 + self.byte() as f32 / 170.0,
            ),
            2 => Vec3::new(-1.0, 1.0, 1.0),
            _ => Vec3::ONE,
        }
    }
}
