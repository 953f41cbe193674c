//! Measurements that draw worlds and compare pictures, a layer between the runtime and the
//! front ends:
//!
//! - [`colour_error`]: a tree level's colour error against the full tree (thesis §5.1.3) and
//!   the metric's protocol (views, frames, framing), which the others share;
//! - [`impostor_fit`]: a character impostor's colour error beside a mesh level's, for the
//!   placement rule of [`crate::bake::impostor::placement`];
//! - [`shading_error`]: a coarse level's shading against full detail's, normal maps on or off;
//! - [`foliage_lighting`]: billboards lit through their atlas against the leaves they stand for;
//! - [`material_share`]: each cut-out material's share of a tree level's foliage pixels;
//! - [`ssim`]: the structural similarity of two pictures (the study's proxy);
//! - [`coverage`]: the pixels each pass of a frame covers (`bench`'s fragments per covered
//!   pixel);
//!
//! and [`GpuMeasurer`], which hands the first two to a bake of levels
//! ([`crate::runtime::levels::Measurer`]).

pub mod colour_error;
pub mod coverage;
pub mod foliage_lighting;
pub mod impostor_fit;
pub mod material_share;
pub mod shading_error;
pub mod ssim;
pub mod statistics;

use crate::bake::character::lod::LodLevel;
use crate::bake::gpu_data::drawable::Drawable;
use crate::bake::gpu_products::{MeasureColour, MeasureImpostor};
use crate::bake::impostor::animated::AnimatedImpostor;
use crate::model::Model;
use crate::render::Gpu;
use anyhow::Result;

/// The measurements a bake of levels takes, drawn on the GPU it is given.
pub struct GpuMeasurer;

impl crate::runtime::levels::Measurer for GpuMeasurer {
    fn colour<'g>(&self, gpu: &'g Gpu) -> Box<dyn MeasureColour + 'g> {
        Box::new(colour_error::GpuColourError::new(gpu))
    }

    fn impostor<'a>(
        &self,
        gpu: &'a Gpu,
        model: &'a Model,
        full: &'a Drawable,
        levels: &'a [LodLevel],
        impostor: &'a AnimatedImpostor,
    ) -> Result<Box<dyn MeasureImpostor + 'a>> {
        Ok(Box::new(impostor_fit::ImpostorFit::new(
            gpu, model, full, levels, impostor,
        )?))
    }
}
