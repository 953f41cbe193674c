//! What runs a scene, between the renderer and the front ends: the scene spec and its models
//! loaded and laid out, the world (models, their levels, the crowd and the camera, drawn each
//! frame), level installation and the background bake. The measurements a bake of levels
//! draws (a tree level's colour error, where a character's impostor comes in) are handed in
//! through [`levels::Measurer`]; the `measure` layer above makes them. Never imports a
//! front end.

pub mod headless;
pub mod levels;
pub mod spec;
pub mod world;
