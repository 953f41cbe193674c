//! Scene: what is in the world and where the camera is. Plain data and arithmetic, no GPU.

pub mod camera;
pub mod camera_path;
pub mod crowd;
pub mod foliage;
pub mod forest;
pub mod kind;
pub mod lod;

pub use camera::Camera;
pub use camera_path::CameraPath;
pub use crowd::{Agent, Crowd, CrowdConfig, CrowdModel, Instance, Path};
pub use kind::SceneKind;
pub use lod::{
    Drive, LodDraw, LodMethod, LodModel, LodPolicy, LodTracker, ScreenProjection, Transition,
};
