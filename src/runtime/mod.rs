//! What runs a scene, between the renderer and the front ends: the scene spec and its models
//! loaded and laid out, the world (models, their levels, the crowd and the camera, drawn each
//! frame), level installation and the background bake,
//! and measurements that draw worlds (the colour error of a tree's level, where a
//! character's impostor comes in). Never imports a
//! front end.

pub mod colour_error;
pub mod foliage_lighting;
pub mod headless;
pub mod impostor_placement;
pub mod levels;
pub mod shading_error;
pub mod spec;
pub mod world;
