// Base colour of every material of a character, one layer each (see src/bake/gpu_data/materials.rs),
// shared by the skinned and the plain character shaders.

@group(1) @binding(2) var material_tex: texture_2d_array<f32>;
@group(1) @binding(3) var material_sampler: sampler;
