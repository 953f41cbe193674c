//! Characters: Merry, Marais & Gain's progressive meshes in animation space. The simplifier
//! ([`simplify`]) ranks half-edge collapses by the memoryless metric; [`lod`] cuts its
//! sequence into levels whose errors [`lod_error`] and [`silhouette`] measure; coarse levels
//! may be lit through normal maps ([`normal_map`]).

pub mod lod;
pub mod lod_error;
pub mod normal_map;
pub mod silhouette;
pub mod simplify;
pub mod uv_grid;
